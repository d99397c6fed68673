#include "io/deviation_map.h"

#include <vtkActor.h>
#include <vtkActor2D.h>
#include <vtkCamera.h>
#include <vtkCaptionActor2D.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkLookupTable.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
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
#include <vtkTextActor.h>
#include <vtkTextProperty.h>
#include <vtkUnsignedCharArray.h>
#include <vtkWindowToImageFilter.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "io/io_error.h"

namespace tolver {
namespace {

Rgb mix(const Rgb& a, const Rgb& b, double t) {
  t = std::clamp(t, 0.0, 1.0);
  Rgb c;
  for (int k = 0; k < 3; ++k) c[k] = static_cast<unsigned char>(std::lround(a[k] + t * (b[k] - a[k])));
  return c;
}

std::string um(double mm) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%+.1f", mm * 1e3);
  return buf;
}

void writePng(vtkRenderWindow* window, const std::string& path) {
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(window);
  grab->ReadFrontBufferOff();
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
  w->SetMultiSamples(4);
  return w;
}

// 2-D drawing in pixel coordinates (origin bottom left): filled quads, lines and text.
class Canvas {
 public:
  Canvas(int width, int height) : width_(width), height_(height) {
    points_->SetDataTypeToDouble();
    colours_->SetNumberOfComponents(3);
    line_colours_->SetNumberOfComponents(3);
    renderer_->SetBackground(1, 1, 1);
  }
  void rect(double x0, double y0, double x1, double y1, const Rgb& c) {
    const vtkIdType base = points_->GetNumberOfPoints();
    points_->InsertNextPoint(x0, y0, 0);
    points_->InsertNextPoint(x1, y0, 0);
    points_->InsertNextPoint(x1, y1, 0);
    points_->InsertNextPoint(x0, y1, 0);
    const vtkIdType ids[4] = {base, base + 1, base + 2, base + 3};
    quads_->InsertNextCell(4, ids);
    colours_->InsertNextTypedTuple(c.data());
  }
  void line(const std::vector<double>& x, const std::vector<double>& y, const Rgb& c) {
    const vtkIdType base = line_points_->GetNumberOfPoints();
    std::vector<vtkIdType> ids;
    for (size_t i = 0; i < x.size(); ++i) {
      line_points_->InsertNextPoint(x[i], y[i], 0);
      ids.push_back(base + static_cast<vtkIdType>(i));
    }
    lines_->InsertNextCell(static_cast<vtkIdType>(ids.size()), ids.data());
    line_colours_->InsertNextTypedTuple(c.data());
  }
  void text(const std::string& s, double x, double y, int size, int justify = 0, bool bold = false,
            double angle = 0) {
    vtkNew<vtkTextActor> t;
    t->SetInput(s.c_str());
    t->SetPosition(x, y);
    t->GetTextProperty()->SetFontSize(size);
    t->GetTextProperty()->SetColor(0.1, 0.1, 0.1);
    t->GetTextProperty()->SetBold(bold);
    t->GetTextProperty()->SetJustification(justify);  // 0 left, 1 centred, 2 right
    t->GetTextProperty()->SetOrientation(angle);
    renderer_->AddActor2D(t);
  }
  void write(const std::string& path) {
    vtkNew<vtkPolyData> quads;
    quads->SetPoints(points_);
    quads->SetPolys(quads_);
    quads->GetCellData()->SetScalars(colours_);
    vtkNew<vtkPolyDataMapper2D> qm;
    qm->SetInputData(quads);
    qm->SetColorModeToDirectScalars();
    vtkNew<vtkActor2D> qa;
    qa->SetMapper(qm);
    renderer_->AddActor2D(qa);
    vtkNew<vtkPolyData> lines;
    lines->SetPoints(line_points_);
    lines->SetLines(lines_);
    lines->GetCellData()->SetScalars(line_colours_);
    vtkNew<vtkPolyDataMapper2D> lm;
    lm->SetInputData(lines);
    lm->SetColorModeToDirectScalars();
    vtkNew<vtkActor2D> la;
    la->SetMapper(lm);
    la->GetProperty()->SetLineWidth(2);
    renderer_->AddActor2D(la);
    auto window = offscreenWindow(width_, height_);
    window->AddRenderer(renderer_);
    window->Render();
    writePng(window, path);
  }

