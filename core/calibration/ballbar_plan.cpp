#include "core/calibration/ballbar_plan.h"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "core/calibration/identifiability.h"
#include "core/kinematics/inverse_kinematics.h"
#include "core/kinematics/sensitivity_jacobian.h"
#include "core/numerics/units.h"
#include "core/path/prediction_uncertainty.h"

namespace tolver {

std::vector<BallbarSetup> defaultBallbarSetups(int n) {
  std::vector<BallbarSetup> out;
  for (int s = 0; s < n; ++s) {
    // Table balls off the rotary axes (a ball on a rotation axis cannot see rotations about it),
    // at three heights; tool balls 25 mm off the spindle axis.
    const double psi = 2.0 * kPi * s / std::max(n, 1), phi = psi + kPi / 3;
    BallbarSetup b;
    b.id = s + 1;
    b.table_ball_w = Eigen::Vector3d(80.0 * std::cos(psi), 80.0 * std::sin(psi), 20.0 + 30.0 * s);
    b.tool_ball_t = Eigen::Vector3d(25.0 * std::cos(phi), 25.0 * std::sin(phi), 0.0);
    out.push_back(b);
  }
  return out;
}

namespace {

// 1. Candidate configurations per set-up: rotary joints at random in their ranges, the bar at
// a random azimuth and an elevation above the machine's xy plane (seen from F), the linear
// joints placing the tool ball; inside travel (and the asked ranges).
std::vector<std::vector<BallbarReading>> candidatePool(const MachineModel& model,
                                                       const BallbarPlanOptions& opt,
                                                       const ForwardKinematics& fk,
                                                       BallbarPlan& plan) {
  const int nsetups = static_cast<int>(plan.test.setups.size());
  const InverseKinematics ik(model);
  std::mt19937 rng(opt.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double min_el = degToRad(opt.min_elevation_deg);
  std::vector<std::vector<BallbarReading>> pool(nsetups);
  const int per_setup = (opt.poses + nsetups - 1) / nsetups;
  const int wanted = per_setup * std::max(1, opt.candidates_per_pose);
  for (int s = 0; s < nsetups; ++s) {
    const BallbarSetup& bs = plan.test.setups[s];
    int attempts = 0;
    while (static_cast<int>(pool[s].size()) < wanted && attempts < 200 * wanted) {
      ++attempts;
      ++plan.sampled;
      JointVector q = JointVector::Zero(model.axes.size());
      for (size_t a = 0; a < model.axes.size(); ++a)
        if (model.axes[a].isRotary()) {
          const bool ranged = a < opt.range_min.size();
          const double lo = ranged ? opt.range_min[a] : model.axes[a].travel_min;
          const double hi = ranged ? opt.range_max[a] : model.axes[a].travel_max;
          q[a] = lo + unit(rng) * (hi - lo);
        }
      // Bar direction: azimuth anywhere, elevation above the machine's xy plane, seen from F.
      const double az = 2.0 * kPi * unit(rng);
      const double el = std::asin(std::sin(min_el) + unit(rng) * (1.0 - std::sin(min_el)));
      const Eigen::Vector3d d_F(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                                std::sin(el));
      const Eigen::Matrix3d F_R_w = fk.F_T_w(q).linear();
      const double length =
          opt.bar_lengths.empty() ? opt.bar_length : opt.bar_lengths[s % opt.bar_lengths.size()];
      const Eigen::Vector3d target = bs.table_ball_w + length * (F_R_w.transpose() * d_F);
      int violated = -1;
      if (!ik.placeToolPoint(bs.tool_ball_t, target, q, &violated)) {
        ++plan.rejected;
        continue;
      }
      bool in_range = true;
      for (size_t a = 0; a < model.axes.size() && a < opt.range_min.size(); ++a)
        if (!model.axes[a].isRotary() && (q[a] < opt.range_min[a] - opt.range_margin ||
                                          q[a] > opt.range_max[a] + opt.range_margin))
          in_range = false;
      if (!in_range) {
        ++plan.rejected;
        continue;
      }
      BallbarReading r;
      r.setup = s;
      r.q = q;
      pool[s].push_back(r);
    }
  }

  return pool;
}

// The rows of the candidates that can still be picked, and the picks' bookkeeping.
struct Greedy {
  const Eigen::MatrixXd& rows;                    // column-scaled identification rows
  const std::vector<std::pair<int, int>>& index;  // row -> (set-up, pool index)
  std::vector<bool> used;

  // The unused candidate of set-up s with the largest gain(i), marked used; -1 when none is left.
  template <class Gain>
  int pick(int s, const Gain& gain) {
    int best = -1;
    double best_gain = -1.0;
    for (size_t i = 0; i < index.size(); ++i) {
      if (used[i] || index[i].first != s) continue;
      const double v = gain(i);
      if (v > best_gain) {
        best_gain = v;
        best = static_cast<int>(i);
      }
    }
    if (best >= 0) used[best] = true;
    return best;
  }
};

// 3. I-optimal (target poses given): the candidate that most reduces tr(G M^-1 G^T), G the tip
// sensitivities at the targets: gain |G M^-1 x|^2 / (1 + x^T M^-1 x), with V = X M^-1,
// d = diag(X M^-1 X^T) and Y = X M^-1 G^T kept up to date by rank-one updates (O(pool (n + g))
// per pick). Returns the picks in order.
std::vector<int> chooseIOptimal(const MachineModel& model, const std::vector<int>& unknowns,
                                const BallbarPlanOptions& opt, const ForwardKinematics& fk,
                                const Eigen::VectorXd& scale, int nsetups, Greedy& g) {
  const Eigen::MatrixXd& rows = g.rows;
  const int n = static_cast<int>(rows.cols());
  std::vector<int> picks;
  const int np_ = static_cast<int>(unknowns.size());
  // Tip sensitivities at the targets (in w), with what a measured set-up takes up projected
  // off (the part's pose and the tool tip's offset: see core/path/prediction_uncertainty.h).
  std::vector<int> setup;
  for (const ParameterBlock& b : model.blocks) {
    if (b.kind == BlockKind::WorkpieceSetup)
      for (int c = 0; c < 6; ++c) setup.push_back(b.offset + c);
    if (b.kind == BlockKind::ToolSetup)
      for (int c = 0; c < 3; ++c) setup.push_back(b.offset + c);
  }
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(3 * opt.target_poses.size(), n);
  Eigen::MatrixXd S(3 * opt.target_poses.size(), setup.size());
  Eigen::MatrixXd Jt(6, model.parameterCount());
  for (size_t t = 0; t < opt.target_poses.size(); ++t) {
    Jt.setZero();
    sensitivityJacobian(fk, opt.target_poses[t], Jt);
    const Eigen::Matrix3d R = fk.w_T_t(opt.target_poses[t]).linear();
    for (int k = 0; k < np_; ++k)
      G.block(3 * t, k, 3, 1) = R * Jt.block<3, 1>(0, unknowns[k]) / scale[k];
    for (size_t k = 0; k < setup.size(); ++k)
      S.block(3 * t, k, 3, 1) = R * Jt.block<3, 1>(0, setup[k]);
  }
  if (S.cols() > 0) G -= S * S.completeOrthogonalDecomposition().solve(G);
  const double eps = 1e-6;
  Eigen::MatrixXd V = rows / eps;  // X M^-1
  Eigen::VectorXd d = rows.rowwise().squaredNorm() / eps;
  Eigen::MatrixXd Y = (rows * G.transpose()) / eps;  // X M^-1 G^T
  for (int k = 0; k < opt.poses; ++k) {
    if (opt.progress && k % 16 == 0) opt.progress(k / static_cast<double>(opt.poses));
    const int best =
        g.pick(k % nsetups, [&](size_t i) { return Y.row(i).squaredNorm() / (1.0 + d[i]); });
    if (best < 0) continue;
    const Eigen::VectorXd Mx = V.row(best).transpose();  // M^-1 x
    const double denom = 1.0 + d[best];
    const Eigen::VectorXd XMx = rows * Mx;       // x_i^T M^-1 x
    const Eigen::RowVectorXd GMx = Y.row(best);  // (G M^-1 x)^T
    V -= XMx * Mx.transpose() / denom;
    d -= XMx.cwiseAbs2() / denom;
    Y -= XMx * GMx / denom;
    picks.push_back(best);
  }
  return picks;
}

// 3. D-optimal: the candidate with the largest x^T M^-1 x (M = eps I + sum of chosen x x^T),
// M^-1 kept by Sherman-Morrison. Returns the picks in order.
std::vector<int> chooseDOptimal(const BallbarPlanOptions& opt, int nsetups, Greedy& g) {
  const Eigen::MatrixXd& rows = g.rows;
  // The gain of each candidate, d_i = x_i^T M^-1 x_i, kept up to date by the rank-one update of
  // M^-1 (Sherman-Morrison): after picking x, d_i -= (x_i^T M^-1 x)^2 / (1 + x^T M^-1 x), one
  // matrix-vector product over the pool per pick (O(pool n)) instead of a quadratic form per
  // candidate (O(pool n^2)).
  const double lambda = 1e-6;
  Eigen::MatrixXd Minv = Eigen::MatrixXd::Identity(rows.cols(), rows.cols()) / lambda;
  Eigen::VectorXd d = rows.rowwise().squaredNorm() / lambda;
  Eigen::VectorXd Mx(rows.cols()), v(rows.rows());
  std::vector<int> picks;
  for (int k = 0; k < opt.poses; ++k) {
    if (opt.progress && k % 16 == 0) opt.progress(k / static_cast<double>(opt.poses));
    const int best = g.pick(k % nsetups, [&](size_t i) { return d[i]; });
    if (best < 0) continue;
    Mx.noalias() = Minv * rows.row(best).transpose();
    const double denominator = 1.0 + rows.row(best).dot(Mx);
    Minv.noalias() -= (Mx * Mx.transpose()) / denominator;
    v.noalias() = rows * Mx;
    d -= v.cwiseAbs2() / denominator;
    picks.push_back(best);
  }
  return picks;
}

// Measurement order: set-up by set-up; within a set-up, an order in which time is not
// correlated with any joint (so that a thermal drift cannot pass for an error along an axis):
// the D-optimal order when it already is, else a random one (first pose kept: it is the
// reference the drift checks return to) with the smallest correlation found.
void orderForTime(const MachineModel& model, const BallbarPlanOptions& opt, BallbarPlan& plan) {
  std::stable_sort(
      plan.test.readings.begin(), plan.test.readings.end(),
      [](const BallbarReading& a, const BallbarReading& b) { return a.setup < b.setup; });
  {
    auto correlation = [&](const std::vector<BallbarReading>& order) {
      BallbarTest t;
      t.setups = plan.test.setups;
      t.readings = order;
      for (size_t i = 0; i < t.readings.size(); ++i)
        t.readings[i].context.time_s = static_cast<double>(i);
      return timeJointCorrelation(model, t);
    };
    std::vector<BallbarReading> best = plan.test.readings;
    TimeJointCorrelation c = correlation(best);
    std::mt19937 order_rng(opt.seed + 104729u);
    for (int attempt = 0; attempt < 200 && c.worst >= opt.max_time_correlation; ++attempt) {
      std::vector<BallbarReading> trial = plan.test.readings;
      for (size_t b = 0; b < trial.size();) {
        size_t e = b;
        while (e < trial.size() && trial[e].setup == trial[b].setup) ++e;
        if (e - b > 2) std::shuffle(trial.begin() + b + 1, trial.begin() + e, order_rng);
        b = e;
      }
      const TimeJointCorrelation ct = correlation(trial);
      if (ct.worst < c.worst) {
        c = ct;
        best = trial;
      }
    }
    plan.test.readings = best;
  }
}

// A return to each set-up's first pose every reference_every readings (drift checks).
void insertReferenceChecks(const BallbarPlanOptions& opt, BallbarPlan& plan) {
  std::vector<BallbarReading> with_checks;
  int since = 0;
  for (size_t i = 0; i < plan.test.readings.size(); ++i) {
    const BallbarReading& r = plan.test.readings[i];
    if (i == 0 || plan.test.readings[i - 1].setup != r.setup) since = 0;
    with_checks.push_back(r);
    if (++since % opt.reference_every == 0) {
      size_t first = i;
      while (first > 0 && plan.test.readings[first - 1].setup == r.setup) --first;
      with_checks.push_back(plan.test.readings[first]);
    }
  }
  plan.test.readings = std::move(with_checks);
}

}  // namespace

BallbarPlan planBallbarTest(const MachineModel& model, const std::vector<int>& unknowns,
                            const BallbarPlanOptions& opt) {
  BallbarPlan plan;
  plan.test.setups = opt.geometry.empty() ? defaultBallbarSetups(opt.setups) : opt.geometry;
  const int nsetups = static_cast<int>(plan.test.setups.size());
  const ForwardKinematics fk(model, Eigen::VectorXd::Zero(model.parameterCount()));

  const std::vector<std::vector<BallbarReading>> pool = candidatePool(model, opt, fk, plan);

  // 2. Identification rows of every candidate, columns scaled by their norms over the pool.
  const int np = static_cast<int>(unknowns.size());
  const int n = np + 6 * nsetups;
  plan.unknowns = n;
  std::vector<std::pair<int, int>> index;  // (setup, k)
  for (int s = 0; s < nsetups; ++s)
    for (size_t k = 0; k < pool[s].size(); ++k) index.emplace_back(s, static_cast<int>(k));
  BallbarTest candidates;
  candidates.setups = plan.test.setups;
  for (const auto& [s, k] : index) candidates.readings.push_back(pool[s][k]);
  Eigen::MatrixXd rows =
      identificationJacobian(fk, candidates, std::vector<BallErrors>(nsetups), unknowns);
  Eigen::VectorXd scale;
  rows = scaleColumns(rows, &scale);

  // 3. Greedy choice, set-ups in turn: I-optimal for target poses, else D-optimal.
  Greedy g{rows, index, std::vector<bool>(index.size(), false)};
  const std::vector<int> picks = opt.target_poses.empty()
                                     ? chooseDOptimal(opt, nsetups, g)
                                     : chooseIOptimal(model, unknowns, opt, fk, scale, nsetups, g);
  for (int best : picks) plan.test.readings.push_back(pool[index[best].first][index[best].second]);
  orderForTime(model, opt, plan);
  if (opt.reference_every > 0) insertReferenceChecks(opt, plan);

  // 4. Rank and condition of the chosen design.
  const Eigen::MatrixXd J =
      identificationJacobian(fk, plan.test, std::vector<BallErrors>(nsetups), unknowns);
  const SvdSummary sum = analyseColumns(J);
  plan.rank = sum.rank;
  plan.condition = sum.condition;
  {
    BallbarTest t = plan.test;
    for (size_t i = 0; i < t.readings.size(); ++i)
      t.readings[i].context.time_s = static_cast<double>(i);
    const TimeJointCorrelation c = timeJointCorrelation(model, t);
    plan.time_correlation = c.worst;
    plan.time_correlation_axis = c.worst_axis;
  }
  return plan;
}

TimeJointCorrelation timeJointCorrelation(const MachineModel& model, const BallbarTest& test) {
  TimeJointCorrelation out;
  const size_t na = model.axes.size();
  out.r.assign(na, std::numeric_limits<double>::quiet_NaN());
  const size_t ns = test.setups.size();
  std::vector<double> n(ns, 0.0), tm(ns, 0.0);
  std::vector<Eigen::VectorXd> qm(ns, Eigen::VectorXd::Zero(na));
  for (const BallbarReading& b : test.readings) {
    if (std::isnan(b.context.time_s)) return out;
    n[b.setup] += 1;
    tm[b.setup] += b.context.time_s;
    qm[b.setup] += b.q;
  }
  for (size_t s = 0; s < ns; ++s)
    if (n[s] > 0) {
      tm[s] /= n[s];
      qm[s] /= n[s];
    }
  Eigen::VectorXd sxy = Eigen::VectorXd::Zero(na), syy = Eigen::VectorXd::Zero(na);
  double sxx = 0.0;
  for (const BallbarReading& b : test.readings) {
    const double dt = b.context.time_s - tm[b.setup];
    const Eigen::VectorXd dq = b.q - qm[b.setup];
    sxx += dt * dt;
    sxy += dt * dq;
    syy += dq.cwiseAbs2();
  }
  for (size_t a = 0; a < na; ++a) {
    if (!(sxx > 0) || !(syy[a] > 1e-18)) continue;
    out.r[a] = sxy[a] / std::sqrt(sxx * syy[a]);
    if (std::abs(out.r[a]) > out.worst) {
      out.worst = std::abs(out.r[a]);
      out.worst_axis = static_cast<int>(a);
    }
  }
  return out;
}

std::vector<double> expectedTipUncertainty(const MachineModel& model,
                                           const std::vector<int>& unknowns,
                                           const BallbarTest& plan, double noise_mm,
                                           const std::vector<JointVector>& poses) {
  Machine m;
  m.model = model;
  m.params = Eigen::VectorXd::Zero(model.parameterCount());
  const ForwardKinematics fk(model, m.params);
  const Eigen::MatrixXd J =
      identificationJacobian(fk, plan, std::vector<BallErrors>(plan.setups.size()), unknowns);
  Eigen::VectorXd scale;
  const Eigen::MatrixXd Js = scaleColumns(J, &scale);
  const Eigen::MatrixXd cov_s =
      (Js.transpose() * Js).completeOrthogonalDecomposition().pseudoInverse();
  const int np = static_cast<int>(unknowns.size());
  const Eigen::VectorXd d = scale.head(np).cwiseInverse();
  m.identification.parameters = unknowns;
  m.identification.covariance =
      noise_mm * noise_mm * (d.asDiagonal() * cov_s.topLeftCorner(np, np) * d.asDiagonal());
  PredictionUncertainty pu(m);
  pu.setupModulo(poses);
  std::vector<double> out;
  for (const JointVector& q : poses) out.push_back(pu.at(q).tip);
  return out;
}

}  // namespace tolver
