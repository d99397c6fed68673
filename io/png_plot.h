#pragma once
// Small raster plots written as PNG (VTK's PNG writer; no window or display needed).
#include <string>
#include <vector>

namespace tolver {

struct ScatterSeries {
  std::vector<double> x, y;
  unsigned char rgb[3] = {40, 90, 200};
  int radius = 3;  // pixels
};

// A scatter plot of the series on common axes (frame and tick marks, no text: the report that
// embeds the image names the axes). Written atomically. Throws InputError when it cannot write.
void writeScatterPng(const std::string& path, const std::vector<ScatterSeries>& series,
                     int width = 640, int height = 420);

}  // namespace tolver