 private:
  int width_, height_;
  vtkNew<vtkPoints> points_, line_points_;
  vtkNew<vtkCellArray> quads_, lines_;
  vtkNew<vtkUnsignedCharArray> colours_, line_colours_;
  vtkNew<vtkRenderer> renderer_;
};

// Axis frame with ticks for plots: maps data to pixels.
struct Frame {
  double x0, y0, x1, y1;        // pixel box
  double xmin, xmax, ymin, ymax;
  double px(double x) const { return x0 + (x - xmin) / (xmax - xmin) * (x1 - x0); }
  double py(double y) const { return y0 + (y - ymin) / (ymax - ymin) * (y1 - y0); }
};

double niceStep(double range) {
  const double raw = range / 6.0;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10 * p;
}

void drawAxes(Canvas& c, const Frame& f, const std::string& xlabel, const std::string& ylabel) {
  const Rgb ink = {60, 60, 60};
  c.line({f.x0, f.x1, f.x1, f.x0, f.x0}, {f.y0, f.y0, f.y1, f.y1, f.y0}, ink);
  const double sx = niceStep(f.xmax - f.xmin), sy = niceStep(f.ymax - f.ymin);
  char buf[32];
  for (double x = std::ceil(f.xmin / sx) * sx; x <= f.xmax + 1e-9 * sx; x += sx) {
    c.line({f.px(x), f.px(x)}, {f.y0, f.y0 - 6}, ink);
    std::snprintf(buf, sizeof buf, "%g", std::abs(x) < 1e-9 * sx ? 0.0 : x);
    c.text(buf, f.px(x), f.y0 - 24, 14, 1);
  }
  for (double y = std::ceil(f.ymin / sy) * sy; y <= f.ymax + 1e-9 * sy; y += sy) {
    c.line({f.x0, f.x0 - 6}, {f.py(y), f.py(y)}, ink);
    std::snprintf(buf, sizeof buf, "%g", std::abs(y) < 1e-9 * sy ? 0.0 : y);
    c.text(buf, f.x0 - 10, f.py(y) - 6, 14, 2);
  }
  c.text(xlabel, 0.5 * (f.x0 + f.x1), f.y0 - 48, 15, 1);
  c.text(ylabel, f.x0 - 62, 0.5 * (f.y0 + f.y1), 15, 1, false, 90);
}

}  // namespace

Rgb deviationColour(double d, double lower, double upper, double saturation) {
  static const Rgb low_edge = {168, 214, 88}, centre = {46, 160, 67}, high_edge = {88, 196, 160};
  static const Rgb gouge0 = {250, 160, 60}, gouge1 = {190, 0, 0};
  static const Rgb excess0 = {120, 165, 240}, excess1 = {25, 40, 170};
  const double mid = 0.5 * (lower + upper), half = std::max(0.5 * (upper - lower), 1e-12);
  const double x = (d - mid) / half;
  if (d < lower) return mix(gouge0, gouge1, (-x - 1.0) / (saturation - 1.0));
  if (d > upper) return mix(excess0, excess1, (x - 1.0) / (saturation - 1.0));
  return x < 0 ? mix(centre, low_edge, -x) : mix(centre, high_edge, x);
}

