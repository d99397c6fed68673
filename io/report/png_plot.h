#pragma once
// Charts written as PNG, drawn by VTK's chart module (vtkChartXY) off screen: points, lines or
// bars; a title, axis titles with units, tick numbers, a legend, and, for before/after pairs, a
// shared scale.
#include <string>
#include <vector>

namespace tolver {

struct ScatterSeries {
  std::vector<double> x, y;
  unsigned char rgb[3] = {40, 90, 200};
  int radius = 3;      // pixels (points), line width (lines)
  std::string legend;  // empty: not in the legend
  enum class Style { Points, Line, Bars } style = Style::Points;
};

struct ScatterChart {
  std::string title, x_label, y_label;  // labels carry their units: "residual (µm)"
  std::vector<ScatterSeries> series;
  bool fixed_y = false;  // y from y_min to y_max (a scale shared between charts)
  double y_min = 0.0, y_max = 0.0;
  bool fixed_x = false;  // x from x_min to x_max
  double x_min = 0.0, x_max = 0.0;
  double bar_width = 0.0;  // bars: their width in x units (0: VTK's default)
  int width = 640, height = 420;
};

// Written atomically. Throws InputError when it cannot render (no display: see
// io/report/offscreen_display.h) or write.
void writeScatterPng(const std::string& path, const ScatterChart& chart);

// A range covering every y of the series with 5 % headroom: the shared scale of a pair.
void sharedYRange(const std::vector<const std::vector<ScatterSeries>*>& charts, double* y_min,
                  double* y_max);

}  // namespace tolver
