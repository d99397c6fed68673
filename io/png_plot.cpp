#include "io/png_plot.h"

#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "io/io_error.h"

namespace tolver {

void writeScatterPng(const std::string& path, const std::vector<ScatterSeries>& series, int width,
                     int height) {
  vtkNew<vtkImageData> img;
  img->SetDimensions(width, height, 1);
  img->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* px = static_cast<unsigned char*>(img->GetScalarPointer());
  std::fill(px, px + 3 * width * height, 255);
  auto put = [&](int x, int y, const unsigned char* c) {
    if (x < 0 || y < 0 || x >= width || y >= height) return;
    unsigned char* p = px + 3 * (y * width + x);  // VTK rows run bottom-up
    p[0] = c[0];
    p[1] = c[1];
    p[2] = c[2];
  };
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
  for (const auto& s : series)
    for (size_t i = 0; i < s.x.size(); ++i) {
      x0 = std::min(x0, s.x[i]);
      x1 = std::max(x1, s.x[i]);
      y0 = std::min(y0, s.y[i]);
      y1 = std::max(y1, s.y[i]);
    }
  if (!(x1 > x0)) x1 = x0 + 1, x0 -= 1;
  if (!(y1 > y0)) y1 = y0 + 1, y0 -= 1;
  const int m = 40;
  const unsigned char axis[3] = {60, 60, 60};
  for (int x = m; x < width - m; ++x) put(x, m, axis);
  for (int y = m; y < height - m; ++y) put(m, y, axis);
  for (int k = 0; k <= 10; ++k) {  // tick marks every tenth of the range
    const int tx = m + k * (width - 2 * m) / 10, ty = m + k * (height - 2 * m) / 10;
    for (int d = 1; d <= 6; ++d) {
      put(tx, m - d, axis);
      put(m - d, ty, axis);
    }
  }
  for (const auto& s : series)
    for (size_t i = 0; i < s.x.size(); ++i) {
      const int cx = m + static_cast<int>(std::lround((s.x[i] - x0) / (x1 - x0) * (width - 2 * m)));
      const int cy = m + static_cast<int>(std::lround((s.y[i] - y0) / (y1 - y0) * (height - 2 * m)));
      for (int dy = -s.radius; dy <= s.radius; ++dy)
        for (int dx = -s.radius; dx <= s.radius; ++dx)
          if (dx * dx + dy * dy <= s.radius * s.radius) put(cx + dx, cy + dy, s.rgb);
    }
  const std::string tmp = path + ".tmp-tolver.png";
  vtkNew<vtkPNGWriter> w;
  w->SetFileName(tmp.c_str());
  w->SetInputData(img);
  w->Write();
  if (w->GetErrorCode() != 0 || std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw InputError(path, 0, 0, "output", "cannot write the PNG image");
  }
}

}  // namespace tolver
