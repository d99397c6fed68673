// Deviation maps' colours, legends, views and callout places (no rendering: the images are
// drawn by VTK in the tolver_vtk module, io/report/vtk_render.cpp).
#include "io/report/deviation_map.h"

#include <algorithm>
#include <cmath>

#include "core/numerics/lazy_module.h"
#include "core/numerics/units.h"

namespace tolver {

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

Rgb sampleColour(const VerifyResult& r, const std::vector<ToleranceZone>& zones, size_t i) {
  if (r.conformance[i] == Conformance::Unmachined) return kUnmachinedColour;
  if (r.conformance[i] == Conformance::Unchecked) return kUncheckedColour;
  return deviationColour(r.total[i], zones[r.zone[i]].lower, zones[r.zone[i]].upper);
}

std::vector<LegendBand> deviationLegend(double lower, double upper, double saturation) {
  // The bands of deviationColour, at its own boundaries.
  const double half = std::max(0.5 * (upper - lower), 1e-12);
  const double band = std::max((saturation - 1.0) * half / 4.0, 1e-12);
  std::vector<LegendBand> out;
  for (int k = 3; k >= 0; --k)
    out.push_back({deviationColour(lower - (k + 0.5) * band, lower, upper, saturation),
                   k == 3 ? -INFINITY : lower - (k + 1) * band, lower - k * band});
  out.push_back({deviationColour(0.5 * (lower + upper), lower, upper, saturation), lower, upper});
  for (int k = 0; k < 4; ++k)
    out.push_back({deviationColour(upper + (k + 0.5) * band, lower, upper, saturation),
                   upper + k * band, k == 3 ? INFINITY : upper + (k + 1) * band});
  return out;
}

std::vector<MapView> deviationMapViews(const SurfaceSamples& s, const VerifyResult& r) {
  std::vector<MapView> views = {
      {"isometric", Eigen::Vector3d(-1, 1, -1), Eigen::Vector3d::UnitZ(), false, {}},
      {"top", Eigen::Vector3d(0, 0, -1), Eigen::Vector3d::UnitY(), false, {}}};
  auto upFor = [](const Eigen::Vector3d& n) {
    return std::abs(n.z()) > 0.9 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitZ();
  };
  for (size_t k = 0; k < r.regions.size() && k < 3; ++k) {
    const auto& g = r.regions[k];
    views.push_back({k == 0 ? "worst" : "region" + std::to_string(k + 1), -g.normal_w,
                     upFor(g.normal_w), true, g.where_w});
  }
  if (r.regions.empty()) {
    int worst = r.total_stats.max_sample;
    if (r.total_stats.min_sample >= 0 && std::abs(r.total_stats.min) > std::abs(r.total_stats.max))
      worst = r.total_stats.min_sample;
    if (worst >= 0)
      views.push_back({"worst", -s.n_w[worst], upFor(s.n_w[worst]), true, s.p_w[worst]});
  }
  return views;
}

std::vector<Eigen::Vector2d> placeCallouts(const std::vector<Eigen::Vector2d>& at, double label_w,
                                           double label_h, double view_w, double view_h) {
  std::vector<size_t> order(at.size());
  for (size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return at[a].y() < at[b].y(); });
  std::vector<Eigen::Vector2d> out(at.size());
  double next_free = 0;
  for (size_t k : order) {
    const double x = at[k].x() + 30 + label_w < view_w ? at[k].x() + 30
                                                       : std::max(5.0, at[k].x() - 30 - label_w);
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

// The renderers, in the tolver_vtk module (core/numerics/lazy_module.h).
void renderDeviationMap(const std::string& png_path, const DeviationMap& map, const MapView& view,
                        int width, int height) {
  moduleFunction<decltype(renderDeviationMap)>("tolver_vtk", "renderDeviationMap")(
      png_path, map, view, width, height);
}

void renderDeviationMaps(const std::vector<std::pair<std::string, MapView>>& views,
                         const DeviationMap& map, int width, int height) {
  moduleFunction<decltype(renderDeviationMaps)>("tolver_vtk", "renderDeviationMaps")(views, map,
                                                                                     width, height);
}

void renderHistogram(const std::string& png_path, const std::vector<double>& deviation,
                     const std::vector<double>& weight, double lower, double upper,
                     const std::string& title, int width, int height, const std::string& x_label,
                     const std::string& y_label, const std::string& band_label) {
  moduleFunction<decltype(renderHistogram)>("tolver_vtk", "renderHistogram")(
      png_path, deviation, weight, lower, upper, title, width, height, x_label, y_label,
      band_label);
}

void renderLineProfile(const std::string& png_path, const std::vector<double>& arc_length,
                       const std::vector<double>& total, const std::vector<double>& machine,
                       double lower, double upper, const std::string& title, int width,
                       int height) {
  moduleFunction<decltype(renderLineProfile)>("tolver_vtk", "renderLineProfile")(
      png_path, arc_length, total, machine, lower, upper, title, width, height);
}

}  // namespace tolver
