// tracePart's selection on synthetic residuals built from closed-form fields (not from its own
// columns' code): a uniform offset, a rigid shift of a part, and a field of "machine" rows with a
// prior. The independent machining simulation is tests/measure_test.cpp.
#include "core/diagnosis/part_trace.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace tolver {
namespace {

// Points on a hemisphere of radius 30 (normals outward), a ball-end tool along z.
std::vector<TracePoint> dome(int n, unsigned seed, double noise) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> g(0, noise);
  std::vector<TracePoint> pts(n);
  for (int i = 0; i < n; ++i) {
    const double phi = 2 * M_PI * u(rng), th = std::acos(1 - 0.9 * u(rng));
    TracePoint& p = pts[i];
    p.n_w =
        Eigen::Vector3d(std::sin(th) * std::cos(phi), std::sin(th) * std::sin(phi), std::cos(th));
    p.p_w = 30.0 * p.n_w;
    p.axis_w = Eigen::Vector3d::UnitZ();
    p.radius_sensitivity = -(1.0 - p.n_w.z());
    p.residual = g(rng);
    p.held_out = i % 5 == 4;
  }
  return pts;
}

TEST(PartTrace, NoiseAloneAddsNothing) {
  int added = 0;
  for (unsigned seed = 1; seed <= 20; ++seed)
    added += !tracePart(dome(500, seed, 1e-3)).added.empty();
  EXPECT_LE(added, 1);
}

// A part shifted by (5, -3, 2) um: -n.t at each point. Named as the set-up, with its values.
TEST(PartTrace, ARigidShiftIsTheSetUpWithItsValues) {
  std::vector<TracePoint> pts = dome(500, 3, 0.5e-3);
  const Eigen::Vector3d t(0.005, -0.003, 0.002);
  for (TracePoint& p : pts) p.residual += -p.n_w.dot(t);
  const PartTrace r = tracePart(pts);
  ASSERT_EQ(r.added.size(), 1u) << r.verdict_text;
  EXPECT_EQ(r.groups[0].name, "set-up");
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(r.groups[0].values[k], t[k], 3 * r.groups[0].sd[k]);
  EXPECT_LT(r.heldout_rms_after, 0.65e-3);
}

// A uniform 4 um of stock: "stock" (or a group that fits as well, named confounded with it).
TEST(PartTrace, AUniformStockIsNamedOrConfounded) {
  std::vector<TracePoint> pts = dome(500, 4, 0.5e-3);
  for (TracePoint& p : pts) p.residual += 0.004;
  const PartTrace r = tracePart(pts);
  ASSERT_FALSE(r.added.empty()) << r.verdict_text;
  const TraceGroup& g = r.groups[0];
  const bool named = g.name == "stock" || std::find(g.confounded.begin(), g.confounded.end(),
                                                    "stock") != g.confounded.end();
  EXPECT_TRUE(named) << g.name;
  EXPECT_LT(r.heldout_rms_after, 0.65e-3);
}

// Machine parameters with a prior: the residual made by a draw from the prior through fixed rows
// is taken up by the machine group, and its values follow the draw where the rows see them.
TEST(PartTrace, TheMachineGroupTakesUpADrawFromItsPrior) {
  std::vector<TracePoint> pts = dome(800, 5, 0.3e-3);
  const int np = 4;
  TraceOptions o;
  o.machine_rows.resize(pts.size(), np);
  for (size_t i = 0; i < pts.size(); ++i) {
    const Eigen::Vector3d& x = pts[i].p_w;
    // Rows like a straightness and an angular error's lever arms, smooth in position.
    o.machine_rows.row(i) << std::pow(x.x() / 30, 2), x.y() * x.z() / 900, std::sin(x.x() / 10),
        std::cos(x.y() / 7);
  }
  o.machine_covariance = Eigen::MatrixXd::Identity(np, np) * 1e-5;  // 3.2 um per parameter
  const Eigen::Vector4d theta(0.004, -0.003, 0.002, 0.003);
  for (size_t i = 0; i < pts.size(); ++i) pts[i].residual += o.machine_rows.row(i).dot(theta);
  o.machine_names = {"a", "b", "c", "d"};
  const PartTrace r = tracePart(pts, o);
  ASSERT_FALSE(r.added.empty()) << r.verdict_text;
  EXPECT_EQ(r.groups[0].name, "machine");
  for (int k = 0; k < np; ++k) EXPECT_NEAR(r.groups[0].values[k], theta[k], 0.5e-3) << k;
  EXPECT_LT(r.heldout_rms_after, 0.4e-3);
}

}  // namespace
}  // namespace tolver
