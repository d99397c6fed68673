#include "io/deviation_map.h"

#include <vtkActor.h>
#include <vtkActor2D.h>
#include <vtkCamera.h>
#include <vtkCaptionActor2D.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCubeAxesActor.h>
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
  // Discrete steps, as inspection software draws them: one colour in the zone, then four bands
  // beyond each limit, the last one saturated.
  static const Rgb in_zone = {46, 160, 67};
  static const Rgb gouge[4] = {{250, 205, 40}, {245, 135, 30}, {215, 50, 25}, {150, 0, 0}};
  static const Rgb excess[4] = {{120, 175, 245}, {60, 110, 230}, {35, 60, 185}, {20, 25, 125}};
  const double half = std::max(0.5 * (upper - lower), 1e-12);
  const double band = std::max((saturation - 1.0) * half / 4.0, 1e-12);
  if (d < lower) return gouge[std::clamp(static_cast<int>((lower - d) / band), 0, 3)];
  if (d > upper) return excess[std::clamp(static_cast<int>((d - upper) / band), 0, 3)];
  return in_zone;
}

std::vector<Eigen::Vector2d> placeCallouts(const std::vector<Eigen::Vector2d>& at, double label_w,
                                           double label_h, double view_w, double view_h) {
  std::vector<size_t> order(at.size());
  for (size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return at[a].y() < at[b].y(); });
  std::vector<Eigen::Vector2d> out(at.size());
  double next_free = 0;
  for (size_t k : order) {
    const double x = at[k].x() + 30 + label_w < view_w ? at[k].x() + 30 : std::max(5.0, at[k].x() - 30 - label_w);
    const double y = std::max(at[k].y() + 30, next_free);
    out[k] = Eigen::Vector2d(x, y);
    next_free = y + label_h + 6;
  }
  // Labels pushed above the view come down as a stack from its top.
  double top = view_h - 5;
  for (auto it = order.rbegin(); it != order.rend(); ++it) {
    if (out[*it].y() + label_h > top) out[*it].y() = top - label_h;
    top = out[*it].y() - 6;
  }
  return out;
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
  // The whole part in every view (a region's view looks along its normal; nothing is cropped),
  // with room for the box's coordinates.
  cam->Zoom(0.85);
  renderer->ResetCameraClippingRange();

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
  // The band boundaries beyond the limits.
  const double band = 2.0 * half / 4.0;
  for (int k = 1; k <= 3; ++k) {
    lut->SetAnnotation(vtkVariant((up + k * band) * 1e3), um(up + k * band).c_str());
    lut->SetAnnotation(vtkVariant((lo - k * band) * 1e3), um(lo - k * band).c_str());
  }
  vtkNew<vtkScalarBarActor> bar;
  bar->SetLookupTable(lut);
  bar->SetTitle("deviation um\n+ material left\n- gouge");
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

  // The part's bounding box with its coordinates in mm (the axes' directions and a scale).
  vtkNew<vtkCubeAxesActor> axes;
  axes->SetBounds(bounds);
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
  renderer->AddActor(axes);
  renderer->ResetCameraClippingRange();

  // Callouts, placed without overlap beside their points.
  struct Placed {
    const MapCallout* c;
    double x, y;  // the attachment in display pixels
    double lx = 0, ly = 0;
  };
  std::vector<Placed> placed;
  std::vector<Eigen::Vector2d> at;
  for (const auto& c : map.callouts) {
    renderer->SetWorldPoint(c.p_w.x(), c.p_w.y(), c.p_w.z(), 1.0);
    renderer->WorldToDisplay();
    double dp[3];
    renderer->GetDisplayPoint(dp);
    placed.push_back({&c, dp[0], dp[1]});
    at.emplace_back(dp[0], dp[1]);
  }
  const double label_w = 0.26 * width, label_h = 0.055 * height;
  const std::vector<Eigen::Vector2d> where = placeCallouts(at, label_w, label_h, 0.84 * width, 0.93 * height);
  for (size_t k = 0; k < placed.size(); ++k) {
    placed[k].lx = where[k].x();
    placed[k].ly = where[k].y();
  }
  for (const Placed& p : placed) {
    vtkNew<vtkCaptionActor2D> cap;
    cap->SetCaption(p.c->text.c_str());
    cap->SetAttachmentPoint(const_cast<double*>(p.c->p_w.data()));
    cap->BorderOn();
    cap->LeaderOn();
    cap->ThreeDimensionalLeaderOff();
    cap->GetCaptionTextProperty()->SetColor(0.1, 0.1, 0.1);
    cap->GetCaptionTextProperty()->SetFontSize(13);
    cap->GetCaptionTextProperty()->BoldOff();
    cap->GetCaptionTextProperty()->ShadowOff();
    cap->GetCaptionTextProperty()->ItalicOff();
    cap->GetCaptionTextProperty()->SetJustificationToLeft();
    cap->GetProperty()->SetColor(0.1, 0.1, 0.1);
    cap->SetPosition(p.lx - p.x, p.ly - p.y);
    cap->SetWidth(label_w / width);
    cap->SetHeight(label_h / height);
    cap->GetTextActor()->SetTextScaleModeToNone();
    renderer->AddActor2D(cap);
  }
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
