// Known-truth recovery (thesis 3.7.4 and 4.9.1): simulate ball-bar readings from a machine with
// known errors, identify, compare.
#include "core/calibration.h"

#include <gtest/gtest.h>

#include <random>

#include "core/ballbar_plan.h"
#include "core/identifiability.h"
#include "core/sensitivity_jacobian.h"
#include "io/machine_file.h"
#include "test_support.h"

namespace tolver {
namespace {

struct Fixture {
  Machine m;
  std::vector<int> unknowns;
  BallbarPlan plan;
};

const Fixture& fixture() {
  static const Fixture f = [] {
    Fixture x;
    x.m = readMachineFile(test::sourcePath(test::shippedMachines()[0]));
    x.m.model.setup.gauge_length = 100;
    x.unknowns = defaultCalibrationUnknowns(x.m.model);
    BallbarPlanOptions o;
    o.poses = 180;
    x.plan = planBallbarTest(x.m.model, x.unknowns, o);
    return x;
  }();
  return f;
}

BallbarTest simulate(const MachineModel& m, const Eigen::VectorXd& truth, const BallbarTest& plan,
                     const std::vector<BallErrors>& balls, double noise_mm, unsigned seed) {
  BallbarTest t = plan;
  const ForwardKinematics fk(m, truth);
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, noise_mm);
  for (BallbarReading& r : t.readings)
    r.length = ballbarLength(fk, r.q, t.setups[r.setup], balls[r.setup]) + (noise_mm > 0 ? n(rng) : 0.0);
  return t;
}

double scaleOf(const MachineModel& m, int p) { return m.parameters[p].angular ? 20e-6 : 0.005; }

std::vector<BallErrors> randomBalls(int n, std::mt19937& rng) {
  std::normal_distribution<double> d(0.0, 0.01);
  std::vector<BallErrors> b(n);
  for (auto& e : b) {
    e.table_w = Eigen::Vector3d(d(rng), d(rng), d(rng));
    e.tool_t = Eigen::Vector3d(d(rng), d(rng), d(rng));
  }
  return b;
}

// Thesis 4.8.1: three set-ups with the tool balls off the spindle axis identify the 92
// coefficients and 18 ball positions: 110 unknowns, condition of order 10^3 or better.
TEST(Calibration, ThreeSetupPlanIdentifies110Unknowns) {
  const Fixture& f = fixture();
  EXPECT_EQ(f.unknowns.size(), 92u);
  EXPECT_EQ(f.plan.unknowns, 110);
  EXPECT_EQ(f.plan.rank, 110);
  EXPECT_EQ(f.plan.test.readings.size(), 180u);
  EXPECT_LT(f.plan.condition, 1e4);
  // Every planned pose is inside travel and has the nominal bar length.
  const ForwardKinematics fk(f.m.model, Eigen::VectorXd::Zero(f.m.model.parameterCount()));
  for (const BallbarReading& r : f.plan.test.readings) {
    EXPECT_NEAR(ballbarLength(fk, r.q, f.plan.test.setups[r.setup]), 150.0, 1e-9);
    for (size_t a = 0; a < f.m.model.axes.size(); ++a) {
      EXPECT_GE(r.q[a], f.m.model.axes[a].travel_min - 1e-9);
      EXPECT_LE(r.q[a], f.m.model.axes[a].travel_max + 1e-9);
    }
  }
}

// Simulation B: true errors on the minimal-complete set only, no noise: identified = true.
TEST(Calibration, SimulationBRecoversTheMinimalSetExactly) {
  const Fixture& f = fixture();
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::VectorXd truth = Eigen::VectorXd::Zero(f.m.model.parameterCount());
  for (int p : f.unknowns) truth[p] = n(rng) * scaleOf(f.m.model, p);
  const auto balls = randomBalls(3, rng);
  const BallbarTest data = simulate(f.m.model, truth, f.plan.test, balls, 0.0, 1);
  const CalibrationResult r = calibrate(f.m.model, Eigen::VectorXd::Zero(truth.size()), data, f.unknowns);
  ASSERT_EQ(r.status, CalibrationStatus::Converged) << r.message;
  EXPECT_TRUE(r.held.empty());
  for (int p : f.unknowns)
    EXPECT_NEAR(r.params[p], truth[p], 1e-9 * scaleOf(f.m.model, p)) << f.m.model.parameters[p].iso_code;
  for (int s = 0; s < 3; ++s) {
    EXPECT_LT((r.ball_errors[s].table_w - balls[s].table_w).norm(), 1e-9);
    EXPECT_LT((r.ball_errors[s].tool_t - balls[s].tool_t).norm(), 1e-9);
  }
  EXPECT_LT(r.rms_residual, 1e-10);
  EXPECT_LE(r.iterations, 6);
}

// Simulation A: true errors on every parameter of the maximal model; the identified machine
// reproduces the true tool pose at 60 other configurations, up to the part and tool set-up
// (which a ball-bar cannot see and which a set-up procedure measures).
TEST(Calibration, SimulationAReproducesThePoseElsewhere) {
  const Fixture& f = fixture();
  const MachineModel& m = f.m.model;
  std::mt19937 rng(6);
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::VectorXd truth(m.parameterCount());
  for (int p = 0; p < m.parameterCount(); ++p) truth[p] = n(rng) * scaleOf(m, p);
  const auto balls = randomBalls(3, rng);
  const BallbarTest data = simulate(m, truth, f.plan.test, balls, 0.0, 1);
  const CalibrationResult r = calibrate(m, Eigen::VectorXd::Zero(truth.size()), data, f.unknowns);
  ASSERT_EQ(r.status, CalibrationStatus::Converged) << r.message;
  EXPECT_LT(r.rms_residual, 1e-7);
  // Fit the 12 set-up parameters on the held-out poses, then compare poses.
  const auto poses = randomPoses(m, 60, 99);
  const ForwardKinematics truth_fk(m, truth);
  std::vector<int> setup_cols;
  for (const ParameterBlock& b : m.blocks)
    if (b.kind == BlockKind::WorkpieceSetup || b.kind == BlockKind::ToolSetup)
      for (int i = 0; i < 6; ++i) setup_cols.push_back(b.offset + i);
  Eigen::VectorXd ident = r.params;
  for (int it = 0; it < 4; ++it) {
    const ForwardKinematics fk(m, ident);
    Eigen::MatrixXd J = stackedJacobian(fk, poses, setup_cols);
    Eigen::VectorXd dt(6 * poses.size());
    for (size_t k = 0; k < poses.size(); ++k) {
      const Eigen::Isometry3d M = fk.w_T_t(poses[k]).inverse() * truth_fk.w_T_t(poses[k]);
      const Eigen::Matrix3d S = 0.5 * (M.linear() - M.linear().transpose());
      dt.segment<6>(6 * k) << M.translation(), S(2, 1), S(0, 2), S(1, 0);
    }
    const Eigen::VectorXd step = J.colPivHouseholderQr().solve(dt);
    for (size_t c = 0; c < setup_cols.size(); ++c) ident[setup_cols[c]] += step[c];
  }
  const ForwardKinematics fk(m, ident);
  double worst_pos = 0, worst_rot = 0;
  for (const JointVector& q : poses) {
    const Eigen::Isometry3d a = fk.w_T_t(q), b = truth_fk.w_T_t(q);
    worst_pos = std::max(worst_pos, (a.translation() - b.translation()).norm());
    worst_rot = std::max(worst_rot, Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle());
  }
  EXPECT_LT(worst_pos, 1e-6);
  EXPECT_LT(worst_rot, 1e-9);
}

// With 0.5 um noise the fit's reduced chi-square lies near 1.
TEST(Calibration, NoisyReadingsGiveAReducedChiSquareNearOne) {
  const Fixture& f = fixture();
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::VectorXd truth = Eigen::VectorXd::Zero(f.m.model.parameterCount());
  for (int p : f.unknowns) truth[p] = n(rng) * scaleOf(f.m.model, p);
  const auto balls = randomBalls(3, rng);
  BallbarPlanOptions o;
  o.poses = 600;
  const BallbarPlan big = planBallbarTest(f.m.model, f.unknowns, o);
  const BallbarTest data = simulate(f.m.model, truth, big.test, balls, 0.5e-3, 3);
  const CalibrationResult r = calibrate(f.m.model, Eigen::VectorXd::Zero(truth.size()), data, f.unknowns);
  ASSERT_EQ(r.status, CalibrationStatus::Converged);
  const double chi2 = std::pow(r.residual_sigma / 0.5e-3, 2);
  EXPECT_GT(chi2, 0.7);
  EXPECT_LT(chi2, 1.4);
  // Identified within a few standard uncertainties of the truth.
  int outside = 0;
  for (size_t k = 0; k < r.identified.size(); ++k)
    outside += std::abs(r.params[r.identified[k]] - truth[r.identified[k]]) > 4 * r.uncertainty[k];
  EXPECT_LE(outside, 1);
  for (int k = 0; k < r.observability.size(); ++k) {
    EXPECT_GT(r.observability[k], 0.0);
    EXPECT_LE(r.observability[k], 1.0 + 1e-12);
  }
}

// With every tool ball on the spindle axis some parameters are unobservable: named and held.
TEST(Calibration, ToolBallsOnTheSpindleAxisLeaveParametersUnobservable) {
  const Fixture& f = fixture();
  BallbarPlanOptions o;
  o.poses = 180;
  o.geometry = defaultBallbarSetups(3);
  for (auto& s : o.geometry) s.tool_ball_t = Eigen::Vector3d(0, 0, 0);
  const BallbarPlan plan = planBallbarTest(f.m.model, f.unknowns, o);
  EXPECT_LT(plan.rank, 110);
  const BallbarTest data = simulate(f.m.model, Eigen::VectorXd::Zero(f.m.model.parameterCount()),
                                    plan.test, std::vector<BallErrors>(3), 0.0, 1);
  const CalibrationResult r = calibrate(f.m.model, Eigen::VectorXd::Zero(f.m.model.parameterCount()),
                                        data, f.unknowns);
  EXPECT_EQ(static_cast<int>(r.held.size()), 110 - plan.rank);
  CalibrationOptions strict;
  strict.strict = true;
  EXPECT_EQ(calibrate(f.m.model, Eigen::VectorXd::Zero(f.m.model.parameterCount()), data, f.unknowns,
                      strict).status,
            CalibrationStatus::Unobservable);
}

}  // namespace
}  // namespace tolver
