// The VTK module (libtolver_vtk.so, core/numerics/lazy_module.h): the deviation maps, histograms
// and line profiles (io/report/deviation_map.h), the scatter charts (io/report/png_plot.h) and
// the VTP surfaces (io/mesh/mesh_file.h), drawn and written by VTK. Opened by the first image a
// command draws; the other commands start without VTK.
#include <vtkActor.h>
#include <vtkActor2D.h>
#include <vtkAxis.h>
#include <vtkCamera.h>
#include <vtkCaptionActor2D.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkChartLegend.h>
#include <vtkChartXY.h>
#include <vtkContextScene.h>
#include <vtkContextView.h>
#include <vtkCubeAxesActor.h>
#include <vtkDoubleArray.h>
#include <vtkLookupTable.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPen.h>
#include <vtkPlotBar.h>
#include <vtkPlotLine.h>
#include <vtkPlotPoints.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkPolyDataMapper2D.h>
#include <vtkProperty.h>
#include <vtkProperty2D.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkScalarBarActor.h>
#include <vtkSmartPointer.h>
#include <vtkTable.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>
#include <vtkTypeInt32Array.h>
#include <vtkUnsignedCharArray.h>
#include <vtkWindowToImageFilter.h>
#include <vtkXMLPolyDataWriter.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <type_traits>

#include "core/numerics/lazy_module.h"
#include "core/numerics/units.h"
#include "io/common/io_error.h"
#include "io/common/text_util.h"
#include "io/mesh/mesh_file.h"
#include "io/report/deviation_map.h"
#include "io/report/offscreen_display.h"
#include "io/report/png_plot.h"

namespace tolver::vtk {
namespace {

std::string um(double mm) { return formatWith("%+.1f", mmToUm(mm)); }

void writePng(vtkRenderWindow* window, const std::string& path) {
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(window);
  grab->ReadFrontBufferOff();
  // The window was just rendered: read it as it is (a render again cost 0.07 s a map at 120 000
  // vertices in the software rasteriser; the pictures are byte-identical).
  grab->ShouldRerenderOff();
  grab->Update();
  vtkNew<vtkPNGWriter> png;
  png->SetInputConnection(grab->GetOutputPort());
  png->WriteToMemoryOn();
  png->Write();
  vtkUnsignedCharArray* bytes = png->GetResult();
  if (!bytes || bytes->GetNumberOfTuples() == 0)
    throw InputError(path, 0, 0, "image", "rendering produced no image");
  writeFileAtomically(path, std::string(reinterpret_cast<const char*>(bytes->GetPointer(0)),
                                        static_cast<size_t>(bytes->GetNumberOfTuples())));
}

vtkNew<vtkRenderWindow> offscreenWindow(int width, int height) {
  vtkNew<vtkRenderWindow> w;
  w->SetOffScreenRendering(1);
  w->SetSize(width, height);
  // No multisampling: the software rasteriser's cost grows with the samples, and a map of a
  // million triangles (about a pixel each) took 7 s for its three views with four samples, 3.7 s
  // without; the pictures differ only on the silhouette's staircase.
  w->SetMultiSamples(0);
  return w;
}

}  // namespace

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

void writeVtpWithScalars(
    const std::string& path, const std::vector<Eigen::Vector3d>& points,
    const std::vector<Eigen::Vector3i>& faces,
    const std::vector<std::pair<std::string, const std::vector<double>*>>& scalars) {
  // VTK's arrays over the caller's own (save = 1: VTK neither copies nor frees them; the poly
  // data lives only in this call): a million samples' points and values are not copied, and
  // the triangles are written as 32-bit connectivity and offsets, half the bytes of VTK's
  // default 64-bit cell array.
  static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double) &&
                    sizeof(Eigen::Vector3i) == 3 * sizeof(int) && sizeof(int) == 4,
                "points and faces are packed triples");
  vtkNew<vtkDoubleArray> xyz;
  xyz->SetNumberOfComponents(3);
  if (!points.empty())
    xyz->SetArray(const_cast<double*>(points.front().data()),
                  static_cast<vtkIdType>(3 * points.size()), /*save=*/1);
  vtkNew<vtkPoints> pts;
  pts->SetData(xyz);
  vtkNew<vtkTypeInt32Array> connectivity, offsets;
  if (!faces.empty())
    connectivity->SetArray(const_cast<int*>(faces.front().data()),
                           static_cast<vtkIdType>(3 * faces.size()), /*save=*/1);
  offsets->SetNumberOfValues(static_cast<vtkIdType>(faces.size() + 1));
  for (size_t k = 0; k <= faces.size(); ++k)
    offsets->SetValue(static_cast<vtkIdType>(k), static_cast<int>(3 * k));
  vtkNew<vtkCellArray> cells;
  cells->SetData(offsets, connectivity);
  vtkNew<vtkPolyData> poly;
  poly->SetPoints(pts);
  poly->SetPolys(cells);
  for (const auto& [name, values] : scalars) {
    vtkNew<vtkDoubleArray> a;
    a->SetName(name.c_str());
    if (!values->empty())
      a->SetArray(const_cast<double*>(values->data()), static_cast<vtkIdType>(values->size()),
                  /*save=*/1);
    poly->GetPointData()->AddArray(a);
  }
  OutputSet out;
  out.addWritten(path, [&](const std::string& tmp) {
    vtkNew<vtkXMLPolyDataWriter> writer;
    writer->SetFileName(tmp.c_str());
    writer->SetInputData(poly);
    // Raw appended binary without compression: zlib took most of the writing time and saved
    // little (doubles compress poorly); ParaView and VTK read it as they read the compressed form.
    writer->SetDataModeToAppended();
    writer->EncodeAppendedDataOff();
    writer->SetCompressorTypeToNone();
    return writer->Write() == 1;
  });
  out.commit();
}

