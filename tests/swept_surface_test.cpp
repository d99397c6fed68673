// The point-vector sweep against analytic cases.
#include "geometry/swept_surface.h"

#include <gtest/gtest.h>

#include <cmath>

namespace tolver {
namespace {

Cutter ballEnd(double r) {
  Cutter c;
  c.type = CutterType::BallEnd;
  c.diameter = 2 * r;
  c.corner_radius = r;
  c.length = 6 * r;
  return c;
}

// A ball end of radius r runs along y on passes around a cylinder of radius Rc (axis y), its
// axis radial, its tip on the surface, the passes dtheta apart. Between two passes the cusp lies
// on the bisector, where the two balls' spheres meet: at rho = D cos(dtheta/2) -
// sqrt(r^2 - D^2 sin^2(dtheta/2)) from the axis, D = Rc + r. The scallop height is rho - Rc.
TEST(SweptSurface, BallEndOnCylinderLeavesTheAnalyticScallop) {
  const double Rc = 30.0, r = 3.0, dtheta = 2.0 * M_PI / 180.0;
  const Cutter cutter = ballEnd(r);
  std::vector<ToolPlacement> placements;
  for (int k = -5; k <= 5; ++k) {
    const double th = k * dtheta;
    const Eigen::Vector3d radial(std::sin(th), 0, std::cos(th));
    for (int k5 = -125; k5 <= 125; ++k5) {  // y every 0.2 mm, exact where the samples are
      const double y = k5 / 5.0;
      ToolPlacement p;
      p.tip_w = Rc * radial + Eigen::Vector3d(0, y, 0);
      p.axis_w = radial;
      placements.push_back(p);
    }
  }
  SurfaceSamples s;
  s.group_names = {"cylinder"};
  for (int k = -4; k <= 3; ++k)
    for (double y : {-50 / 5.0, 0.0, 36 / 5.0}) {
      for (double th : {k * dtheta, (k + 0.5) * dtheta}) {
        const Eigen::Vector3d radial(std::sin(th), 0, std::cos(th));
        s.p_w.push_back(Rc * radial + Eigen::Vector3d(0, y, 0));
        s.n_w.push_back(radial);
        s.area.push_back(1.0);
        s.group.push_back(0);
      }
    }
  SweepOptions opt;
  opt.excess_range = opt.gouge_range = 0.5;
  SweepResult res;
  sweepSurface(s, cutter, placements, opt, &res);
  const double D = Rc + r, h = 0.5 * dtheta;
  const double scallop = D * std::cos(h) - std::sqrt(r * r - D * D * std::sin(h) * std::sin(h)) - Rc;
  EXPECT_NEAR(scallop, 0.0508, 1e-4);  // about 51 um
  for (size_t i = 0; i < s.size(); ++i) {
    ASSERT_TRUE(res.machined[i]) << i;
    const bool on_pass = (i % 2) == 0;
    EXPECT_NEAR(res.deviation[i], on_pass ? 0.0 : scallop, 1e-9) << i;
  }
}

// A flat end whose bottom passes at height e over a horizontal sample leaves exactly e, and one
// that dips below leaves a gouge of that depth; a sample out of reach stays unmachined.
TEST(SweptSurface, FlatEndBottomCutsAtItsHeight) {
  Cutter c;
  c.diameter = 10;
  c.length = 30;
  SurfaceSamples s;
  s.group_names = {"plane"};
  for (double x : {0.0, 4.9, 20.0}) {
    s.p_w.push_back(Eigen::Vector3d(x, 0, 0));
    s.n_w.push_back(Eigen::Vector3d::UnitZ());
    s.area.push_back(1);
    s.group.push_back(0);
  }
  for (double e : {0.003, -0.004}) {
    ToolPlacement p;
    p.tip_w = Eigen::Vector3d(0, 0, e);
    SweepResult res;
    sweepSurface(s, c, {p}, SweepOptions(), &res);
    EXPECT_NEAR(res.deviation[0], e, 1e-12);
    EXPECT_NEAR(res.deviation[1], e, 1e-12);
    EXPECT_FALSE(res.machined[2]);
  }
}

// The bull nose's corner: a vertical line at distance rho from the axis (in the corner ring,
// R - rc < rho < R) enters the torus at h = rc - sqrt(rc^2 - (rho - (R - rc))^2).
TEST(SweptSurface, BullNoseCornerEntryMatchesTheTorus) {
  Cutter c;
  c.type = CutterType::BullNose;
  c.diameter = 16;
  c.corner_radius = 2;
  c.length = 40;
  for (double rho : {6.2, 6.9, 7.5, 7.95}) {
    const double expected = 2.0 - std::sqrt(4.0 - (rho - 6.0) * (rho - 6.0));
    const double s = c.lineEntry(Eigen::Vector3d(rho, 0, -1), Eigen::Vector3d::UnitZ(),
                                 Eigen::Vector3d::UnitZ(), 0.0, 5.0);
    EXPECT_NEAR(s - 1.0, expected, 1e-9) << rho;
  }
  // Inside the flat bottom: enters at the tip plane.
  EXPECT_NEAR(c.lineEntry(Eigen::Vector3d(3, 0, -1), Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitZ(), 0, 5), 1.0, 1e-9);
  // Beyond the radius: never.
  EXPECT_TRUE(std::isinf(c.lineEntry(Eigen::Vector3d(8.5, 0, -1), Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitZ(), 0, 5)));
}

}  // namespace
}  // namespace tolver