void renderDeviationMap(const std::string& png_path, const DeviationMap& map, const MapView& view,
                        int width, int height) {
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
  vtkNew<vtkPolyData> poly;
  poly->SetPoints(pts);
  poly->SetPolys(cells);
  poly->GetPointData()->SetScalars(rgb);

  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputData(poly);
  mapper->SetColorModeToDirectScalars();
  mapper->ScalarVisibilityOn();
  vtkNew<vtkActor> actor;
  actor->SetMapper(mapper);
  actor->GetProperty()->SetAmbient(0.35);
  actor->GetProperty()->SetDiffuse(0.65);
  actor->GetProperty()->SetSpecular(0.0);
  actor->GetProperty()->BackfaceCullingOff();

  vtkNew<vtkRenderer> renderer;
  renderer->SetBackground(1, 1, 1);
  renderer->AddActor(actor);
  renderer->SetViewport(0.0, 0.0, 0.84, 0.93);

  // Camera: looking along view.direction at the whole part, or zoomed onto the focus point.
  vtkCamera* cam = renderer->GetActiveCamera();
  double bounds[6];
  poly->GetBounds(bounds);
  const Eigen::Vector3d centre(0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]),
                               0.5 * (bounds[4] + bounds[5]));
  const Eigen::Vector3d dir = view.direction.normalized();
  cam->SetFocalPoint(centre.data());
  const Eigen::Vector3d eye = centre - dir * 1000.0;
  cam->SetPosition(eye.data());
  cam->SetViewUp(view.up.data());
  cam->ParallelProjectionOn();
  renderer->ResetCamera();
  if (view.focus) {
    const Eigen::Vector3d shift = view.focus_w - centre;
    double fp[3], pos[3];
    cam->GetFocalPoint(fp);
    cam->GetPosition(pos);
    for (int k = 0; k < 3; ++k) {
      fp[k] += shift[k];
      pos[k] += shift[k];
    }
    cam->SetFocalPoint(fp);
    cam->SetPosition(pos);
    cam->Zoom(2.5);
  }
  renderer->ResetCameraClippingRange();

  // Callouts at the worst points.
  for (const auto& c : map.callouts) {
    vtkNew<vtkCaptionActor2D> cap;
    cap->SetCaption(c.text.c_str());
    cap->SetAttachmentPoint(const_cast<double*>(c.p_w.data()));
    cap->BorderOn();
    cap->LeaderOn();
    cap->ThreeDimensionalLeaderOff();
    cap->GetCaptionTextProperty()->SetColor(0.1, 0.1, 0.1);
    cap->GetCaptionTextProperty()->SetFontSize(14);
    cap->GetCaptionTextProperty()->BoldOff();
    cap->GetCaptionTextProperty()->ShadowOff();
    cap->GetCaptionTextProperty()->ItalicOff();
    cap->GetProperty()->SetColor(0.1, 0.1, 0.1);
    cap->SetPosition(25, 25);
    cap->SetWidth(0.11);
    cap->SetHeight(0.04);
    renderer->AddActor2D(cap);
  }

  // Colour bar: the same colour function sampled over the zone and beyond, in um.
  const double lo = map.bar_lower, up = map.bar_upper, half = 0.5 * (up - lo), mid = 0.5 * (lo + up);
  const double range_lo = mid - 3.0 * half, range_hi = mid + 3.0 * half;
  vtkNew<vtkLookupTable> lut;
  const int n = 240;
  lut->SetNumberOfTableValues(n);
  lut->SetTableRange(range_lo * 1e3, range_hi * 1e3);
  for (int i = 0; i < n; ++i) {
    const double d = range_lo + (i + 0.5) / n * (range_hi - range_lo);
    const Rgb c = deviationColour(d, lo, up);
    lut->SetTableValue(i, c[0] / 255.0, c[1] / 255.0, c[2] / 255.0, 1.0);
  }
  lut->SetAnnotation(vtkVariant(lo * 1e3), ("lower " + um(lo)).c_str());
  lut->SetAnnotation(vtkVariant(up * 1e3), ("upper " + um(up)).c_str());
  vtkNew<vtkScalarBarActor> bar;
  bar->SetLookupTable(lut);
  bar->SetTitle("deviation um\n+ material left\n- gouge");
  bar->SetNumberOfLabels(7);
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
  vtkNew<vtkRenderer> overlay;
  overlay->SetBackground(1, 1, 1);
  overlay->SetViewport(0.0, 0.0, 1.0, 1.0);
  overlay->SetLayer(0);
  renderer->SetLayer(1);
  overlay->AddActor2D(bar);
  vtkNew<vtkTextActor> title;
  title->SetInput((map.title + "   [" + view.name + " view; grey: not machined]").c_str());
  title->SetPosition(12, height - 34);
  title->GetTextProperty()->SetFontSize(18);
  title->GetTextProperty()->SetColor(0.1, 0.1, 0.1);
  overlay->AddActor2D(title);

  auto window = offscreenWindow(width, height);
  window->SetNumberOfLayers(2);
  window->AddRenderer(overlay);
  window->AddRenderer(renderer);
  renderer->SetBackground(1, 1, 1);
  window->Render();
  writePng(window, png_path);
}