namespace {

// The part's surface coloured per vertex by the map's colours.
vtkSmartPointer<vtkPolyData> colouredSurface(const DeviationMap& map) {
  const auto& P = *map.points;
  vtkNew<vtkPoints> pts;
  pts->SetDataTypeToDouble();
  pts->SetNumberOfPoints(static_cast<vtkIdType>(P.size()));
  for (size_t i = 0; i < P.size(); ++i) pts->SetPoint(static_cast<vtkIdType>(i), P[i].data());
  vtkNew<vtkCellArray> cells;
  for (const auto& f : *map.faces) {
    const vtkIdType ids[3] = {f[0], f[1], f[2]};
    cells->InsertNextCell(3, ids);
  }
  vtkNew<vtkUnsignedCharArray> rgb;
  rgb->SetNumberOfComponents(3);
  rgb->SetNumberOfTuples(static_cast<vtkIdType>(P.size()));
  for (size_t i = 0; i < P.size(); ++i)
    rgb->SetTypedTuple(static_cast<vtkIdType>(i), map.colours[i].data());
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  poly->SetPoints(pts);
  poly->SetPolys(cells);
  poly->GetPointData()->SetScalars(rgb);
  return poly;
}

// The map's markers as round dots, drawn over the surface (the surface's depth offset back).
vtkSmartPointer<vtkActor> markerActor(const DeviationMap& map) {
  vtkNew<vtkPoints> pts;
  pts->SetDataTypeToDouble();
  vtkNew<vtkCellArray> verts;
  vtkNew<vtkUnsignedCharArray> rgb;
  rgb->SetNumberOfComponents(3);
  for (size_t i = 0; i < map.markers.size(); ++i) {
    const vtkIdType id = pts->InsertNextPoint(map.markers[i].data());
    verts->InsertNextCell(1, &id);
    rgb->InsertNextTypedTuple(map.marker_colours[i].data());
  }
  vtkNew<vtkPolyData> poly;
  poly->SetPoints(pts);
  poly->SetVerts(verts);
  poly->GetPointData()->SetScalars(rgb);
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputData(poly);
  mapper->SetColorModeToDirectScalars();
  mapper->ScalarVisibilityOn();
  mapper->SetResolveCoincidentTopologyToPolygonOffset();
  auto actor = vtkSmartPointer<vtkActor>::New();
  actor->SetMapper(mapper);
  actor->GetProperty()->SetPointSize(map.markers.size() > 3000 ? 4.0f : 7.0f);
  actor->GetProperty()->RenderPointsAsSpheresOn();
  actor->GetProperty()->SetAmbient(1.0);
  actor->GetProperty()->SetDiffuse(0.0);
  return actor;
}

vtkSmartPointer<vtkActor> surfaceActor(vtkPolyData* poly) {
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputData(poly);
  mapper->SetColorModeToDirectScalars();
  mapper->ScalarVisibilityOn();
  auto actor = vtkSmartPointer<vtkActor>::New();
  actor->SetMapper(mapper);
  actor->GetProperty()->SetAmbient(0.35);
  actor->GetProperty()->SetDiffuse(0.65);
  actor->GetProperty()->SetSpecular(0.0);
  actor->GetProperty()->BackfaceCullingOff();
  return actor;
}

// Camera: looking along view.direction at the whole part (a region's view looks along its
// normal; nothing is cropped), with room for the box's coordinates.
void aimCamera(vtkRenderer* renderer, const double bounds[6], const MapView& view) {
  vtkCamera* cam = renderer->GetActiveCamera();
  const Eigen::Vector3d centre(0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]),
                               0.5 * (bounds[4] + bounds[5]));
  const Eigen::Vector3d dir = view.direction.normalized();
  cam->SetFocalPoint(centre.data());
  const Eigen::Vector3d eye = centre - dir * 1000.0;
  cam->SetPosition(eye.data());
  cam->SetViewUp(view.up.data());
  cam->ParallelProjectionOn();
  renderer->ResetCamera(const_cast<double*>(bounds));
  cam->Zoom(0.85);
  renderer->ResetCameraClippingRange();
}

