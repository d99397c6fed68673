// Rendered maps have the colours the scale promises at known pixels.
#include "io/deviation_map.h"

#include <gtest/gtest.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>

#include "io/offscreen_display.h"
#include "test_support.h"

namespace tolver {
namespace {

TEST(DeviationMap, ColourScaleIsGreenInsideRedForGougesBlueForExcess) {
  const Rgb in = deviationColour(0.0, -0.01, 0.01);
  EXPECT_GT(in[1], in[0] + 60);
  EXPECT_GT(in[1], in[2] + 60);
  const Rgb gouge = deviationColour(-0.05, -0.01, 0.01);  // saturated
  EXPECT_EQ(gouge, (Rgb{190, 0, 0}));
  const Rgb excess = deviationColour(0.05, -0.01, 0.01);
  EXPECT_EQ(excess, (Rgb{25, 40, 170}));
  // Exactly at a limit: still the band's colour (green dominant).
  const Rgb edge = deviationColour(0.01, -0.01, 0.01);
  EXPECT_GT(edge[1], edge[0]);
}

class RenderTest : public test::TempDirTest {};

// A 100 x 100 mm plane in tolerance with a planted gouge (-50 um) of radius 15 mm at its centre,
// seen from the top: the centre pixel of the view is red, a pixel 30 mm away green.
TEST_F(RenderTest, TopViewShowsAPlantedGougeRedOnGreen) {
  std::string why;
  ASSERT_TRUE(ensureDisplay(&why)) << why;
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3i> faces;
  const int n = 100;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) points.emplace_back(-50.0 + i, -50.0 + j, 0.0);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i;
      faces.emplace_back(a, a + 1, a + n + 2);
      faces.emplace_back(a, a + n + 2, a + n + 1);
    }
  DeviationMap map;
  map.points = &points;
  map.faces = &faces;
  for (const auto& p : points)
    map.colours.push_back(deviationColour(p.head<2>().norm() < 15.0 ? -0.05 : 0.002, -0.01, 0.01));
  map.title = "test";
  const std::string png = path("map.png");
  renderDeviationMap(png, map, {"top", Eigen::Vector3d(0, 0, -1), Eigen::Vector3d::UnitY(), false, {}}, 1200, 900);

  vtkNew<vtkPNGReader> reader;
  reader->SetFileName(png.c_str());
  reader->Update();
  vtkImageData* img = reader->GetOutput();
  int dims[3];
  img->GetDimensions(dims);
  ASSERT_EQ(dims[0], 1200);
  ASSERT_EQ(dims[1], 900);
  auto pixel = [&](int x, int y) {
    Rgb c;
    for (int k = 0; k < 3; ++k)
      c[k] = static_cast<unsigned char>(img->GetScalarComponentAsDouble(x, y, 0, k));
    return c;
  };
  // The 3-D view spans x in [0, 0.84 w], y in [0, 0.93 h] (VTK images start bottom left).
  const int cx = static_cast<int>(0.42 * 1200), cy = static_cast<int>(0.465 * 900);
  const Rgb centre = pixel(cx, cy);
  EXPECT_GT(centre[0], 120) << int(centre[0]) << " " << int(centre[1]) << " " << int(centre[2]);
  EXPECT_LT(centre[1], 60);
  EXPECT_LT(centre[2], 60);
  // 30 mm up: the plane spans most of the view's height (837 px for 100 mm or a bit less).
  const Rgb away = pixel(cx, cy + 200);
  EXPECT_GT(away[1], away[0] + 40) << int(away[0]) << " " << int(away[1]) << " " << int(away[2]);
  EXPECT_GT(away[1], away[2] + 40);
  // Background white in the corner of the view.
  const Rgb corner = pixel(5, 5);
  EXPECT_EQ(corner, (Rgb{255, 255, 255}));
}

}  // namespace
}  // namespace tolver
