#include "io/report/png_plot.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/numerics/lazy_module.h"

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

// The chart, drawn by VTK in the tolver_vtk module (io/report/vtk_render.cpp).
void writeScatterPng(const std::string& path, const ScatterChart& chart) {
  moduleFunction<decltype(writeScatterPng)>("tolver_vtk", "writeScatterPng")(path, chart);
}

}  // namespace tolver