// Colour bar: the same colour function sampled over the zone and beyond, in um, with the limits
// and the band boundaries beyond them annotated.
vtkSmartPointer<vtkScalarBarActor> colourBar(const DeviationMap& map) {
  const double lo = map.bar_lower, up = map.bar_upper, half = 0.5 * (up - lo),
               mid = 0.5 * (lo + up);
  const double range_lo = mid - 3.0 * half, range_hi = mid + 3.0 * half;
  vtkNew<vtkLookupTable> lut;
  const int n = 240;
  lut->SetNumberOfTableValues(n);
  lut->SetTableRange(mmToUm(range_lo), mmToUm(range_hi));
  for (int i = 0; i < n; ++i) {
    const double d = range_lo + (i + 0.5) / n * (range_hi - range_lo);
    const Rgb c = deviationColour(d, lo, up);
    lut->SetTableValue(i, c[0] / 255.0, c[1] / 255.0, c[2] / 255.0, 1.0);
  }
  lut->SetAnnotation(vtkVariant(mmToUm(lo)), (map.limit_names[0] + " " + um(lo)).c_str());
  lut->SetAnnotation(vtkVariant(mmToUm(up)), (map.limit_names[1] + " " + um(up)).c_str());
  const double band = 2.0 * half / 4.0;
  for (int k = 1; k <= 3; ++k) {
    lut->SetAnnotation(vtkVariant(mmToUm(up + k * band)), um(up + k * band).c_str());
    lut->SetAnnotation(vtkVariant(mmToUm(lo - k * band)), um(lo - k * band).c_str());
  }
  auto bar = vtkSmartPointer<vtkScalarBarActor>::New();
  bar->SetLookupTable(lut);
  bar->SetTitle(map.bar_title.c_str());
  bar->SetNumberOfLabels(0);
  bar->SetLabelFormat("%+.1f");
  bar->DrawAnnotationsOn();
  bar->SetPosition(0.84, 0.06);
  bar->SetPosition2(0.15, 0.86);
  bar->SetBarRatio(0.25);
  bar->UnconstrainedFontSizeOn();
  for (vtkTextProperty* t : {bar->GetTitleTextProperty(), bar->GetLabelTextProperty(),
                             bar->GetAnnotationTextProperty()}) {
    t->SetColor(0.1, 0.1, 0.1);
    t->ShadowOff();
    t->ItalicOff();
    t->BoldOff();
    t->SetFontSize(14);
  }
  return bar;
}

