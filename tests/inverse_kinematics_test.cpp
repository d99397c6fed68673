#include "core/kinematics/inverse_kinematics.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <string>

#include "io/machine/machine_file.h"
#include "test_support.h"

namespace tolver {
namespace {

JointVector randomJoints(const MachineModel& m, std::mt19937& rng) {
  JointVector q(m.axes.size());
  for (size_t a = 0; a < m.axes.size(); ++a) {
    std::uniform_real_distribution<double> u(m.axes[a].travel_min, m.axes[a].travel_max);
    q[a] = u(rng);
  }
  return q;
}

// The path and brute-force tests enumerate a few turns of each rotary axis: rotary travel of many
// turns (LinuxCNC's +-36000 deg, endless tables) is limited to +-360 deg for them. Multi-turn
// values are tested through the G-code reader (tests/gcode_reader_test.cpp).
Machine limitedToOneTurn(Machine m) {
  for (Axis& a : m.model.axes)
    if (a.isRotary()) {
      a.travel_min = std::max(a.travel_min, -2.0 * M_PI);
      a.travel_max = std::min(a.travel_max, 2.0 * M_PI);
      a.endless = false;
    }
  return m;
}

double angleBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

class EveryMachine : public ::testing::TestWithParam<const char*> {};

// FK(IK(p, u)) = (p, u) over thousands of random reachable points.
TEST_P(EveryMachine, ForwardAfterInverseIsTheIdentity) {
  Machine m = readMachineFile(test::sourcePath(GetParam()));
  m.model.setup.part_zero_table = Eigen::Vector3d(10, -20, 30);
  m.model.setup.gauge_length = 100;
  const ForwardKinematics fk(m.model, Eigen::VectorXd::Zero(m.model.parameterCount()));
  const InverseKinematics ik(m.model);
  std::mt19937 rng(42);
  int solved = 0;
  for (int n = 0; n < 5000; ++n) {
    const Eigen::Isometry3d T = fk.w_T_t(randomJoints(m.model, rng));
    const Eigen::Vector3d p = T.translation(), u = T.linear().col(2);
    const IkSolution s = ik.solve(p, u, nullptr);
    ASSERT_EQ(s.status, IkStatus::Ok) << GetParam() << " point " << n;
    const Eigen::Isometry3d back = fk.w_T_t(s.q);
    EXPECT_LT((back.translation() - p).norm(), 1e-9);
    // Inside the singular band the free angle is kept and the axis reached to within the band.
    EXPECT_LT(angleBetween(back.linear().col(2), u),
              s.singular ? 2.0 * m.model.control.singular_band : 1e-12);
    ++solved;
  }
  EXPECT_EQ(solved, 5000);
}

// Along a smooth path from known joints, the solution that keeps the rotary motion continuous is
// the one the path was made from. (The first point needs the start: without a previous point
// the solution nearest to zero is taken, which on a nutating head is often the other branch.)
TEST_P(EveryMachine, ContinuityRecoversTheGeneratingJointsAlongAPath) {
  Machine m = limitedToOneTurn(readMachineFile(test::sourcePath(GetParam())));
  const ForwardKinematics fk(m.model, Eigen::VectorXd::Zero(m.model.parameterCount()));
  const InverseKinematics ik(m.model);
  std::mt19937 rng(5);
  JointVector q = randomJoints(m.model, rng);
  for (size_t a = 0; a < m.model.axes.size(); ++a)  // start well inside travel
    q[a] = 0.5 * (q[a] + 0.5 * (m.model.axes[a].travel_min + m.model.axes[a].travel_max));
  JointVector prev = q;
  std::normal_distribution<double> step(0.0, 1.0);
  for (int n = 0; n < 2000; ++n) {
    JointVector next = q;
    for (size_t a = 0; a < m.model.axes.size(); ++a) {
      const Axis& ax = m.model.axes[a];
      const double span = ax.travel_max - ax.travel_min;
      next[a] = std::clamp(q[a] + 0.002 * span * step(rng), ax.travel_min + 0.01 * span,
                           ax.travel_max - 0.01 * span);
    }
    q = next;
    const Eigen::Isometry3d T = fk.w_T_t(q);
    const IkSolution s = ik.solve(T.translation(), T.linear().col(2), &prev);
    ASSERT_EQ(s.status, IkStatus::Ok);
    if (!s.singular) EXPECT_LT((s.q - q).cwiseAbs().maxCoeff(), 1e-7) << n;
    prev = s.q;
  }
}

// The returned solution is the cheapest feasible candidate, found by brute force: every
// orientation candidate, every 2 pi representative inside travel, its prismatic solution
// inside travel, cost = sum of |rotary value - previous|. The previous joints are random (large
// jumps), so both candidates compete and solve()'s chord shortcut is tested against the full
// search; with and without the previous point's cos and sin.
TEST_P(EveryMachine, ChoiceIsTheCheapestFeasibleCandidate) {
  Machine m = limitedToOneTurn(readMachineFile(test::sourcePath(GetParam())));
  const ForwardKinematics fk(m.model, Eigen::VectorXd::Zero(m.model.parameterCount()));
  const InverseKinematics ik(m.model);
  const auto& rot = ik.rotaryAxes();
  std::mt19937 rng(11);
  int compared = 0, second_cheaper = 0;
  for (int n = 0; n < 3000; ++n) {
    const Eigen::Isometry3d T = fk.w_T_t(randomJoints(m.model, rng));
    const Eigen::Vector3d p = T.translation(), u = T.linear().col(2);
    const JointVector prev = randomJoints(m.model, rng);
    std::array<double, kMaxAxes> pc{}, ps{};
    for (int a : rot) {
      pc[a] = std::cos(prev[a]);
      ps[a] = std::sin(prev[a]);
    }
    double best = std::numeric_limits<double>::infinity();
    bool singular = false;
    InverseKinematics::RotaryCandidate cand[2];
    const int ncand = ik.rotaryCandidates(u, cand, &singular);
    if (singular) continue;
    double costs[2] = {best, best};
    for (int ci = 0; ci < ncand; ++ci) {
      JointVector q = prev;
      double cost = 0.0;
      for (size_t r = 0; r < rot.size(); ++r) {
        const Axis& ax = m.model.axes[rot[r]];
        double near = std::numeric_limits<double>::infinity();
        for (int k = -3; k <= 3; ++k) {
          const double v = cand[ci].angleOf(static_cast<int>(r)) + 2 * M_PI * k;
          if (v >= ax.travel_min - 1e-9 && v <= ax.travel_max + 1e-9 &&
              std::abs(v - prev[rot[r]]) < std::abs(near - prev[rot[r]]))
            near = v;
        }
        q[rot[r]] = near;
        cost += std::abs(near - prev[rot[r]]);
      }
      int violated = -1;
      if (std::isfinite(cost) && ik.placeToolPoint(Eigen::Vector3d::Zero(), p, q, &violated))
        costs[ci] = cost;
    }
    best = std::min(costs[0], costs[1]);
    if (costs[1] < costs[0]) ++second_cheaper;
    for (bool with_trig : {false, true}) {
      const IkSolution s =
          with_trig ? ik.solve(p, u, &prev, pc.data(), ps.data()) : ik.solve(p, u, &prev);
      if (!std::isfinite(best)) {
        EXPECT_NE(s.status, IkStatus::Ok) << GetParam() << " point " << n;
        continue;
      }
      ASSERT_EQ(s.status, IkStatus::Ok) << GetParam() << " point " << n;
      double cost = 0.0;
      for (int a : rot) cost += std::abs(s.q[a] - prev[a]);
      EXPECT_NEAR(cost, best, 1e-9) << GetParam() << " point " << n;
      ++compared;
    }
  }
  EXPECT_GT(compared, 2000);
  if (ik.rotaryAxes().size() == 2) EXPECT_GT(second_cheaper, 100);  // both orders occur
}

// The batch path (solveBlock: candidates, prismatic solutions and angle steps four points at
// a time, the continuity choice point by point) gives solve()'s bits point by point, with the
// reference predictToolPath uses (the previous solution, none after a failure), on a path that
// mixes small steps, jumps, near-singular and singular tool axes, unreachable axes and points
// beyond the stroke, in blocks of varying length.
TEST_P(EveryMachine, BlockEqualsPointByPointBitForBit) {
  Machine m = readMachineFile(test::sourcePath(GetParam()));
  m.model.setup.part_zero_table = Eigen::Vector3d(10, -20, 30);
  m.model.setup.gauge_length = 100;
  const InverseKinematics ik(m.model);
  if (!ik.batchable()) {  // the nutating head (axis off x/y/z), four and three axes
    EXPECT_NE(std::string(GetParam()).find("fixtures"), std::string::npos) << GetParam();
    return;
  }
  const ForwardKinematics fk(m.model, Eigen::VectorXd::Zero(m.model.parameterCount()));
  std::mt19937 rng(77);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Eigen::Vector3d> ps, us;
  JointVector q = randomJoints(m.model, rng);
  for (int n = 0; n < 3000; ++n) {
    const double kind = unit(rng);
    if (kind < 0.9) {  // a small step of every joint
      for (size_t a = 0; a < m.model.axes.size(); ++a) {
        const Axis& ax = m.model.axes[a];
        const double span = ax.travel_max - ax.travel_min;
        q[a] = std::clamp(
            q[a] + 0.003 * (ax.isRotary() ? std::min(span, 2 * M_PI) : span) * (unit(rng) - 0.5),
            ax.travel_min, ax.travel_max);
      }
    } else if (kind < 0.95) {
      q = randomJoints(m.model, rng);  // a jump
    }
    const Eigen::Isometry3d T = fk.w_T_t(q);
    Eigen::Vector3d p = T.translation(), u = T.linear().col(2);
    const double odd = unit(rng);
    if (odd < 0.01)
      p.x() += 1e4;  // beyond the stroke
    else if (odd < 0.02)
      u = -u;  // often unreachable
    else if (odd < 0.04)
      u = Eigen::Vector3d(std::pow(10.0, -9 * unit(rng)), 0, 1).normalized();
    else if (odd < 0.05)
      u = Eigen::Vector3d::UnitZ();  // along a rotary axis on most machines
    ps.push_back(p);
    us.push_back(u);
  }
  // Point by point.
  std::vector<IkSolution> ref;
  const JointVector* previous = nullptr;
  for (size_t i = 0; i < ps.size(); ++i) {
    ref.push_back(ik.solve(ps[i], us[i], previous, previous ? ref[i - 1].cos_q.data() : nullptr,
                           previous ? ref[i - 1].sin_q.data() : nullptr));
    previous = ref.back().status == IkStatus::Ok ? &ref.back().q : nullptr;
  }
  // In blocks.
  auto block = std::make_unique<InverseKinematics::Block>();
  InverseKinematics::Cursor cursor;
  const int axes = static_cast<int>(m.model.axes.size());
  int solved = 0, from_lanes = 0;
  for (size_t start = 0, len = 1; start < ps.size(); start += len, len = (len * 7 + 5) % 64 + 1) {
    const int n = static_cast<int>(std::min(len, ps.size() - start));
    block->n = n;
    block->has_before = start > 0;
    if (start > 0)
      for (int k = 0; k < 3; ++k) block->u_before[k] = us[start - 1][k];
    for (int i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) {
        block->p[k][i] = ps[start + i][k];
        block->u[k][i] = us[start + i][k];
      }
    ik.solveBlock(*block, cursor);
    for (int i = 0; i < n; ++i) {
      const IkSolution& r = ref[start + i];
      const std::string where = std::string(GetParam()) + " point " + std::to_string(start + i);
      ASSERT_EQ(block->status[i], r.status) << where;
      ASSERT_EQ(block->violated_axis[i], r.violated_axis) << where;
      if (r.status != IkStatus::Ok) continue;
      ASSERT_EQ(block->singular[i], r.singular) << where;
      for (int a = 0; a < axes; ++a) {
        ASSERT_EQ(block->q[a][i], r.q[a]) << where << " axis " << a;
        if (!m.model.axes[a].isRotary()) continue;
        ASSERT_EQ(block->c[a][i], r.cos_q[a]) << where << " axis " << a;
        ASSERT_EQ(block->s[a][i], r.sin_q[a]) << where << " axis " << a;
      }
      ++solved;
    }
    from_lanes += block->from_lanes;
  }
  EXPECT_GT(solved, 2000);
  EXPECT_GT(from_lanes, 0.8 * solved);  // the lane stage's numbers were used, not only solve()
}

INSTANTIATE_TEST_SUITE_P(Shipped, EveryMachine,
                         ::testing::ValuesIn(test::kinematicsTestMachines()));

TEST(InverseKinematics, ToolAxisBeyondTheTiltRangeIsOutOfTravel) {
  const Machine m = readMachineFile(test::sourcePath(test::shippedMachines()[0]));
  const InverseKinematics ik(m.model);
  // Matsuura: A in [-120, 30] deg; a tool axis tilted 150 deg from vertical needs |a| = 150.
  const Eigen::Vector3d u(0, std::sin(150 * M_PI / 180), std::cos(150 * M_PI / 180));
  const IkSolution s = ik.solve(Eigen::Vector3d::Zero(), u, nullptr);
  EXPECT_EQ(s.status, IkStatus::OutOfTravel);
  EXPECT_EQ(m.model.axes[s.violated_axis].name, "A");
}

// When nothing fits, the axis named is the one that breaks first on the solution the choice
// prefers, not a rotary violation of the other solution (on the Matsuura a 50 deg tilt has a
// solution with A = -50 inside travel and one with A = +50 outside; the point is beyond X).
TEST(InverseKinematics, FailureNamesTheAxisOfThePreferredSolution) {
  const Machine m = readMachineFile(test::sourcePath(test::shippedMachines()[0]));
  const InverseKinematics ik(m.model);
  const double t = 50 * M_PI / 180;
  for (const Eigen::Vector3d& u : {Eigen::Vector3d(0, std::sin(t), std::cos(t)),
                                   Eigen::Vector3d(0, -std::sin(t), std::cos(t))}) {
    const IkSolution s = ik.solve(Eigen::Vector3d(900, 0, 0), u, nullptr);
    ASSERT_EQ(s.status, IkStatus::OutOfTravel);
    ASSERT_GE(s.violated_axis, 0);
    EXPECT_EQ(m.model.axes[s.violated_axis].name, "X") << u.transpose();
  }
}

// Inside the singular band a micro-radian tilt of the tool axis keeps the free angle (it used to
// swing C to wherever the tilt pointed, -90 deg for a tilt towards -x).
TEST(InverseKinematics, MicroRadianTiltNearThePoleKeepsTheFreeAngle) {
  const Machine m = readMachineFile(test::sourcePath("resources/machines/trunnion_ac_trt.xml"));
  const InverseKinematics ik(m.model);
  const IkSolution first = ik.solve(Eigen::Vector3d(10, 20, 5), Eigen::Vector3d::UnitZ(), nullptr);
  ASSERT_EQ(first.status, IkStatus::Ok);
  const int c = m.model.axisIndex("C");
  for (double dir : {0.0, M_PI / 2, M_PI, -M_PI / 2}) {
    const Eigen::Vector3d u(1e-6 * std::cos(dir), 1e-6 * std::sin(dir), 1.0);
    const IkSolution s = ik.solve(Eigen::Vector3d(10, 20, 5), u.normalized(), &first.q);
    ASSERT_EQ(s.status, IkStatus::Ok);
    EXPECT_TRUE(s.singular);
    EXPECT_NEAR(s.q[c], first.q[c], 1e-12) << dir;
  }
  // Beyond the band the angle follows the tool axis again.
  const double t = 2.0 * m.model.control.singular_band;
  const IkSolution s =
      ik.solve(Eigen::Vector3d(10, 20, 5), Eigen::Vector3d(0, std::sin(t), std::cos(t)), &first.q);
  EXPECT_FALSE(s.singular);
}

TEST(InverseKinematics, PointBeyondTheStrokeNamesTheAxis) {
  const Machine m = readMachineFile(test::sourcePath(test::shippedMachines()[0]));
  const InverseKinematics ik(m.model);
  const IkSolution s = ik.solve(Eigen::Vector3d(500, 0, 0), Eigen::Vector3d::UnitZ(), nullptr);
  EXPECT_EQ(s.status, IkStatus::OutOfTravel);
  EXPECT_EQ(m.model.axes[s.violated_axis].name, "X");
  EXPECT_NEAR(s.violated_value, -500.0, 1e-9);  // the table moves -x to bring the tool to +x
}

TEST(InverseKinematics, ToolAxisAlongTheRotaryAxisKeepsTheFreeAngle) {
  const Machine m = readMachineFile(test::sourcePath(test::shippedMachines()[0]));
  const InverseKinematics ik(m.model);
  JointVector prev(5);
  prev << 0, 0, 0, 0, 0.7;
  const IkSolution s = ik.solve(Eigen::Vector3d(10, 20, 5), Eigen::Vector3d::UnitZ(), &prev);
  ASSERT_EQ(s.status, IkStatus::Ok);
  EXPECT_TRUE(s.singular);
  EXPECT_NEAR(s.q[4], 0.7, 1e-12);  // C kept
  EXPECT_NEAR(s.q[3], 0.0, 1e-12);  // A vertical
}

TEST(InverseKinematics, XKH800CannotTiltTheToolBeyondItsHeadRange) {
  const Machine m = readMachineFile(test::sourcePath(test::shippedMachines()[1]));
  const InverseKinematics ik(m.model);
  // Only A (head, +-45 deg about x) gives the tool axis a y component; B turns about y.
  const Eigen::Vector3d u = Eigen::Vector3d(0, std::sin(1.0), std::cos(1.0));
  const IkSolution s = ik.solve(Eigen::Vector3d::Zero(), u, nullptr);
  EXPECT_EQ(s.status, IkStatus::OutOfTravel);
}

}  // namespace
}  // namespace tolver