void renderHistogram(const std::string& png_path, const std::vector<double>& deviation,
                     const std::vector<double>& weight, double lower, double upper,
                     const std::string& title, int width, int height) {
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
    const int b = std::clamp(static_cast<int>((deviation[i] - dmin) / (dmax - dmin) * bins), 0, bins - 1);
    h[b] += weight[i];
  }
  double hmax = 1e-12;
  for (double& v : h) {
    v = total > 0 ? 100.0 * v / total : 0.0;
    hmax = std::max(hmax, v);
  }
  Canvas c(width, height);
  const Frame f{90, 80, width - 30.0, height - 50.0, dmin * 1e3, dmax * 1e3, 0, hmax * 1.1};
  for (int b = 0; b < bins; ++b) {
    const double a = dmin + (dmax - dmin) * b / bins, e = dmin + (dmax - dmin) * (b + 1) / bins;
    if (h[b] <= 0) continue;
    c.rect(f.px(a * 1e3), f.py(0), f.px(e * 1e3) - 1, f.py(h[b]), deviationColour(0.5 * (a + e), lower, upper));
  }
  const Rgb limit = {20, 20, 20};
  for (double l : {lower, upper}) c.line({f.px(l * 1e3), f.px(l * 1e3)}, {f.y0, f.y1}, limit);
  c.text("lower " + um(lower), f.px(lower * 1e3) - 4, f.y1 - 18, 13, 2);
  c.text("upper " + um(upper), f.px(upper * 1e3) + 4, f.y1 - 18, 13, 0);
  drawAxes(c, f, "normal deviation, um (+ material left, - gouge)", "% of machined area");
  c.text(title, 12, height - 30, 17, 0, true);
  c.write(png_path);
}

void renderLineProfile(const std::string& png_path, const std::vector<double>& arc_length,
                       const std::vector<double>& total, const std::vector<double>& machine,
                       double lower, double upper, const std::string& title, int width,
                       int height) {
  double ymin = lower, ymax = upper, xmax = 1e-9;
  for (size_t i = 0; i < total.size(); ++i) {
    ymin = std::min({ymin, total[i], machine[i]});
    ymax = std::max({ymax, total[i], machine[i]});
    xmax = std::max(xmax, arc_length[i]);
  }
  const double pad = 0.1 * (ymax - ymin);
  Canvas c(width, height);
  const Frame f{90, 80, width - 30.0, height - 50.0, 0, xmax, (ymin - pad) * 1e3, (ymax + pad) * 1e3};
  c.rect(f.x0 + 1, f.py(lower * 1e3), f.x1 - 1, f.py(upper * 1e3), {215, 238, 215});
  std::vector<double> x, yt, ym;
  for (size_t i = 0; i < total.size(); ++i) {
    x.push_back(f.px(arc_length[i]));
    yt.push_back(f.py(total[i] * 1e3));
    ym.push_back(f.py(machine[i] * 1e3));
  }
  if (x.size() >= 2) {
    c.line(x, yt, {190, 0, 0});
    c.line(x, ym, {25, 40, 170});
  }
  drawAxes(c, f, "arc length along the pass, mm", "normal deviation, um");
  c.text("red: total (predicted - CAD)   blue: machine (predicted - nominal swept)   green: zone",
         f.x0 + 8, f.y1 + 8, 13);
  c.text(title, 12, height - 30, 17, 0, true);
  c.write(png_path);
}

}  // namespace tolver