// The part's bounding box with its coordinates in mm (the axes' directions and a scale).
vtkSmartPointer<vtkCubeAxesActor> boundingAxes(const double bounds[6], vtkCamera* cam) {
  auto axes = vtkSmartPointer<vtkCubeAxesActor>::New();
  axes->SetBounds(const_cast<double*>(bounds));
  axes->SetCamera(cam);
  axes->SetXTitle("x mm");
  axes->SetYTitle("y mm");
  axes->SetZTitle("z mm");
  axes->SetFlyModeToOuterEdges();
  axes->SetGridLineLocation(vtkCubeAxesActor::VTK_GRID_LINES_FURTHEST);
  axes->XAxisMinorTickVisibilityOff();
  axes->YAxisMinorTickVisibilityOff();
  axes->ZAxisMinorTickVisibilityOff();
  for (int k = 0; k < 3; ++k) {
    axes->GetTitleTextProperty(k)->SetColor(0.15, 0.15, 0.15);
    axes->GetLabelTextProperty(k)->SetColor(0.15, 0.15, 0.15);
  }
  axes->GetXAxesLinesProperty()->SetColor(0.3, 0.3, 0.3);
  axes->GetYAxesLinesProperty()->SetColor(0.3, 0.3, 0.3);
  axes->GetZAxesLinesProperty()->SetColor(0.3, 0.3, 0.3);
  return axes;
}

// Callouts, placed without overlap beside their points (the camera must be final).
std::vector<vtkSmartPointer<vtkCaptionActor2D>> addCallouts(vtkRenderer* renderer,
                                                            const std::vector<MapCallout>& callouts,
                                                            int width, int height) {
  std::vector<Eigen::Vector2d> at;
  for (const auto& c : callouts) {
    renderer->SetWorldPoint(c.p_w.x(), c.p_w.y(), c.p_w.z(), 1.0);
    renderer->WorldToDisplay();
    double dp[3];
    renderer->GetDisplayPoint(dp);
    at.emplace_back(dp[0], dp[1]);
  }
  const double label_w = 0.26 * width, label_h = 0.055 * height;
  const std::vector<Eigen::Vector2d> where =
      placeCallouts(at, label_w, label_h, 0.84 * width, 0.93 * height);
  std::vector<vtkSmartPointer<vtkCaptionActor2D>> added;
  for (size_t k = 0; k < callouts.size(); ++k) {
    auto cap = vtkSmartPointer<vtkCaptionActor2D>::New();
    cap->SetCaption(callouts[k].text.c_str());
    cap->SetAttachmentPoint(const_cast<double*>(callouts[k].p_w.data()));
    cap->BorderOn();
    cap->LeaderOn();
    cap->ThreeDimensionalLeaderOff();
    vtkTextProperty* text = cap->GetCaptionTextProperty();
    text->SetColor(0.1, 0.1, 0.1);
    text->SetFontSize(13);
    text->BoldOff();
    text->ShadowOff();
    text->ItalicOff();
    text->SetJustificationToLeft();
    cap->GetProperty()->SetColor(0.1, 0.1, 0.1);
    cap->SetPosition(where[k].x() - at[k].x(), where[k].y() - at[k].y());
    cap->SetWidth(label_w / width);
    cap->SetHeight(label_h / height);
    cap->GetTextActor()->SetTextScaleModeToNone();
    renderer->AddActor2D(cap);
    added.push_back(cap);
  }
  return added;
}

}  // namespace

