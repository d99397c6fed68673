#include "io/report/png_plot.h"

#include <vtkAxis.h>
#include <vtkChartLegend.h>
#include <vtkChartXY.h>
#include <vtkContextScene.h>
#include <vtkContextView.h>
#include <vtkDoubleArray.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPen.h>
#include <vtkPlotBar.h>
#include <vtkPlotLine.h>
#include <vtkPlotPoints.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkTable.h>
#include <vtkTextProperty.h>
#include <vtkUnsignedCharArray.h>
#include <vtkWindowToImageFilter.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "io/common/io_error.h"
#include "io/report/offscreen_display.h"

namespace tolver {

void sharedYRange(const std::vector<const std::vector<ScatterSeries>*>& charts, double* y_min,
                  double* y_max) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto* c : charts)
    for (const ScatterSeries& s : *c)
      for (double y : s.y)
        if (std::isfinite(y)) {
          lo = std::min(lo, y);
          hi = std::max(hi, y);
        }
  if (!(hi > lo)) {
    lo = std::isfinite(lo) ? lo - 1 : -1;
    hi = lo + 2;
  }
  const double pad = 0.05 * (hi - lo);
  *y_min = lo - pad;
  *y_max = hi + pad;
}

void writeScatterPng(const std::string& path, const ScatterChart& c) {
  std::string message;
  if (!ensureDisplay(&message)) throw InputError(path, 0, 0, "image", message);
  vtkNew<vtkContextView> view;
  view->GetRenderWindow()->SetOffScreenRendering(1);
  view->GetRenderWindow()->SetSize(c.width, c.height);
  view->GetRenderer()->SetBackground(1.0, 1.0, 1.0);
  vtkNew<vtkChartXY> chart;
  view->GetScene()->AddItem(chart);
  chart->SetTitle(c.title);
  chart->GetTitleProperties()->SetFontSize(14);
  chart->GetAxis(vtkAxis::BOTTOM)->SetTitle(c.x_label);
  chart->GetAxis(vtkAxis::LEFT)->SetTitle(c.y_label);
  for (int a : {vtkAxis::BOTTOM, vtkAxis::LEFT}) {
    chart->GetAxis(a)->GetTitleProperties()->SetFontSize(12);
    chart->GetAxis(a)->GetLabelProperties()->SetFontSize(11);
  }
  bool legend = false;
  std::vector<vtkSmartPointer<vtkTable>> tables;
  for (const ScatterSeries& s : c.series) {
    if (s.x.empty()) continue;
    vtkNew<vtkTable> t;
    vtkNew<vtkDoubleArray> x, y;
    x->SetName("x");
    y->SetName(s.legend.empty() ? "y" : s.legend.c_str());
    for (size_t i = 0; i < s.x.size(); ++i) {
      x->InsertNextValue(s.x[i]);
      y->InsertNextValue(s.y[i]);
    }
    t->AddColumn(x);
    t->AddColumn(y);
    tables.push_back(t.Get());
    vtkPlot* p = nullptr;
    if (s.style == ScatterSeries::Style::Points) {
      auto* pts = vtkPlotPoints::SafeDownCast(chart->AddPlot(vtkChart::POINTS));
      pts->SetMarkerStyle(vtkPlotPoints::CIRCLE);
      pts->SetMarkerSize(2.0f * static_cast<float>(s.radius));
      p = pts;
    } else if (s.style == ScatterSeries::Style::Line) {
      p = chart->AddPlot(vtkChart::LINE);
      p->SetWidth(static_cast<float>(s.radius));
      if (auto* lp = vtkPlotPoints::SafeDownCast(p)) lp->SetMarkerStyle(vtkPlotPoints::NONE);
    } else {
      auto* bar = vtkPlotBar::SafeDownCast(chart->AddPlot(vtkChart::BAR));
      if (c.bar_width > 0) bar->SetWidth(static_cast<float>(c.bar_width));
      p = bar;
    }
    p->SetInputData(t, 0, 1);
    p->SetColor(s.rgb[0], s.rgb[1], s.rgb[2], 255);
    p->SetLabel(s.legend.empty() ? "" : s.legend);
    p->SetLegendVisibility(!s.legend.empty());
    legend = legend || !s.legend.empty();
  }
  chart->SetShowLegend(legend);
  if (c.fixed_y) {
    vtkAxis* y = chart->GetAxis(vtkAxis::LEFT);
    y->SetBehavior(vtkAxis::FIXED);
    y->SetRange(c.y_min, c.y_max);
  }
  if (c.fixed_x) {
    vtkAxis* x = chart->GetAxis(vtkAxis::BOTTOM);
    x->SetBehavior(vtkAxis::FIXED);
    x->SetRange(c.x_min, c.x_max);
  }
  view->GetRenderWindow()->Render();
  keepGlDriverLoaded();
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(view->GetRenderWindow());
  grab->Update();
  vtkNew<vtkPNGWriter> w;
  w->SetWriteToMemory(1);
  w->SetInputConnection(grab->GetOutputPort());
  w->Write();
  vtkUnsignedCharArray* bytes = w->GetResult();
  if (!bytes || bytes->GetNumberOfTuples() == 0)
    throw InputError(path, 0, 0, "image", "rendering produced no image");
  writeFileAtomically(path, std::string(reinterpret_cast<const char*>(bytes->GetPointer(0)),
                                        static_cast<size_t>(bytes->GetNumberOfTuples())));
}

}  // namespace tolver
