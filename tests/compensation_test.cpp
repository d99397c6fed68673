// Compensation against independent truths: closed-form corrections (a constant angular
// positioning error of a rotary axis, a scale error of a linear axis), the round trip on every
// kinematics test machine (compensate, take the corrected CL as a perfect machine's
// post-processor would, then predict on the erroneous machine: the program's pose to 1e-6 mm),
// a fixed point (compensating again from the compensating joints changes nothing), travel and
// singular poses reported, never clipped.
#include "core/path/compensation.h"

#include <gtest/gtest.h>

#include <random>

#include "core/kinematics/forward_kinematics.h"
#include "io/machine/machine_file.h"
#include "test_support.h"

namespace tolver {
namespace {

// Joints along a line through the travel (rotaries within +-15 deg of tilt, through the pole)
// and the nominal poses there: a program whose nominal IK is known.
std::vector<ClPoint> pathOn(const MachineModel& model, std::vector<JointVector>* q_out, int n = 200,
                            double from = 0.3, double to = 0.95) {
  const ForwardKinematics nominal(model, Eigen::VectorXd::Zero(model.parameterCount()));
  std::vector<ClPoint> path;
  for (int k = 0; k <= n; ++k) {
    const double t = static_cast<double>(k) / n;
    JointVector q(model.axes.size());
    for (size_t a = 0; a < model.axes.size(); ++a) {
      const Axis& ax = model.axes[a];
      if (ax.isRotary()) {
        const double lim = std::min({15.0 * M_PI / 180.0, ax.travel_max, -ax.travel_min});
        q[a] = lim * (2.0 * t - 1.0) + 0.01;
      } else {
        q[a] = ax.travel_min + (from + (to - from) * t) * (ax.travel_max - ax.travel_min);
      }
    }
    Eigen::Vector3d p, u;
    nominal.tipAndAxis(q, &p, &u);
    ClPoint c;
    c.p_w = p;
    c.u_w = u;
    c.line = k + 1;
    path.push_back(c);
    if (q_out) q_out->push_back(q);
  }
  return path;
}

TEST(Compensation, AConstantRotaryPositioningErrorIsTakenOffThatAxisAlone) {
  Machine m = readMachineFile(test::sourcePath("resources/machines/matsuura_mc760vx.xml"));
  m.model.setup.gauge_length = 100;
  const double delta = 50e-6;  // 50 urad
  m.params[m.model.findParameter("ECC.c0")] = delta;
  std::vector<JointVector> q0;
  const std::vector<ClPoint> path = pathOn(m.model, &q0);
  const CompensationResult r = compensateToolPath(m.model, m.params, path, q0);
  const int c = m.model.axisIndex("C");
  for (size_t i = 0; i < path.size(); ++i) {
    const CompensatedPoint& p = r.points[i];
    if (p.status == CompensationStatus::IllConditioned) continue;  // at the pole C is free
    ASSERT_EQ(p.status, CompensationStatus::Compensated) << i;
    EXPECT_GT(p.before_w.norm(), 1e-6);
    EXPECT_LT(p.after_w.norm(), 1e-7);
    EXPECT_LT(p.after_axis, 1e-9);
    for (int a = 0; a < 5; ++a)
      // To what the stopping rule (1e-7 mm, 1e-9 rad) pins the joints: C is weakly seen near the
      // pole.
      EXPECT_NEAR(p.q[a] - p.q0[a], a == c ? -delta : 0.0, a == c ? 1e-8 : 5e-7)
          << "point " << i << " axis " << a;
  }
}

TEST(Compensation, AScaleErrorOfALinearAxisHasItsClosedForm) {
  Machine m = readMachineFile(test::sourcePath("tests/fixtures/machines/three_axis.xml"));
  m.model.setup.gauge_length = 50;
  const int x = m.model.axisIndex("X");
  const Axis& ax = m.model.axes[x];
  const double c1 = 0.02;  // e_x(X) = c1 * s_N, s_N = (X - mid) / half: 20 um at the ends
  m.params[m.model.findParameter("EXX.c1")] = c1;
  const double mid = 0.5 * (ax.travel_min + ax.travel_max),
               half = 0.5 * (ax.travel_max - ax.travel_min);
  std::vector<JointVector> q0;
  const std::vector<ClPoint> path = pathOn(m.model, &q0, 50, 0.05, 0.95);
  const CompensationResult r = compensateToolPath(m.model, m.params, path, q0, false);
  for (size_t i = 0; i < path.size(); ++i) {
    const CompensatedPoint& p = r.points[i];
    ASSERT_EQ(p.status, CompensationStatus::Compensated);
    EXPECT_LT(p.after_w.norm(), 1e-7);
    // The table moves X + e(X) along x: the compensating X' satisfies X' + e(X') = X, i.e.
    // X' = (X + c1 mid / half) / (1 + c1 / half); the other joints do not move.
    const double expected = (q0[i][x] + c1 * mid / half) / (1.0 + c1 / half);
    EXPECT_NEAR(p.q[x], expected, 1e-9) << i;
    for (int a = 0; a < 3; ++a)
      if (a != x) EXPECT_NEAR(p.q[a], p.q0[a], 1e-12);
  }
}

class EveryKinematicsMachine : public ::testing::TestWithParam<const char*> {};

TEST_P(EveryKinematicsMachine, CompensatedPosesPutTheToolOnTheProgramAndAreAFixedPoint) {
  Machine m = readMachineFile(test::sourcePath(GetParam()));
  m.model.setup.gauge_length = 80;
  std::mt19937 rng(17);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < m.model.parameterCount(); ++i)
    m.params[i] = n(rng) * (m.model.parameters[i].angular ? 20e-6 : 0.005);
  const bool five = m.model.axes.size() >= 5;
  std::vector<JointVector> q0;
  const std::vector<ClPoint> path = pathOn(m.model, &q0);
  const CompensationResult r = compensateToolPath(m.model, m.params, path, q0, five);
  const ForwardKinematics real(m.model, m.params);
  int compensated = 0;
  std::vector<JointVector> again_from;
  for (size_t i = 0; i < path.size(); ++i) {
    const CompensatedPoint& c = r.points[i];
    again_from.push_back(c.q);
    if (c.status == CompensationStatus::OutOfTravel ||
        c.status == CompensationStatus::NotConverged) {
      EXPECT_EQ(c.q, c.q0);  // left as programmed, never clipped
      continue;
    }
    if (c.status == CompensationStatus::Compensated) ++compensated;
    // The corrected CL is the nominal pose at the compensating joints; the machine with its
    // errors at those joints puts the tool on the program (independent of the Newton residual).
    Eigen::Vector3d p, u;
    real.tipAndAxis(c.q, &p, &u);
    EXPECT_LT((p - path[i].p_w).norm(), 1e-6) << GetParam() << " point " << i;
    if (five && c.status == CompensationStatus::Compensated)
      EXPECT_LT(std::atan2(u.cross(path[i].u_w).norm(), u.dot(path[i].u_w)), 1e-8)
          << GetParam() << " point " << i;
  }
  EXPECT_GT(compensated, static_cast<int>(path.size()) * 9 / 10) << GetParam();
  // A fixed point: compensating again from the compensating joints changes nothing.
  const CompensationResult again = compensateToolPath(m.model, m.params, path, again_from, five);
  for (size_t i = 0; i < path.size(); ++i) {
    if (r.points[i].status != CompensationStatus::Compensated) continue;
    for (Eigen::Index a = 0; a < again.points[i].q.size(); ++a)
      EXPECT_NEAR(again.points[i].q[a], r.points[i].q[a], 1e-6) << GetParam() << " point " << i;
    EXPECT_EQ(again.points[i].iterations, 0);
  }
}

INSTANTIATE_TEST_SUITE_P(Machines, EveryKinematicsMachine,
                         ::testing::ValuesIn(test::kinematicsTestMachines()));

TEST(Compensation, APointWhoseCorrectionLeavesTravelIsReportedAndLeftAlone) {
  Machine m = readMachineFile(test::sourcePath("tests/fixtures/machines/three_axis.xml"));
  m.model.setup.gauge_length = 50;
  m.params[m.model.findParameter("EXX.c0")] = 0.05;  // 50 um along x everywhere
  std::vector<JointVector> q0;
  std::vector<ClPoint> path = pathOn(m.model, &q0, 10, 0.0, 1.0);  // to both ends of the travel
  const CompensationResult r = compensateToolPath(m.model, m.params, path, q0, false);
  EXPECT_EQ(r.out_of_travel, 1);
  int out = 0;
  for (const CompensatedPoint& c : r.points)
    if (c.status == CompensationStatus::OutOfTravel) {
      ++out;
      EXPECT_EQ(c.axis_out, m.model.axisIndex("X"));
      EXPECT_EQ(c.q, c.q0);
      EXPECT_NEAR(c.after_w.norm(), c.before_w.norm(), 1e-12);
    }
  EXPECT_EQ(out, 1);
}

// Linear-axis tables: on a three-axis machine with a scale error of X and a straightness of X in
// y (no angular errors: nothing depends on more than one axis), the X table holds the closed-form
// corrections relative to the reference, and the tables leave nothing over the travel.
TEST(CompensationTables, PitchAndStraightnessOfALinearAxis) {
  Machine m = readMachineFile(test::sourcePath("tests/fixtures/machines/three_axis.xml"));
  m.model.setup.gauge_length = 50;
  const int x = m.model.axisIndex("X"), y = m.model.axisIndex("Y");
  const Axis& ax = m.model.axes[x];
  const double c1 = 0.02, s2 = 0.008;  // e_x(X) = c1 T1, e_y(X) = s2 T2
  m.params[m.model.findParameter("EXX.c1")] = c1;
  m.params[m.model.findParameter("EYX.c2")] = s2;
  const JointVector q_ref = JointVector::Zero(3);
  const std::vector<AxisTable> tables = linearAxisTables(m.model, m.params, q_ref, 20.0);
  ASSERT_EQ(tables.size(), 3u);
  const AxisTable& tx = tables[x];
  const double mid = 0.5 * (ax.travel_min + ax.travel_max),
               half = 0.5 * (ax.travel_max - ax.travel_min);
  auto xOf = [&](double X) { return (X + c1 * mid / half) / (1.0 + c1 / half); };  // X' + e(X') = X
  for (size_t k = 0; k < tx.position.size(); ++k) {
    const double X = tx.position[k];
    EXPECT_NEAR(tx.correction[k][x], (xOf(X) - X) - (xOf(0) - 0), 1e-7) << X;
    // The straightness along y: e_y(X') = s2 T2(s_N(X')), taken off relative to X = 0.
    auto ey = [&](double Xc) {
      const double sn = (Xc - mid) / half;
      return s2 * (2 * sn * sn - 1);
    };
    EXPECT_NEAR(std::abs(tx.correction[k][y]), std::abs(ey(xOf(X)) - ey(xOf(0))), 1e-7)
        << X;  // the stopping rule
  }
  // Tables of the other axes are zero (their errors are zero).
  for (const Eigen::Vector3d& d : tables[y].correction) EXPECT_LT(d.norm(), 1e-12);
  const TableEffect e = tableEffect(m.model, m.params, tables, q_ref, true);
  EXPECT_GT(e.before_rms, 1e-3);
  EXPECT_LT(e.after_rms, 1e-4);  // the interpolation between 20 mm grid points
}

}  // namespace
}  // namespace tolver