// One VTK scene: the coloured surface and its bounding box in a renderer on top of an overlay
// that holds the colour bar and the title; for each view the camera, the title and the callouts
// (placed once the camera is set), rendered and written. One window for all the views: its
// context, shaders and the surface's buffers are made once (a new window a map cost 0.1-0.15 s
// more a view at 120 000 vertices in the software rasteriser).
void renderDeviationMaps(const std::vector<std::pair<std::string, MapView>>& views,
                         const DeviationMap& map, int width, int height) {
  if (views.empty()) return;
  const vtkSmartPointer<vtkPolyData> poly = colouredSurface(map);
  vtkNew<vtkRenderer> renderer;
  renderer->SetBackground(1, 1, 1);
  renderer->AddActor(surfaceActor(poly));
  renderer->SetViewport(0.0, 0.0, 0.84, 0.93);
  double bounds[6];
  poly->GetBounds(bounds);

  vtkNew<vtkRenderer> overlay;
  overlay->SetBackground(1, 1, 1);
  overlay->SetViewport(0.0, 0.0, 1.0, 1.0);
  overlay->SetLayer(0);
  renderer->SetLayer(1);
  overlay->AddActor2D(colourBar(map));
  vtkNew<vtkTextActor> title;
  title->SetPosition(12, height - 34);
  title->GetTextProperty()->SetFontSize(18);
  title->GetTextProperty()->SetColor(0.1, 0.1, 0.1);
  overlay->AddActor2D(title);

  auto window = offscreenWindow(width, height);
  window->SetNumberOfLayers(2);
  window->AddRenderer(overlay);
  window->AddRenderer(renderer);

  renderer->AddActor(boundingAxes(bounds, renderer->GetActiveCamera()));
  if (!map.markers.empty()) renderer->AddActor(markerActor(map));
  std::vector<vtkSmartPointer<vtkCaptionActor2D>> callouts;
  for (const auto& [png_path, view] : views) {
    aimCamera(renderer, bounds, view);
    title->SetInput(
        (map.title + "   [" + view.name + " view; grey: " + map.grey_means + "]").c_str());
    for (const auto& c : callouts) renderer->RemoveActor2D(c);
    renderer->ResetCameraClippingRange();
    callouts = addCallouts(renderer, map.callouts, width, height);
    window->Render();
    keepGlDriverLoaded();
    writePng(window, png_path);
  }
}

void renderDeviationMap(const std::string& png_path, const DeviationMap& map, const MapView& view,
                        int width, int height) {
  vtk::renderDeviationMaps({{png_path, view}}, map, width, height);
}

void renderHistogram(const std::string& png_path, const std::vector<double>& deviation,
                     const std::vector<double>& weight, double lower, double upper,
                     const std::string& title, int width, int height, const std::string& x_label,
                     const std::string& y_label, const std::string& band_label) {
  double dmin = lower, dmax = upper;
  double total = 0;
  for (size_t i = 0; i < deviation.size(); ++i) {
    dmin = std::min(dmin, deviation[i]);
    dmax = std::max(dmax, deviation[i]);
    total += weight[i];
  }
  const double pad = 0.12 * (dmax - dmin + 1e-9);
  dmin -= pad;
  dmax += pad;
  const int bins = 60;
  std::vector<double> h(bins, 0.0);
  for (size_t i = 0; i < deviation.size(); ++i) {
    const int b =
        std::clamp(static_cast<int>((deviation[i] - dmin) / (dmax - dmin) * bins), 0, bins - 1);
    h[b] += weight[i];
  }
  double hmax = 1e-12;
  for (double& v : h) {
    v = total > 0 ? 100.0 * v / total : 0.0;
    hmax = std::max(hmax, v);
  }
  // Bars in the zone green, beyond it blue (material left) or red (gouge); the limits as lines.
  ScatterChart c;
  c.title = title;
  c.x_label = x_label.empty() ? "normal deviation (µm): + material left, - gouge" : x_label;
  c.y_label = y_label.empty() ? "% of the machined area" : y_label;
  c.width = width;
  c.height = height;
  c.bar_width = mmToUm(dmax - dmin) / bins;
  ScatterSeries in, over, under;
  in.style = over.style = under.style = ScatterSeries::Style::Bars;
  const bool band = !band_label.empty();
  in.legend = band ? "within " + band_label : "in the zone";
  over.legend = band ? "above" : "material left beyond the zone";
  under.legend = band ? "below" : "gouge beyond the zone";
  in.rgb[0] = 46, in.rgb[1] = 160, in.rgb[2] = 67;
  over.rgb[0] = 60, over.rgb[1] = 110, over.rgb[2] = 230;
  under.rgb[0] = 215, under.rgb[1] = 50, under.rgb[2] = 25;
  for (int b = 0; b < bins; ++b) {
    const double mid = dmin + (dmax - dmin) * (b + 0.5) / bins;
    ScatterSeries& s = mid > upper ? over : mid < lower ? under : in;
    s.x.push_back(mmToUm(mid));
    s.y.push_back(h[b]);
  }
  c.series = {in, over, under};
  for (double l : {lower, upper}) {
    ScatterSeries lim;
    lim.style = ScatterSeries::Style::Line;
    lim.radius = 2;
    lim.rgb[0] = lim.rgb[1] = lim.rgb[2] = 20;
    lim.legend = l == lower ? (band ? band_label : std::string("zone limits")) + " " + um(lower) +
                                  " / " + um(upper) + " µm"
                            : "";
    lim.x = {mmToUm(l), mmToUm(l)};
    lim.y = {0.0, hmax * 1.1};
    c.series.push_back(lim);
  }
  c.fixed_x = true;
  c.x_min = mmToUm(dmin);
  c.x_max = mmToUm(dmax);
  c.fixed_y = true;
  c.y_min = 0;
  c.y_max = hmax * 1.15;
  vtk::writeScatterPng(png_path, c);
}

