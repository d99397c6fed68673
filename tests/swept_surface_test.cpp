// The point-vector sweep against analytic cases.
#include "geometry/swept_surface.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

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
  const double scallop =
      D * std::cos(h) - std::sqrt(r * r - D * D * std::sin(h) * std::sin(h)) - Rc;
  EXPECT_NEAR(scallop, 0.0508, 1e-4);  // about 51 um
  for (size_t i = 0; i < s.size(); ++i) {
    ASSERT_TRUE(res.machined[i]) << i;
    const bool on_pass = (i % 2) == 0;
    EXPECT_NEAR(res.deviation[i], on_pass ? 0.0 : scallop, 1e-9) << i;
  }
}

// The sweep against the definition, placement by placement: for random scenes (passes of tilted
// tools over a wavy patch, tools lying on their side, samples facing every way, placements far
// away), every cutter shape, each sample's deviation, state and cutting placement equal those of
// testing every placement against the whole blade (ties to the earliest), bit for bit. The sweep
// only skips placements its bounds prove cannot reach what is left of the blade.
TEST(SweptSurface, EqualsTestingEveryPlacement) {
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  std::vector<Cutter> cutters;
  cutters.push_back(ballEnd(3.0));
  Cutter flat;
  flat.type = CutterType::FlatEnd;
  flat.diameter = 6.0;
  flat.length = 20.0;
  cutters.push_back(flat);
  Cutter bull = flat;
  bull.type = CutterType::BullNose;
  bull.corner_radius = 1.0;
  cutters.push_back(bull);
  Cutter tapered = ballEnd(2.0);
  tapered.taper_angle = 0.1;
  cutters.push_back(tapered);
  for (const Cutter& cutter : cutters) {
    std::vector<ToolPlacement> placements;
    for (int pass = 0; pass < 12; ++pass) {
      const double y = -6.0 + pass;
      const Eigen::Vector3d tilt = Eigen::Vector3d(0.8 * U(rng), 0.8 * U(rng), 1.0).normalized();
      for (int k = 0; k < 60; ++k) {
        ToolPlacement t;
        const double x = -6.0 + 0.2 * k;
        t.tip_w = Eigen::Vector3d(x, y, 0.3 * std::sin(x) - 0.05 + 0.1 * U(rng));
        t.axis_w = (tilt + 0.05 * Eigen::Vector3d(U(rng), U(rng), U(rng))).normalized();
        placements.push_back(t);
      }
    }
    for (int k = 0; k < 40; ++k) {  // on their side (flank), and far away
      ToolPlacement t;
      t.tip_w = Eigen::Vector3d(6 * U(rng), 6 * U(rng), (k % 2 ? 0.5 : 200.0) + U(rng));
      t.axis_w = Eigen::Vector3d(U(rng), U(rng), 0.1 * U(rng)).normalized();
      placements.push_back(t);
    }
    SurfaceSamples s;
    s.group_names = {"patch"};
    // Blades that graze the side of a lying tool just above its corner (where a ball end's ball
    // and shank meet): 0.01 mm into it, 0.05 to 0.6 mm above the corner's centre.
    const double rc = cutter.corner_radius;
    for (int i = 0; i < 400; ++i) {
      const ToolPlacement& t = placements[placements.size() - 1 - 2 * (i % 20)];
      const Eigen::Vector3d v = t.axis_w.unitOrthogonal();
      const Eigen::Vector3d side = Eigen::AngleAxisd(M_PI * U(rng), t.axis_w) * v;
      const double h = rc + 0.05 + 0.55 * (0.5 + 0.5 * U(rng));
      s.p_w.push_back(t.tip_w + h * t.axis_w + (cutter.radiusAt(h) + 0.3 - 0.01) * side);
      s.n_w.push_back(side);
      s.area.push_back(1.0);
      s.group.push_back(0);
    }
    for (int i = 0; i < 3000; ++i) {
      const double x = 9 * U(rng), y = 9 * U(rng);
      s.p_w.push_back(Eigen::Vector3d(x, y, 0.3 * std::sin(x) + 0.05 * U(rng)));
      const Eigen::Vector3d n =
          i % 5 == 0 ? Eigen::Vector3d(U(rng), U(rng), U(rng))
                     : Eigen::Vector3d(-0.3 * std::cos(x) + 0.2 * U(rng), 0.2 * U(rng), 1.0);
      s.n_w.push_back(n.normalized());
      s.area.push_back(1.0);
      s.group.push_back(0);
    }
    const bool bisected = cutter.type == CutterType::BullNose;
    SweepOptions opt;
    opt.excess_range = 0.4;
    opt.gouge_range = 0.3;
    SweepResult res;
    sweepSurface(s, cutter, placements, opt, &res);
    int machined = 0;
    for (size_t i = 0; i < s.size(); ++i) {
      double top = opt.excess_range;
      int who = -1;
      for (size_t k = 0; k < placements.size(); ++k) {
        const double e = cutter.lineEntry(s.p_w[i] - placements[k].tip_w, s.n_w[i],
                                          placements[k].axis_w, -opt.gouge_range, top);
        if (e < top) {  // strictly deeper: the earliest of equal ones stays
          top = e;
          who = static_cast<int>(k);
        }
      }
      ASSERT_EQ(res.machined[i], who >= 0 ? 1 : 0) << i;
      if (bisected) {
        // The bull nose's corner is found by bisection to 1e-9 mm, whose last digits depend on
        // the interval searched (the blade left when the placement comes up).
        ASSERT_NEAR(res.deviation[i], top, 2e-9) << i;
      } else {
        ASSERT_EQ(res.placement[i], who) << i;
        ASSERT_EQ(res.deviation[i], top) << i;
      }
      machined += who >= 0;
    }
    // The scenes exercise the search: most samples cut, some not.
    EXPECT_GT(machined, 1900);
    EXPECT_LT(machined, 3400);
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

// A program that changes tools: each placement is swept with the cutter of its CL point, and a
// sample keeps the deepest cut of any tool (a D10 at +0.1 mm over x 0..5, then a D2 at -0.05 mm
// over x 0..1; one cutter for both would leave or gouge elsewhere).
TEST(SweptSurface, EachToolCutsWithItsOwnCutter) {
  Cutter big, small;
  big.diameter = 10;
  big.length = 30;
  small.diameter = 2;
  small.length = 30;
  SurfaceSamples s;
  s.group_names = {"plane"};
  for (double x : {0.0, 3.0, 20.0}) {
    s.p_w.push_back(Eigen::Vector3d(x, 0, 0));
    s.n_w.push_back(Eigen::Vector3d::UnitZ());
    s.area.push_back(1);
    s.group.push_back(0);
  }
  ToolPlacement a, b;
  a.tip_w = Eigen::Vector3d(0, 0, 0.1);
  a.cl_index = 0;
  b.tip_w = Eigen::Vector3d(0, 0, -0.05);
  b.cl_index = 1;
  ToolSet tools;
  tools.cutters = {big, small};
  tools.tool_of_cl = {0, 1};
  SweepResult r;
  sweepSurface(s, tools, {a, b}, SweepOptions(), &r);
  EXPECT_NEAR(r.deviation[0], -0.05, 1e-12);
  EXPECT_EQ(r.placement[0], 1);
  EXPECT_NEAR(r.deviation[1], 0.1, 1e-12);  // the D2 does not reach x = 3
  EXPECT_EQ(r.placement[1], 0);
  EXPECT_FALSE(r.machined[2]);
  // The same placements with the D10 for both: x = 3 is gouged.
  tools.tool_of_cl = {0, 0};
  sweepSurface(s, tools, {a, b}, SweepOptions(), &r);
  EXPECT_NEAR(r.deviation[1], -0.05, 1e-12);
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
  EXPECT_NEAR(c.lineEntry(Eigen::Vector3d(3, 0, -1), Eigen::Vector3d::UnitZ(),
                          Eigen::Vector3d::UnitZ(), 0, 5),
              1.0, 1e-9);
  // Beyond the radius: never.
  EXPECT_TRUE(std::isinf(c.lineEntry(Eigen::Vector3d(8.5, 0, -1), Eigen::Vector3d::UnitZ(),
                                     Eigen::Vector3d::UnitZ(), 0, 5)));
}

}  // namespace
}  // namespace tolver
