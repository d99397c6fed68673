// Known-truth recovery ([AM01] 3.7.4 and 4.9.1): simulate ball-bar readings from a machine with
// known errors, identify, compare.
#include "core/calibration/calibration.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "core/calibration/ballbar_plan.h"
#include "core/calibration/identifiability.h"
#include "core/kinematics/sensitivity_jacobian.h"
#include "io/machine/machine_file.h"
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
    r.length =
        ballbarLength(fk, r.q, t.setups[r.setup], balls[r.setup]) + (noise_mm > 0 ? n(rng) : 0.0);
  return t;
}

struct HeldOut {
  double worst_position = 0, rms_position = 0;  // mm, tool tip
  double worst_rotation = 0;                    // rad, whole tool frame
  double worst_axis = 0;                        // rad, tool axis direction
};

// Difference between the identified and the true machine at 60 configurations not used in the
// calibration, after fitting the 12 part and tool set-up parameters (which a ball-bar cannot see
// and a set-up procedure measures).
HeldOut heldOutPoseError(const MachineModel& m, const Eigen::VectorXd& identified,
                         const Eigen::VectorXd& truth) {
  const auto poses = randomPoses(m, 60, 99);
  const ForwardKinematics truth_fk(m, truth);
  std::vector<int> setup_cols;
  for (const ParameterBlock& b : m.blocks)
    if (b.kind == BlockKind::WorkpieceSetup || b.kind == BlockKind::ToolSetup)
      for (int i = 0; i < 6; ++i) setup_cols.push_back(b.offset + i);
  Eigen::VectorXd ident = identified;
  for (int it = 0; it < 4; ++it) {
    const ForwardKinematics fk(m, ident);
    const Eigen::MatrixXd J = stackedJacobian(fk, poses, setup_cols);
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
  HeldOut h;
  double sum2 = 0;
  for (const JointVector& q : poses) {
    const Eigen::Isometry3d a = fk.w_T_t(q), b = truth_fk.w_T_t(q);
    const double d = (a.translation() - b.translation()).norm();
    sum2 += d * d;
    h.worst_position = std::max(h.worst_position, d);
    h.worst_rotation =
        std::max(h.worst_rotation, Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle());
    const Eigen::Vector3d ua = a.linear().col(2), ub = b.linear().col(2);
    h.worst_axis = std::max(h.worst_axis, std::atan2(ua.cross(ub).norm(), ua.dot(ub)));
  }
  h.rms_position = std::sqrt(sum2 / poses.size());
  return h;
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

// Simulation B: true errors on the minimal-complete set only, no noise: identified = true
// within 1e-9 relative, per parameter against the largest true value of its kind (lengths,
// angles) and norm-wise per kind. The floor is rounding: readings of 150 mm carry about
// 3e-14 mm of it, which leaves about 5e-12 mm and 4e-14 rad on the coefficients.
TEST(Calibration, SimulationBRecoversTheMinimalSetExactly) {
  const Fixture& f = fixture();
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::VectorXd truth = Eigen::VectorXd::Zero(f.m.model.parameterCount());
  for (int p : f.unknowns) truth[p] = n(rng) * scaleOf(f.m.model, p);
  const auto balls = randomBalls(3, rng);
  const BallbarTest data = simulate(f.m.model, truth, f.plan.test, balls, 0.0, 1);
  const CalibrationResult r =
      calibrate(f.m.model, Eigen::VectorXd::Zero(truth.size()), data, f.unknowns);
  ASSERT_EQ(r.status, CalibrationStatus::Converged) << r.message;
  EXPECT_TRUE(r.held.empty());
  double err2[2] = {0, 0}, norm2[2] = {0, 0}, largest[2] = {0, 0};
  for (int p : f.unknowns) {
    const int kind = f.m.model.parameters[p].angular ? 1 : 0;
    largest[kind] = std::max(largest[kind], std::abs(truth[p]));
  }
  for (int p : f.unknowns) {
    const int kind = f.m.model.parameters[p].angular ? 1 : 0;
    EXPECT_NEAR(r.params[p], truth[p], 1e-9 * largest[kind]) << f.m.model.parameters[p].iso_code;
    err2[kind] += std::pow(r.params[p] - truth[p], 2);
    norm2[kind] += truth[p] * truth[p];
  }
  for (int kind = 0; kind < 2; ++kind) EXPECT_LT(std::sqrt(err2[kind] / norm2[kind]), 1e-9) << kind;
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
  const HeldOut h = heldOutPoseError(m, r.params, truth);
  const double worst_pos = h.worst_position, worst_rot = h.worst_rotation;
  EXPECT_LT(worst_pos, 1e-6);
  EXPECT_LT(worst_rot, 1e-9);
}

// Thesis 3.7-3.8 and Table 3.5, simulation B of the link-error model: one set-up, 30 poses, a
// 13-inch bar; unknowns the 8 machine link errors of Table 3.4 and the two ball positions
// (14, rank 14); true values from Table 3.5 (inches and radians, some as large as 0.05 rad).
TEST(Calibration, Table35LinkModelSimulationB) {
  Machine mm = readMachineFile(test::sourcePath(test::shippedMachines()[0]));
  const MachineModel& m = mm.model;
  const std::vector<int> unknowns = m.preferred.at("link");
  BallbarPlanOptions o;
  o.bar_length = 13 * 25.4;
  o.setups = 1;
  o.poses = 30;
  const BallbarPlan plan = planBallbarTest(m, unknowns, o);
  ASSERT_EQ(plan.test.readings.size(), 30u);
  EXPECT_EQ(plan.unknowns, 14);
  EXPECT_EQ(plan.rank, 14);
  EXPECT_LT(plan.condition, 1e3);
  const double in = 25.4;
  Eigen::VectorXd truth = Eigen::VectorXd::Zero(m.parameterCount());
  const std::pair<const char*, double> table35[] = {
      {"COX", -0.0060},     {"AOA", 0.0500}, {"BOA", 0.0060}, {"COA", -0.0040},
      {"YOC", 0.0030 * in}, {"BOC", 0.0110}, {"AOZ", 0.0300}, {"BOZ", 0.0350}};
  for (const auto& [code, v] : table35) truth[m.findParameter(code)] = v;
  std::vector<BallErrors> balls(1);
  balls[0].table_w = Eigen::Vector3d(0.0070, 0.0060, 0.0030) * in;  // e_x,w e_y,w e_z,w
  balls[0].tool_t = Eigen::Vector3d(0.0040, 0.0070, 0.0090) * in;   // e_x,t e_y,t e_z,t
  const BallbarTest data = simulate(m, truth, plan.test, balls, 0.0, 1);
  const CalibrationResult r = calibrate(m, Eigen::VectorXd::Zero(truth.size()), data, unknowns);
  ASSERT_EQ(r.status, CalibrationStatus::Converged)
      << r.message << " " << r.iterations << " " << r.rms_residual;
  EXPECT_EQ(r.rank, 14);
  for (const auto& [code, v] : table35)
    EXPECT_NEAR(r.params[m.findParameter(code)], truth[m.findParameter(code)],
                1e-9 * std::abs(v) + 1e-14)
        << code;
  EXPECT_LT((r.ball_errors[0].table_w - balls[0].table_w).norm(), 1e-9 * balls[0].table_w.norm());
  EXPECT_LT((r.ball_errors[0].tool_t - balls[0].tool_t).norm(), 1e-9 * balls[0].tool_t.norm());
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
  const CalibrationResult r =
      calibrate(f.m.model, Eigen::VectorXd::Zero(truth.size()), data, f.unknowns);
  ASSERT_EQ(r.status, CalibrationStatus::Converged);
  const double chi2 = std::pow(r.residual_sigma / 0.5e-3, 2);
  EXPECT_GT(chi2, 0.7);
  EXPECT_LT(chi2, 1.4);
  // Held-out error of the identified machine: noise propagated through the identification and
  // extrapolated over the whole working volume (reported; a bound catches regressions).
  const HeldOut h = heldOutPoseError(f.m.model, r.params, truth);
  RecordProperty("heldout_tip_rms_um", std::to_string(h.rms_position * 1e3));
  RecordProperty("heldout_tip_worst_um", std::to_string(h.worst_position * 1e3));
  RecordProperty("reduced_chi2", std::to_string(chi2));
  std::printf(
      "[ held-out ] 0.5 um noise, 600 readings, reduced chi2 %.3f: tool tip error at 60 "
      "other poses RMS %.3f um, worst %.3f um; tool axis worst %.2f urad\n",
      chi2, h.rms_position * 1e3, h.worst_position * 1e3, h.worst_axis * 1e6);
  EXPECT_LT(h.rms_position, 20e-3);
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

// The normal-equations path and the Householder QR path (the independent truth, backward
// stable) reach the same fixed point: identified values, ball errors, uncertainties, covariance
// and condition number agree, on noisy readings with a prior (regularised) and without.
TEST(Calibration, NormalEquationsReachTheFixedPointOfQr) {
  const Fixture& f = fixture();
  std::mt19937 rng(29);
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::VectorXd truth = Eigen::VectorXd::Zero(f.m.model.parameterCount());
  for (int p : f.unknowns) truth[p] = n(rng) * scaleOf(f.m.model, p);
  const BallbarTest data = simulate(f.m.model, truth, f.plan.test, randomBalls(3, rng), 0.5e-3, 5);
  for (const bool regularised : {false, true}) {
    CalibrationOptions fast, qr;
    if (regularised)
      fast.prior_linear = qr.prior_linear = 5e-3, fast.prior_angular = qr.prior_angular = 20e-6;
    qr.normal_equations = false;
    const Eigen::VectorXd prior = Eigen::VectorXd::Zero(truth.size());
    const CalibrationResult a = calibrate(f.m.model, prior, data, f.unknowns, fast);
    const CalibrationResult b = calibrate(f.m.model, prior, data, f.unknowns, qr);
    ASSERT_EQ(a.status, CalibrationStatus::Converged);
    ASSERT_EQ(b.status, CalibrationStatus::Converged);
    ASSERT_EQ(a.identified, b.identified);
    EXPECT_EQ(a.rank, b.rank);
    EXPECT_NEAR(a.condition, b.condition, 1e-6 * b.condition);
    for (size_t k = 0; k < a.identified.size(); ++k) {
      const int p = a.identified[k];
      // Differences far below each value's uncertainty (a thousandth of it).
      EXPECT_LT(std::abs(a.params[p] - b.params[p]), 1e-3 * b.uncertainty[k]) << p;
      EXPECT_NEAR(a.uncertainty[k], b.uncertainty[k], 1e-6 * b.uncertainty[k]) << p;
    }
    for (size_t s = 0; s < a.ball_errors.size(); ++s)
      EXPECT_LT((a.ball_errors[s].table_w - b.ball_errors[s].table_w).norm() +
                    (a.ball_errors[s].tool_t - b.ball_errors[s].tool_t).norm(),
                1e-9);
    EXPECT_LT((a.covariance - b.covariance).norm(), 1e-6 * b.covariance.norm());
    EXPECT_NEAR(a.rms_residual, b.rms_residual, 1e-12);
  }
}

// Thesis 4.8: one set-up cannot identify the full set: the rank stays at 78 of 98 unknowns.
TEST(Calibration, OneSetupCannotIdentifyTheCubicModel) {
  const Fixture& f = fixture();
  BallbarPlanOptions o;
  o.setups = 1;
  o.poses = 180;
  const BallbarPlan plan = planBallbarTest(f.m.model, f.unknowns, o);
  EXPECT_EQ(plan.unknowns, 98);
  EXPECT_EQ(plan.rank, 78);
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
  const CalibrationResult r =
      calibrate(f.m.model, Eigen::VectorXd::Zero(f.m.model.parameterCount()), data, f.unknowns);
  EXPECT_EQ(static_cast<int>(r.held.size()), 110 - plan.rank);
  // What cannot be seen: the roll of the Z ram about the spindle axis (gamma_z(Z), every
  // position-dependent term): a ball on that axis does not move when the ram turns about it.
  // Its pitch and yaw fall in with the Z straightness terms (which of each pair is held
  // depends on the ball's distance from the gauge point).
  EXPECT_EQ(r.held.size(), 11u);
  std::vector<std::string> held;
  for (int p : r.held) held.push_back(f.m.model.parameters[p].iso_code);
  for (const char* c : {"ECZ.c1", "ECZ.c2", "ECZ.c3"})
    EXPECT_NE(std::find(held.begin(), held.end(), c), held.end()) << c;
  CalibrationOptions strict;
  strict.strict = true;
  EXPECT_EQ(calibrate(f.m.model, Eigen::VectorXd::Zero(f.m.model.parameterCount()), data,
                      f.unknowns, strict)
                .status,
            CalibrationStatus::Unobservable);
}

}  // namespace
}  // namespace tolver

namespace tolver {
namespace {

// What an identified parameter stands for is true: a machine whose only error is a parameter
// the minimal-complete set leaves out (gamma_x(Y).c0, a pitch of the Y carriage) calibrates to
// the kept parameter that absorbs it, at the value its coefficient says.
TEST(Calibration, AnIdentifiedParameterShowsTheRemovedOnesItStandsFor) {
  const Fixture& f = fixture();
  const MachineModel& m = f.m.model;
  const auto absorbed = calibrationAbsorbed(m, f.unknowns);
  const int eay = m.findParameter("EAY.c0"), eax = m.findParameter("EAX.c0");
  ASSERT_GE(eay, 0);
  ASSERT_TRUE(std::find(f.unknowns.begin(), f.unknowns.end(), eay) == f.unknowns.end());
  const size_t k = std::find(f.unknowns.begin(), f.unknowns.end(), eax) - f.unknowns.begin();
  ASSERT_LT(k, f.unknowns.size());
  double coefficient = 0;
  for (const AbsorbedTerm& t : absorbed[k])
    if (t.parameter == eay) coefficient = t.coefficient;
  EXPECT_NEAR(coefficient, 1.0, 1e-6);  // the same rotation about x, seen after Y or after X
  Eigen::VectorXd truth = Eigen::VectorXd::Zero(m.parameterCount());
  truth[eay] = 30e-6;
  const BallbarTest data = simulate(m, truth, f.plan.test, std::vector<BallErrors>(3), 0.0, 1);
  const CalibrationResult r =
      calibrate(m, Eigen::VectorXd::Zero(m.parameterCount()), data, f.unknowns);
  ASSERT_EQ(r.status, CalibrationStatus::Converged);
  EXPECT_NEAR(r.params[eax], coefficient * 30e-6, 1e-9);
}

}  // namespace
}  // namespace tolver

namespace tolver {
namespace {

// The evidence's scale from one thin SVD against the direct log density of the m x m covariance
// (a Cholesky per k, the formula as written), on random problems whose true scale is known: the
// two pick the same grid point, and it lies near the truth.
// log N(y; 0, s2 I + k^2 A diag(d) A^T) by a Cholesky of the m x m covariance (the direct way,
// against which the SVD shortcut is tested).
double directLogEvidence(const Eigen::MatrixXd& A, const Eigen::VectorXd& d,
                         const Eigen::VectorXd& y, double s2, double k) {
  Eigen::MatrixXd C = k * k * A * d.asDiagonal() * A.transpose();
  C.diagonal().array() += s2;
  const Eigen::LLT<Eigen::MatrixXd> llt(C);
  const Eigen::VectorXd z = llt.matrixL().solve(y);
  double logdet = 0;
  for (Eigen::Index j = 0; j < C.rows(); ++j) logdet += 2.0 * std::log(llt.matrixL()(j, j));
  return -0.5 * (z.squaredNorm() + logdet);
}

TEST(Calibration, EvidenceScaleMatchesTheDirectLogDensity) {
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  for (double k_true : {0.1, 1.0, 10.0}) {
    const int m = 300, np = 40;
    const double s2 = 0.25;
    Eigen::MatrixXd A(m, np);
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < np; ++j) A(i, j) = n(rng);
    Eigen::VectorXd d(np), theta(np), y(m);
    for (int j = 0; j < np; ++j) {
      d[j] = j % 2 ? 1.0 : 0.3;
      theta[j] = k_true * std::sqrt(d[j]) * n(rng);
    }
    for (int i = 0; i < m; ++i) y[i] = std::sqrt(s2) * n(rng);
    y += A * theta;
    double direct_k = 0, best = -INFINITY;
    for (int i = 0; i <= 40; ++i) {
      const double k = 0.03 * std::pow(100.0 / 0.03, i / 40.0);
      const double e = directLogEvidence(A, d, y, s2, k);
      if (e > best) {
        best = e;
        direct_k = k;
      }
    }
    const double k = evidenceScale(A, d, y, s2);
    EXPECT_DOUBLE_EQ(k, direct_k) << k_true;
    EXPECT_GT(k, k_true / 2) << k_true;
    EXPECT_LT(k, k_true * 2) << k_true;
  }
}

// Not knowing k: the chosen k's covariance widened by PriorScaleEvidence::inflation equals the
// posterior mixture over the grid computed directly (each k's Gaussian posterior from the normal
// equations, weights from the m x m log density), about the chosen k's mean; with more
// parameters than readings too (the complement of V carries the prior alone).
TEST(Calibration, PriorScaleInflationIsTheMixtureOverTheEvidence) {
  std::mt19937 rng(9);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int m : {12, 6}) {
    const int np = 8;
    const double s2 = 0.5;
    Eigen::MatrixXd A(m, np);
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < np; ++j) A(i, j) = n(rng) * (j < 3 ? 1.0 : 0.05);  // weak columns
    Eigen::VectorXd d(np), y(m);
    for (int j = 0; j < np; ++j) d[j] = j % 2 ? 1.0 : 0.3;
    for (int i = 0; i < m; ++i) y[i] = 2.0 * n(rng);
    const PriorScaleEvidence e = priorScaleEvidence(A, d, y, s2);
    std::vector<double> le;
    std::vector<Eigen::MatrixXd> cov;
    std::vector<Eigen::VectorXd> mean;
    double top = -INFINITY;
    size_t best = 0;
    for (int i = 0; i <= 40; ++i) {
      const double k = 0.03 * std::pow(100.0 / 0.03, i / 40.0);
      le.push_back(directLogEvidence(A, d, y, s2, k));
      if (le.back() > top) top = le.back(), best = le.size() - 1;
      Eigen::MatrixXd P = A.transpose() * A / s2;
      P.diagonal() += d.cwiseInverse() / (k * k);
      cov.push_back(P.inverse());
      mean.push_back(cov.back() * A.transpose() * y / s2);
    }
    ASSERT_DOUBLE_EQ(e.k, 0.03 * std::pow(100.0 / 0.03, best / 40.0));
    double sum = 0;
    for (double v : le) sum += std::exp(v - top);
    Eigen::MatrixXd mixture = Eigen::MatrixXd::Zero(np, np);
    for (size_t i = 0; i < le.size(); ++i) {
      const Eigen::VectorXd dm = mean[i] - mean[best];
      mixture += std::exp(le[i] - top) / sum * (cov[i] + dm * dm.transpose());
    }
    const Eigen::MatrixXd T = e.inflation();
    const Eigen::MatrixXd widened = T * cov[best] * T.transpose();
    EXPECT_LT((widened - mixture).norm(), 1e-8 * mixture.norm()) << m;
    // The widening matters here: k is decided by a few readings.
    EXPECT_GT((mixture - cov[best]).norm(), 0.1 * cov[best].norm()) << m;
  }
}

}  // namespace
}  // namespace tolver
