// Rendered maps have the colours the scale promises at known pixels.
#include "io/report/deviation_map.h"

#include <gtest/gtest.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>

#include <set>

#include "io/report/offscreen_display.h"
#include "test_support.h"

namespace tolver {
namespace {

// Discrete steps with the zone limits as boundaries: one colour in the zone (the limits
// included), then a band per 5 um (a quarter of the way to saturation at 3 half-widths) beyond
// each limit, each its own colour, the last one saturated.
TEST(DeviationMap, ColourScaleHasDiscreteStepsAtTheZoneLimits) {
  const Rgb in = deviationColour(0.0, -0.01, 0.01);
  EXPECT_GT(in[1], in[0] + 60);
  EXPECT_GT(in[1], in[2] + 60);
  EXPECT_EQ(deviationColour(0.0099, -0.01, 0.01), in);
  EXPECT_EQ(deviationColour(-0.01, -0.01, 0.01), in);  // exactly at a limit: in
  EXPECT_EQ(deviationColour(0.01, -0.01, 0.01), in);
  // +10.5 um against +-10: a colour clearly not green (blue dominant).
  const Rgb just_out = deviationColour(0.0105, -0.01, 0.01);
  EXPECT_GT(just_out[2], just_out[1] + 40);
  std::set<Rgb> excess, gouge;
  for (int k = 0; k < 4; ++k) {
    excess.insert(deviationColour(0.01 + 0.0025 + 0.005 * k, -0.01, 0.01));
    gouge.insert(deviationColour(-0.01 - 0.0025 - 0.005 * k, -0.01, 0.01));
  }
  EXPECT_EQ(excess.size(), 4u);  // four distinct steps each side
  EXPECT_EQ(gouge.size(), 4u);
  EXPECT_EQ(deviationColour(0.05, -0.01, 0.01), (Rgb{20, 25, 125}));  // saturated
  EXPECT_EQ(deviationColour(-0.05, -0.01, 0.01), (Rgb{150, 0, 0}));
  EXPECT_EQ(deviationColour(0.013, -0.01, 0.01), deviationColour(0.0149, -0.01, 0.01));  // one step
}

// Callouts never cover each other, also when their points crowd together or near the top.
TEST(DeviationMap, CalloutsArePlacedWithoutOverlap) {
  const double w = 300, h = 50;
  for (const std::vector<Eigen::Vector2d>& at :
       {std::vector<Eigen::Vector2d>{{100, 100}, {110, 105}, {120, 98}},
        std::vector<Eigen::Vector2d>{{900, 800}, {905, 810}, {50, 790}},
        std::vector<Eigen::Vector2d>{{400, 400}}}) {
    const auto p = placeCallouts(at, w, h, 1008, 837);
    ASSERT_EQ(p.size(), at.size());
    for (size_t a = 0; a < p.size(); ++a) {
      EXPECT_GE(p[a].x(), 0);
      EXPECT_LE(p[a].x() + w, 1008 + 1e-9);
      EXPECT_GE(p[a].y(), 0);
      EXPECT_LE(p[a].y() + h, 837 + 1e-9);
      for (size_t b = a + 1; b < p.size(); ++b) {
        const bool apart = p[a].x() + w <= p[b].x() || p[b].x() + w <= p[a].x() ||
                           p[a].y() + h <= p[b].y() || p[b].y() + h <= p[a].y();
        EXPECT_TRUE(apart) << a << " " << b;
      }
    }
  }
}

class RenderTest : public test::TempDirTest {};

// An n x n grid of squares of side `step` from (x0, x0), two triangles each, at height
// slope * (x - x0 - n step / 2).
void squareGrid(int n, double x0, double step, double slope, std::vector<Eigen::Vector3d>* points,
                std::vector<Eigen::Vector3i>* faces) {
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      points->emplace_back(x0 + step * i, x0 + step * j, slope * step * (i - 0.5 * n));
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i;
      faces->emplace_back(a, a + 1, a + n + 2);
      faces->emplace_back(a, a + n + 2, a + n + 1);
    }
}

// A 100 x 100 mm plane in tolerance with a planted gouge (-50 um) of radius 15 mm at its centre,
// seen from the top: the centre pixel of the view is red, a pixel 30 mm away green.
TEST_F(RenderTest, TopViewShowsAPlantedGougeRedOnGreen) {
  std::string why;
  ASSERT_TRUE(ensureDisplay(&why)) << why;
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3i> faces;
  squareGrid(100, -50.0, 1.0, 0.0, &points, &faces);
  DeviationMap map;
  map.points = &points;
  map.faces = &faces;
  for (const auto& p : points)
    map.colours.push_back(deviationColour(p.head<2>().norm() < 15.0 ? -0.05 : 0.002, -0.01, 0.01));
  map.title = "test";
  const std::string png = path("map.png");
  renderDeviationMap(
      png, map, {"top", Eigen::Vector3d(0, 0, -1), Eigen::Vector3d::UnitY(), false, {}}, 1200, 900);

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

// Several views in one window (renderDeviationMaps) draw what each view drew in its own window
// (renderDeviationMap): a tilted plane with a gouge, an isometric view first, then the top and a
// side view, with a callout. Same size; the pixels that differ (a text's anti-aliasing) are
// fewer than 0.2 % of the picture, and the picture is not the previous view's.
TEST_F(RenderTest, SeveralViewsInOneWindowDrawWhatEachDrawsAlone) {
  std::string why;
  ASSERT_TRUE(ensureDisplay(&why)) << why;
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3i> faces;
  squareGrid(40, -20.0, 1.0, 0.3, &points, &faces);
  DeviationMap map;
  map.points = &points;
  map.faces = &faces;
  for (const auto& p : points)
    map.colours.push_back(deviationColour(p.head<2>().norm() < 6.0 ? -0.05 : 0.002, -0.01, 0.01));
  map.title = "views";
  map.callouts.push_back({Eigen::Vector3d(0, 0, 0), "R1 gouge -50.0 um"});
  const std::vector<MapView> views = {
      {"isometric", Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d::UnitZ(), false, {}},
      {"top", Eigen::Vector3d(0, 0, -1), Eigen::Vector3d::UnitY(), false, {}},
      {"side", Eigen::Vector3d(0, 1, 0), Eigen::Vector3d::UnitZ(), false, {}}};
  std::vector<std::pair<std::string, MapView>> together;
  for (const auto& v : views) together.push_back({path("together_" + v.name + ".png"), v});
  renderDeviationMaps(together, map, 600, 450);
  auto pixels = [](const std::string& png) {
    vtkNew<vtkPNGReader> reader;
    reader->SetFileName(png.c_str());
    reader->Update();
    vtkImageData* img = reader->GetOutput();
    int dims[3];
    img->GetDimensions(dims);
    std::vector<unsigned char> out;
    for (int y = 0; y < dims[1]; ++y)
      for (int x = 0; x < dims[0]; ++x)
        for (int k = 0; k < 3; ++k)
          out.push_back(static_cast<unsigned char>(img->GetScalarComponentAsDouble(x, y, 0, k)));
    return out;
  };
  auto differing = [](const std::vector<unsigned char>& a, const std::vector<unsigned char>& b) {
    size_t d = 0;
    for (size_t k = 0; k + 2 < a.size(); k += 3)
      d += a[k] != b[k] || a[k + 1] != b[k + 1] || a[k + 2] != b[k + 2];
    return d;
  };
  std::vector<unsigned char> previous;
  for (const auto& v : views) {
    const std::string alone = path("alone_" + v.name + ".png");
    renderDeviationMap(alone, map, v, 600, 450);
    const auto a = pixels(alone), b = pixels(path("together_" + v.name + ".png"));
    ASSERT_EQ(a.size(), size_t{600 * 450 * 3}) << v.name;
    ASSERT_EQ(b.size(), a.size()) << v.name;
    EXPECT_LT(differing(a, b), 600 * 450 / 500) << v.name;
    if (!previous.empty()) EXPECT_GT(differing(b, previous), 600 * 450 / 20) << v.name;
    previous = b;
  }
}

}  // namespace
}  // namespace tolver
