#include "core/calibration/calibration.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/calibration/identifiability.h"
#include "core/numerics/statistics.h"

namespace tolver {
namespace {

bool isSetupParameter(const MachineModel& m, int p) {
  const BlockKind k = m.blocks[m.parameters[p].block].kind;
  return k == BlockKind::WorkpieceSetup || k == BlockKind::ToolSetup;
}

void linearise(const MachineModel& m, const Eigen::VectorXd& params, const BallbarTest& test,
               const std::vector<BallErrors>& balls, const std::vector<int>& unknowns,
               Eigen::VectorXd* r, Eigen::MatrixXd* J) {
  const ForwardKinematics fk(m, params);
  *J = identificationJacobian(fk, test, balls, unknowns, r);
}

// 1. Which unknowns can the data see? The identification Jacobian at the prior reduced to a
// full-rank set of columns (ball errors protected, strategy III otherwise): the columns kept in
// *keep_cols, the machine parameters left out in res.held. False (res says why) when a ball
// position cannot be seen, or, strict, when a parameter cannot.
bool observableColumns(const Eigen::MatrixXd& J0, const std::vector<int>& unknown_params,
                       const CalibrationOptions& opt, CalibrationResult& res, std::vector<int>* keep_cols) {
  const int np_all = static_cast<int>(unknown_params.size());
  std::vector<int> cols(J0.cols());
  std::vector<bool> protect(J0.cols(), false);
  for (int c = 0; c < J0.cols(); ++c) {
    cols[c] = c;
    protect[c] = c >= np_all;
  }
  // Well conditioned (the usual case after a test plan): every column stays, no reduction.
  if (clearlyFullRank(J0)) {
    for (int c = 0; c < J0.cols(); ++c) keep_cols->push_back(c);
    return true;
  }
  const MinimalSet ms = selectMinimalSet(J0, cols, protect, {}, false);
  for (int c : ms.removed) {
    if (c >= np_all) {
      res.status = CalibrationStatus::Unobservable;
      res.message = "the readings cannot see the ball positions of every set-up";
      return false;
    }
    res.held.push_back(unknown_params[c]);
  }
  std::sort(res.held.begin(), res.held.end());
  if (!res.held.empty() && opt.strict) {
    res.status = CalibrationStatus::Unobservable;
    res.message = std::to_string(res.held.size()) + " parameters cannot be identified from these readings";
    return false;
  }
  for (int c = 0; c < J0.cols(); ++c)
    if (c >= np_all || !std::binary_search(res.held.begin(), res.held.end(), unknown_params[c]))
      keep_cols->push_back(c);
  return true;
}

// The scaled covariance (J_s^T J_s)^+ from the last factorisation J_s = Q R (J_s the column-scaled
// Jacobian): R^-1 R^-T when R has full rank (the usual case: the unknowns were reduced to a
// full-rank set), else the rank-truncated pseudo-inverse V diag(1/sigma^2) V^T.
Eigen::MatrixXd scaledCovariance(const Eigen::MatrixXd& R, int rank) {
  const Eigen::Index n = R.cols();
  if (rank == n) {
    const Eigen::MatrixXd Rinv =
        R.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(n, n));
    return Rinv * Rinv.transpose();
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(R, Eigen::ComputeFullV);
  const Eigen::VectorXd& sv = svd.singularValues();
  Eigen::VectorXd inv2 = Eigen::VectorXd::Zero(sv.size());
  for (int k = 0; k < rank; ++k) inv2[k] = 1.0 / (sv[k] * sv[k]);
  return svd.matrixV() * inv2.asDiagonal() * svd.matrixV().transpose();
}

// 3. Residuals and uncertainties from the last factorisation (C: scaledCovariance, `scale` the
// column scales): cov = s^2 (J^T J)^-1.
void residualsAndUncertainties(const Eigen::VectorXd& r, const Eigen::MatrixXd& C,
                               const Eigen::VectorXd& scale, const std::vector<int>& keep_cols, int np_all, int np,
                               CalibrationResult& res) {
  const int m = static_cast<int>(r.size()), n = static_cast<int>(keep_cols.size());
  res.residuals = r;
  res.rms_residual = std::sqrt(r.squaredNorm() / m);
  res.max_residual = r.cwiseAbs().maxCoeff();
  res.residual_sigma = std::sqrt(r.squaredNorm() / std::max(1, m - n));
  // With unit-norm columns the diagonal is the variance inflation factor.
  const Eigen::VectorXd vif = C.diagonal();
  Eigen::VectorXd sd(n);
  for (int c = 0; c < n; ++c) sd[c] = res.residual_sigma * std::sqrt(vif[c]) / scale[c];
  res.uncertainty = sd.head(np);
  {
    // cov = s^2 D^-1 C D^-1 over the identified parameters (D the column scales).
    const Eigen::VectorXd d = scale.head(np).cwiseInverse();
    res.covariance = res.residual_sigma * res.residual_sigma *
                     (d.asDiagonal() * C.topLeftCorner(np, np) * d.asDiagonal());
  }
  res.observability = vif.head(np).cwiseInverse().cwiseSqrt();
  for (int k = np; k < n; ++k) {
    const int c = keep_cols[k] - np_all;
    BallErrors& u = res.ball_uncertainty[c / 6];
    (c % 6 < 3 ? u.table_w : u.tool_t)[c % 3] = sd[k];
  }
}

}  // namespace

// Long by design: the Gauss-Newton loop of [AM01] 3.7 with its stopping rules; the steps
// before and after it are functions (observableColumns, residualsAndUncertainties).
CalibrationResult calibrate(const MachineModel& model, const Eigen::VectorXd& prior,
                            const BallbarTest& test, const std::vector<int>& unknown_params,
                            const CalibrationOptions& opt) {
  CalibrationResult res;
  res.params = prior;
  res.ball_errors.assign(test.setups.size(), BallErrors{});
  res.ball_uncertainty.assign(test.setups.size(), BallErrors{});
  if (test.readings.empty()) {
    res.message = "no readings";
    return res;
  }
  // 1. Which unknowns can the data see? Reduce the identification Jacobian at the prior to a
  //    full-rank set (ball errors protected, strategy III otherwise).
  Eigen::VectorXd r;
  Eigen::MatrixXd J0;
  linearise(model, prior, test, res.ball_errors, unknown_params, &r, &J0);
  const int np_all = static_cast<int>(unknown_params.size());
  std::vector<int> keep_cols;  // columns of J0 that stay unknowns
  if (!observableColumns(J0, unknown_params, opt, res, &keep_cols)) return res;
  std::vector<int> unknowns;
  for (int c : keep_cols)
    if (c < np_all) unknowns.push_back(unknown_params[c]);
  res.identified = unknowns;
  const int np = static_cast<int>(unknowns.size());
  const int n = static_cast<int>(keep_cols.size());
  res.unknowns = n;
  const int m = static_cast<int>(test.readings.size());
  if (m <= n) {
    res.status = CalibrationStatus::Unobservable;
    res.message = "fewer readings than unknowns";
    return res;
  }
  Eigen::MatrixXd J(m, n);
  for (int k = 0; k < n; ++k) J.col(k) = J0.col(keep_cols[k]);
  // Prior rows (regularisation towards zero): w_k = s / sigma_k on each machine parameter.
  const bool regularised = opt.prior_linear > 0 && opt.prior_angular > 0;
  Eigen::VectorXd w = Eigen::VectorXd::Zero(np);
  if (regularised)
    for (int k = 0; k < np; ++k)
      w[k] = opt.prior_noise /
             (model.parameters[unknowns[k]].angular ? opt.prior_angular : opt.prior_linear);
  const int mp = regularised ? m + np : m;
  auto augmented = [&](const Eigen::MatrixXd& Jr, const Eigen::VectorXd& rr, Eigen::MatrixXd* Ja,
                       Eigen::VectorXd* ra) {
    Ja->setZero(mp, n);
    ra->resize(mp);
    Ja->topRows(m) = Jr;
    ra->head(m) = rr;
    if (regularised)
      for (int k = 0; k < np; ++k) {
        (*Ja)(m + k, k) = w[k];
        (*ra)[m + k] = -w[k] * res.params[unknowns[k]];
      }
  };

  // 2. Gauss-Newton with the pseudo-inverse of the column-scaled Jacobian A (prior rows
  //    included). Two factorisations, chosen at the first pass:
  //    * normal equations, N = A^T A by Cholesky, when N's eigenvalues give kappa(A)^2 below
  //      kNormalConditionMax (kappa below 1e5): the usual case, the unknowns having been reduced
  //      to a full-rank set (step 1); a step's relative error is then at most about
  //      eps kappa^2 = 2e-6, and the residuals are evaluated exactly at every pass, so the
  //      iteration reaches the same fixed point, J^T r = 0;
  //    * otherwise Householder J = QR, the step R^-1 Q^T r when R has full rank (its singular
  //      values decide, by bidiagonalisation), the rank-truncated pseudo-inverse by the SVD of R
  //      otherwise.
  //    The last factorisation also gives the covariance.
  constexpr double kNormalConditionMax = 1e10;  // of N = A^T A
  Eigen::VectorXd scale;
  Eigen::MatrixXd R;
  res.status = CalibrationStatus::NotConverged;
  double previous_step = std::numeric_limits<double>::infinity();
  Eigen::MatrixXd Ja, N;
  Eigen::VectorXd ra;
  Eigen::LLT<Eigen::MatrixXd> llt;
  bool normal = opt.normal_equations;  // the normal-equations path
  Eigen::VectorXd g;  // A^T r_a, scaled
  double ra2 = 0.0;   // |r_a|^2
  // N, g and ra2 at the current point (N and g column-scaled); false when a column is zero.
  auto normalEquations = [&]() {
    N.setZero(n, n);
    N.selfadjointView<Eigen::Lower>().rankUpdate(J.transpose());
    g = J.transpose() * r;
    ra2 = r.squaredNorm();
    for (int k = 0; k < np && regularised; ++k) {
      const double rk = -w[k] * res.params[unknowns[k]];
      N(k, k) += w[k] * w[k];
      g[k] += w[k] * rk;
      ra2 += rk * rk;
    }
    if (!scaleNormalMatrix(N, &scale)) return false;
    g = g.cwiseQuotient(scale);
    return true;
  };
  for (int it = 0; it < opt.max_iterations; ++it) {
    Eigen::VectorXd step_s;
    double reducible2 = 0.0;  // |the part of r a step can remove|^2
    double r2 = 0.0;          // |r_a|^2
    if (normal) {
      normal = normalEquations();
      if (normal && it == 0) normal = normalConditionSquared(N) < kNormalConditionMax;
      if (normal) llt.compute(N);
      normal = normal && llt.info() == Eigen::Success;
      if (normal) {
        step_s = llt.solve(g);
        reducible2 = g.dot(step_s);
        r2 = ra2;
        res.rank = n;
      }
    }
    if (!normal) {
      augmented(J, r, &Ja, &ra);
      Eigen::HouseholderQR<Eigen::MatrixXd> qr(scaleColumns(Ja, &scale));
      R = qr.matrixQR().topRows(n).triangularView<Eigen::Upper>();
      const Eigen::VectorXd Qtr = (qr.householderQ().transpose() * ra).head(n);
      const Eigen::VectorXd sv = summariseScaled(R, mp).singular_values;
      res.rank = numericalRank(sv);
      res.condition = sv[0] / sv[res.rank - 1];
      if (res.rank == n) {
        step_s = R.triangularView<Eigen::Upper>().solve(Qtr);
        reducible2 = Qtr.squaredNorm();
      } else {
        const Eigen::JacobiSVD<Eigen::MatrixXd> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
        Eigen::VectorXd inv = Eigen::VectorXd::Zero(n);
        for (int k = 0; k < res.rank; ++k) inv[k] = 1.0 / svd.singularValues()[k];
        const Eigen::VectorXd Utr = svd.matrixU().transpose() * Qtr;
        step_s = svd.matrixV() * inv.asDiagonal() * Utr;
        reducible2 = Utr.head(res.rank).squaredNorm();
      }
      r2 = ra.squaredNorm();
    }
    // The step's size in column-scaled units.
    const double sn = step_s.norm();
    // What no step can remove: the least-squares residual of the linearised problem.
    const double irreducible = std::sqrt(std::max(0.0, r2 - reducible2));
    const bool done = sn < opt.step_tolerance || sn < opt.relative_tolerance * irreducible ||
                      (sn < opt.floor_tolerance && sn > 0.5 * previous_step);
    previous_step = sn;
    if (done) {
      res.status = CalibrationStatus::Converged;
      res.iterations = it;
      break;
    }
    const Eigen::VectorXd step = step_s.cwiseQuotient(scale);
    for (int k = 0; k < np; ++k) res.params[unknowns[k]] += step[k];
    for (int k = np; k < n; ++k) {
      const int c = keep_cols[k] - np_all;  // ball column: set-up, table/tool, xyz
      BallErrors& b = res.ball_errors[c / 6];
      (c % 6 < 3 ? b.table_w : b.tool_t)[c % 3] += step[k];
    }
    res.iterations = it + 1;
    Eigen::MatrixXd Jall;
    linearise(model, res.params, test, res.ball_errors, unknown_params, &r, &Jall);
    for (int k = 0; k < n; ++k) J.col(k) = Jall.col(keep_cols[k]);
  }
  Eigen::MatrixXd C;  // the scaled covariance
  if (normal) {
    // The condition at the last factorisation, reported; the covariance N^-1.
    const double kappa2 = normalConditionSquared(N);
    res.condition = std::sqrt(kappa2);
    C = llt.solve(Eigen::MatrixXd::Identity(n, n));
  } else {
    C = scaledCovariance(R, res.rank);
  }

  // 3. Residuals and uncertainties from the last factorisation.
  residualsAndUncertainties(r, C, scale, keep_cols, np_all, np, res);
  res.message = res.status == CalibrationStatus::Converged ? "converged" : "did not converge";
  return res;
}

std::vector<int> defaultCalibrationUnknowns(const MachineModel& model, int poses, unsigned seed) {
  const std::vector<int> cols = modelColumns(model, "motion");
  auto it = model.preferred.find("motion");
  const std::vector<int> preferred = it == model.preferred.end() ? std::vector<int>{} : it->second;
  const MinimalSet ms = minimalSetForModel(model, randomPoses(model, poses, seed), cols, preferred);
  std::vector<int> out;
  for (int p : ms.kept)
    if (!isSetupParameter(model, p)) out.push_back(p);
  return out;
}

std::vector<GrossReading> grossReadings(const MachineModel& model, const BallbarTest& test,
                                        const CalibrationResult& fit, double alpha) {
  std::vector<GrossReading> out;
  const int m = static_cast<int>(test.readings.size());
  if (m == 0 || fit.residuals.size() != m) return out;
  const ForwardKinematics fk(model, fit.params);
  Eigen::VectorXd r;
  const Eigen::MatrixXd J =
      scaleColumns(identificationJacobian(fk, test, fit.ball_errors, fit.identified, &r));
  // The hat matrix U U^T, U an orthonormal basis of J's column space: the thin Q of J = QR when
  // J has full rank, else the leading left singular vectors.
  const int n = static_cast<int>(J.cols());
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(J);
  const Eigen::MatrixXd R = m >= n ? Eigen::MatrixXd(qr.matrixQR().topRows(n).triangularView<Eigen::Upper>()) : J;
  const int rank = numericalRank(summariseScaled(R, m).singular_values);
  if (m - rank < 2) return out;  // no redundancy: nothing can be inconsistent
  const double s = std::sqrt(r.squaredNorm() / (m - rank));
  if (!(s > 0)) return out;
  Eigen::MatrixXd U;
  if (rank == n && m >= n) {
    U = qr.householderQ() * Eigen::MatrixXd::Identity(m, n);
  } else {
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(J, Eigen::ComputeThinU);
    U = svd.matrixU().leftCols(rank);
  }
  for (int i = 0; i < m; ++i) {
    const double h = std::min(U.row(i).squaredNorm(), 1.0 - 1e-12);
    const double t = r[i] / (s * std::sqrt(1.0 - h));
    if (2.0 * normalSurvival(std::abs(t)) * m < alpha) out.push_back({i, r[i], t});
  }
  std::sort(out.begin(), out.end(), [](const GrossReading& a, const GrossReading& b) {
    return std::abs(a.studentized) > std::abs(b.studentized);
  });
  return out;
}

RobustCalibration calibrateWithoutGross(const MachineModel& model, const Eigen::VectorXd& prior,
                                        const BallbarTest& test,
                                        const std::vector<int>& unknown_params,
                                        const CalibrationOptions& options, double alpha,
                                        double max_fraction) {
  RobustCalibration out;
  out.with_all = calibrate(model, prior, test, unknown_params, options);
  out.fit = out.with_all;
  out.test = test;
  std::vector<int> original(test.readings.size());
  for (size_t i = 0; i < original.size(); ++i) original[i] = static_cast<int>(i);
  const int limit = static_cast<int>(max_fraction * static_cast<double>(test.readings.size()));
  while (out.fit.status == CalibrationStatus::Converged ||
         out.fit.status == CalibrationStatus::NotConverged) {
    const std::vector<GrossReading> g = grossReadings(model, out.test, out.fit, alpha);
    if (g.empty()) break;
    if (static_cast<int>(out.removed.size()) >= limit) {
      out.limit_reached = true;
      break;
    }
    GrossReading worst = g.front();
    const int k = worst.index;
    worst.index = original[k];
    out.removed.push_back(worst);
    out.test.readings.erase(out.test.readings.begin() + k);
    original.erase(original.begin() + k);
    out.fit = calibrate(model, prior, out.test, unknown_params, options);
  }
  // Each removed reading's deviation from the final fit (what it is off by), and that in units
  // of the fit's residual sigma.
  if (!out.removed.empty()) {
    const ForwardKinematics fk(model, out.fit.params);
    for (GrossReading& g : out.removed) {
      const BallbarReading& b = test.readings[g.index];
      g.residual = b.length - ballbarLength(fk, b.q, test.setups[b.setup],
                                            out.fit.ball_errors[b.setup], &b.context);
      g.studentized = out.fit.residual_sigma > 0 ? g.residual / out.fit.residual_sigma : 0.0;
    }
  }
  return out;
}

std::vector<std::vector<AbsorbedTerm>> calibrationAbsorbed(const MachineModel& model,
                                                           const std::vector<int>& unknowns,
                                                           int poses, unsigned seed) {
  std::vector<int> removed;
  for (int p : modelColumns(model, "motion"))
    if (!isSetupParameter(model, p) && std::find(unknowns.begin(), unknowns.end(), p) == unknowns.end())
      removed.push_back(p);
  return absorbedParameters(model, randomPoses(model, poses, seed), unknowns, removed);
}

IdentificationUncertainty identificationUncertainty(const CalibrationResult& fit, const BallbarTest& test,
                                                    int axes) {
  IdentificationUncertainty u;
  u.parameters = fit.identified;
  u.covariance = fit.covariance;
  u.readings = static_cast<int>(test.readings.size());
  if (!test.readings.empty()) {
    u.covered_min.assign(axes, std::numeric_limits<double>::infinity());
    u.covered_max.assign(axes, -std::numeric_limits<double>::infinity());
    for (const BallbarReading& r : test.readings)
      for (int a = 0; a < axes && a < r.q.size(); ++a) {
        u.covered_min[a] = std::min(u.covered_min[a], r.q[a]);
        u.covered_max[a] = std::max(u.covered_max[a], r.q[a]);
      }
  }
  return u;
}

double choosePriorScale(const MachineModel& model, const BallbarTest& test,
                        const CalibrationResult& fit, double unit_linear, double unit_angular) {
  const ForwardKinematics fk(model, fit.params);
  Eigen::VectorXd r;
  const Eigen::MatrixXd J = identificationJacobian(fk, test, fit.ball_errors, fit.identified, &r);
  const int np = static_cast<int>(fit.identified.size());
  const int m = static_cast<int>(J.rows()), nb = static_cast<int>(J.cols()) - np;
  // The readings at zero machine errors, to first order: r + Jm theta.
  Eigen::VectorXd theta(np);
  Eigen::VectorXd d(np);
  for (int k = 0; k < np; ++k) {
    theta[k] = fit.params[fit.identified[k]];
    const double u = model.parameters[fit.identified[k]].angular ? unit_angular : unit_linear;
    d[k] = u * u;
  }
  const Eigen::VectorXd y0 = r + J.leftCols(np) * theta;
  // Project off the ball columns (flat prior): the complement of their span.
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(J.rightCols(nb));
  const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(m, m);
  const Eigen::MatrixXd P = Q.rightCols(m - nb);
  const Eigen::VectorXd y = P.transpose() * y0;
  const Eigen::MatrixXd A = P.transpose() * J.leftCols(np);
  const Eigen::MatrixXd ADA = A * d.asDiagonal() * A.transpose();
  const double s2 = fit.residual_sigma * fit.residual_sigma;
  double best_k = 1.0, best = -std::numeric_limits<double>::infinity();
  for (int i = 0; i <= 40; ++i) {
    const double k = 0.03 * std::pow(100.0 / 0.03, i / 40.0);
    Eigen::MatrixXd C = k * k * ADA;
    C.diagonal().array() += s2;
    const Eigen::LLT<Eigen::MatrixXd> llt(C);
    if (llt.info() != Eigen::Success) continue;
    const Eigen::VectorXd z = llt.matrixL().solve(y);
    double logdet = 0;
    for (Eigen::Index j = 0; j < C.rows(); ++j) logdet += 2.0 * std::log(llt.matrixL()(j, j));
    const double e = -0.5 * (z.squaredNorm() + logdet);
    if (e > best) {
      best = e;
      best_k = k;
    }
  }
  return best_k;
}

CalibrationOptions evidencePrior(const MachineModel& model, const BallbarTest& test,
                                 const CalibrationResult& free_fit, CalibrationOptions options,
                                 double* scale) {
  const double k = choosePriorScale(model, test, free_fit, kPriorUnitLinear, kPriorUnitAngular);
  options.prior_linear = k * kPriorUnitLinear;
  options.prior_angular = k * kPriorUnitAngular;
  options.prior_noise = std::max(free_fit.residual_sigma, 1e-12);
  if (scale) *scale = k;
  return options;
}

}  // namespace tolver