void renderLineProfile(const std::string& png_path, const std::vector<double>& arc_length,
                       const std::vector<double>& total, const std::vector<double>& machine,
                       double lower, double upper, const std::string& title, int width,
                       int height) {
  double xmax = 1e-9;
  for (double a : arc_length) xmax = std::max(xmax, a);
  ScatterChart c;
  c.title = title;
  c.x_label = "arc length along the pass (mm)";
  c.y_label = "normal deviation (µm)";
  c.width = width;
  c.height = height;
  ScatterSeries t, m;
  t.style = m.style = ScatterSeries::Style::Line;
  t.radius = m.radius = 2;
  t.legend = "total (predicted - CAD)";
  m.legend = "machine (predicted - nominal swept)";
  t.rgb[0] = 190, t.rgb[1] = 0, t.rgb[2] = 0;
  m.rgb[0] = 25, m.rgb[1] = 40, m.rgb[2] = 170;
  for (size_t i = 0; i < total.size(); ++i) {
    t.x.push_back(arc_length[i]);
    t.y.push_back(mmToUm(total[i]));
    m.x.push_back(arc_length[i]);
    m.y.push_back(mmToUm(machine[i]));
  }
  c.series = {t, m};
  double lo = lower, hi = upper;
  for (size_t i = 0; i < total.size(); ++i) {
    lo = std::min({lo, total[i], machine[i]});
    hi = std::max({hi, total[i], machine[i]});
  }
  c.fixed_y = true;
  c.y_min = mmToUm(lo - 0.15 * (hi - lo));
  c.y_max = mmToUm(hi + 0.15 * (hi - lo));
  for (double l : {lower, upper}) {
    ScatterSeries lim;
    lim.style = ScatterSeries::Style::Line;
    lim.radius = 1;
    lim.rgb[0] = 46, lim.rgb[1] = 160, lim.rgb[2] = 67;
    lim.legend = l == lower ? "zone limits" : "";
    lim.x = {0.0, xmax};
    lim.y = {mmToUm(l), mmToUm(l)};
    c.series.push_back(lim);
  }
  vtk::writeScatterPng(png_path, c);
}

}  // namespace tolver::vtk

namespace tolver {
// The module's implementations have the headers' types.
static_assert(std::is_same_v<decltype(vtk::renderDeviationMap), decltype(renderDeviationMap)>);
static_assert(std::is_same_v<decltype(vtk::renderDeviationMaps), decltype(renderDeviationMaps)>);
static_assert(std::is_same_v<decltype(vtk::renderHistogram), decltype(renderHistogram)>);
static_assert(std::is_same_v<decltype(vtk::renderLineProfile), decltype(renderLineProfile)>);
static_assert(std::is_same_v<decltype(vtk::writeScatterPng), decltype(writeScatterPng)>);
static_assert(std::is_same_v<decltype(vtk::writeVtpWithScalars), decltype(writeVtpWithScalars)>);
}  // namespace tolver

TOLVER_MODULE_EXPORTS(
    {"renderDeviationMap", reinterpret_cast<void*>(&tolver::vtk::renderDeviationMap)},
    {"renderDeviationMaps", reinterpret_cast<void*>(&tolver::vtk::renderDeviationMaps)},
    {"renderHistogram", reinterpret_cast<void*>(&tolver::vtk::renderHistogram)},
    {"renderLineProfile", reinterpret_cast<void*>(&tolver::vtk::renderLineProfile)},
    {"writeScatterPng", reinterpret_cast<void*>(&tolver::vtk::writeScatterPng)},
    {"writeVtpWithScalars", reinterpret_cast<void*>(&tolver::vtk::writeVtpWithScalars)})
