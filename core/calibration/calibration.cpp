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
                       const CalibrationOptions& opt, CalibrationResult& res,
                       std::vector<int>* keep_cols) {
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
    res.message =
        std::to_string(res.held.size()) + " parameters cannot be identified from these readings";
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
                               const Eigen::VectorXd& scale, const std::vector<int>& keep_cols,
                               int np_all, int np, CalibrationResult& res) {
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

// Step 2 of calibrate: Gauss-Newton with the pseudo-inverse of the column-scaled Jacobian A
// (prior rows included). Two factorisations, chosen at the first pass:
//  * normal equations, N = A^T A by Cholesky, when N's eigenvalues give kappa(A)^2 below
//    kNormalConditionMax (kappa below 1e5): the usual case, the unknowns having been reduced
//    to a full-rank set (step 1); a step's relative error is then at most about
//    eps kappa^2 = 2e-6, and the residuals are evaluated exactly at every pass, so the
//    iteration reaches the same fixed point, J^T r = 0;
//  * otherwise Householder J = QR, the step R^-1 Q^T r when R has full rank (its singular
//    values decide, by bidiagonalisation), the rank-truncated pseudo-inverse by the SVD of R
//    otherwise.
// The last factorisation also gives the covariance.
class GaussNewton {
 public:
  GaussNewton(const MachineModel& model, const BallbarTest& test,
              const std::vector<int>& unknown_params, const std::vector<int>& keep_cols,
              const std::vector<int>& unknowns, const CalibrationOptions& opt,
              CalibrationResult& res)
      : model_(model),
        test_(test),
        unknown_params_(unknown_params),
        keep_cols_(keep_cols),
        unknowns_(unknowns),
        opt_(opt),
        res_(res),
        np_all_(static_cast<int>(unknown_params.size())),
        np_(static_cast<int>(unknowns.size())),
        n_(static_cast<int>(keep_cols.size())),
        m_(static_cast<int>(test.readings.size())),
        regularised_(opt.prior_linear > 0 && opt.prior_angular > 0),
        mp_(regularised_ ? m_ + np_ : m_),
        normal_(opt.normal_equations) {
    // Prior rows (regularisation towards zero): w_k = s / sigma_k on each machine parameter.
    w_ = Eigen::VectorXd::Zero(np_);
    if (regularised_)
      for (int k = 0; k < np_; ++k)
        w_[k] = opt.prior_noise /
                (model.parameters[unknowns[k]].angular ? opt.prior_angular : opt.prior_linear);
  }

  // Iterates from the linearisation (r, J0) at the prior; returns the scaled covariance of the
  // last factorisation.
  Eigen::MatrixXd run(Eigen::VectorXd& r, const Eigen::MatrixXd& J0) {
    J_.resize(m_, n_);
    for (int k = 0; k < n_; ++k) J_.col(k) = J0.col(keep_cols_[k]);
    res_.status = CalibrationStatus::NotConverged;
    double previous_step = std::numeric_limits<double>::infinity();
    for (int it = 0; it < opt_.max_iterations; ++it) {
      Eigen::VectorXd step_s;
      double reducible2 = 0.0;  // |the part of r a step can remove|^2
      double r2 = 0.0;          // |r_a|^2
      if (normal_) normal_ = normalStep(r, it, &step_s, &reducible2, &r2);
      if (!normal_) qrStep(r, &step_s, &reducible2, &r2);
      // The step's size in column-scaled units, against what no step can remove: the
      // least-squares residual of the linearised problem.
      const double sn = step_s.norm();
      const double irreducible = std::sqrt(std::max(0.0, r2 - reducible2));
      const bool done = sn < opt_.step_tolerance || sn < opt_.relative_tolerance * irreducible ||
                        (sn < opt_.floor_tolerance && sn > 0.5 * previous_step);
      previous_step = sn;
      if (done) {
        res_.status = CalibrationStatus::Converged;
        res_.iterations = it;
        break;
      }
      apply(step_s.cwiseQuotient(scale_));
      res_.iterations = it + 1;
      Eigen::MatrixXd Jall;
      linearise(model_, res_.params, test_, res_.ball_errors, unknown_params_, &r, &Jall);
      for (int k = 0; k < n_; ++k) J_.col(k) = Jall.col(keep_cols_[k]);
    }
    if (!normal_) return scaledCovariance(R_, res_.rank);
    // The condition at the last factorisation, reported; the covariance N^-1.
    res_.condition = std::sqrt(normalConditionSquared(N_));
    return llt_.solve(Eigen::MatrixXd::Identity(n_, n_));
  }

  const Eigen::VectorXd& scale() const { return scale_; }

 private:
  static constexpr double kNormalConditionMax = 1e10;  // of N = A^T A

  // N, g and |r_a|^2 at the current point (N and g column-scaled); false when a column is zero.
  bool normalEquations(const Eigen::VectorXd& r) {
    N_.setZero(n_, n_);
    N_.selfadjointView<Eigen::Lower>().rankUpdate(J_.transpose());
    g_ = J_.transpose() * r;
    ra2_ = r.squaredNorm();
    for (int k = 0; k < np_ && regularised_; ++k) {
      const double rk = -w_[k] * res_.params[unknowns_[k]];
      N_(k, k) += w_[k] * w_[k];
      g_[k] += w_[k] * rk;
      ra2_ += rk * rk;
    }
    if (!scaleNormalMatrix(N_, &scale_)) return false;
    g_ = g_.cwiseQuotient(scale_);
    return true;
  }

  // The step by the normal equations; false when they are not to be used (a zero column, a
  // condition above kNormalConditionMax at the first pass, Cholesky failing).
  bool normalStep(const Eigen::VectorXd& r, int it, Eigen::VectorXd* step_s, double* reducible2,
                  double* r2) {
    bool ok = normalEquations(r);
    if (ok && it == 0) ok = normalConditionSquared(N_) < kNormalConditionMax;
    if (ok) llt_.compute(N_);
    if (!ok || llt_.info() != Eigen::Success) return false;
    *step_s = llt_.solve(g_);
    *reducible2 = g_.dot(*step_s);
    *r2 = ra2_;
    res_.rank = n_;
    return true;
  }

  // The step by Householder QR of the column-scaled augmented Jacobian (the SVD of R when it
  // has not full rank).
  void qrStep(const Eigen::VectorXd& r, Eigen::VectorXd* step_s, double* reducible2, double* r2) {
    Eigen::MatrixXd Ja;
    Eigen::VectorXd ra;
    augmented(r, &Ja, &ra);
    Eigen::HouseholderQR<Eigen::MatrixXd> qr(scaleColumns(Ja, &scale_));
    R_ = qr.matrixQR().topRows(n_).triangularView<Eigen::Upper>();
    const Eigen::VectorXd Qtr = (qr.householderQ().transpose() * ra).head(n_);
    const Eigen::VectorXd sv = summariseScaled(R_, mp_).singular_values;
    res_.rank = numericalRank(sv);
    res_.condition = sv[0] / sv[res_.rank - 1];
    if (res_.rank == n_) {
      *step_s = R_.triangularView<Eigen::Upper>().solve(Qtr);
      *reducible2 = Qtr.squaredNorm();
    } else {
      const Eigen::JacobiSVD<Eigen::MatrixXd> svd(R_, Eigen::ComputeFullU | Eigen::ComputeFullV);
      Eigen::VectorXd inv = Eigen::VectorXd::Zero(n_);
      for (int k = 0; k < res_.rank; ++k) inv[k] = 1.0 / svd.singularValues()[k];
      const Eigen::VectorXd Utr = svd.matrixU().transpose() * Qtr;
      *step_s = svd.matrixV() * inv.asDiagonal() * Utr;
      *reducible2 = Utr.head(res_.rank).squaredNorm();
    }
    *r2 = ra.squaredNorm();
  }

  // The Jacobian and residuals with the prior rows below them.
  void augmented(const Eigen::VectorXd& r, Eigen::MatrixXd* Ja, Eigen::VectorXd* ra) const {
    Ja->setZero(mp_, n_);
    ra->resize(mp_);
    Ja->topRows(m_) = J_;
    ra->head(m_) = r;
    if (regularised_)
      for (int k = 0; k < np_; ++k) {
        (*Ja)(m_ + k, k) = w_[k];
        (*ra)[m_ + k] = -w_[k] * res_.params[unknowns_[k]];
      }
  }

  // The step added to the machine parameters and the ball positions.
  void apply(const Eigen::VectorXd& step) {
    for (int k = 0; k < np_; ++k) res_.params[unknowns_[k]] += step[k];
    for (int k = np_; k < n_; ++k) {
      const int c = keep_cols_[k] - np_all_;  // ball column: set-up, table/tool, xyz
      BallErrors& b = res_.ball_errors[c / 6];
      (c % 6 < 3 ? b.table_w : b.tool_t)[c % 3] += step[k];
    }
  }

  const MachineModel& model_;
  const BallbarTest& test_;
  const std::vector<int>& unknown_params_;
  const std::vector<int>& keep_cols_;
  const std::vector<int>& unknowns_;
  const CalibrationOptions& opt_;
  CalibrationResult& res_;
  const int np_all_, np_, n_, m_;
  const bool regularised_;
  const int mp_;
  bool normal_;  // the normal-equations path
  Eigen::VectorXd w_;
  Eigen::MatrixXd J_, N_, R_;
  Eigen::VectorXd g_, scale_;  // g = A^T r_a, scaled
  double ra2_ = 0.0;           // |r_a|^2
  Eigen::LLT<Eigen::MatrixXd> llt_;
};

}  // namespace

// [AM01] 3.7: which unknowns the readings can see, Gauss-Newton, residuals and uncertainties.
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
  const int n = static_cast<int>(keep_cols.size());
  res.unknowns = n;
  if (static_cast<int>(test.readings.size()) <= n) {
    res.status = CalibrationStatus::Unobservable;
    res.message = "fewer readings than unknowns";
    return res;
  }
  // 2. Gauss-Newton.
  GaussNewton gn(model, test, unknown_params, keep_cols, unknowns, opt, res);
  const Eigen::MatrixXd C = gn.run(r, J0);
  // 3. Residuals and uncertainties from the last factorisation.
  residualsAndUncertainties(r, C, gn.scale(), keep_cols, np_all, static_cast<int>(unknowns.size()),
                            res);
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
  const Eigen::MatrixXd R =
      m >= n ? Eigen::MatrixXd(qr.matrixQR().topRows(n).triangularView<Eigen::Upper>()) : J;
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
    if (!isSetupParameter(model, p) &&
        std::find(unknowns.begin(), unknowns.end(), p) == unknowns.end())
      removed.push_back(p);
  return absorbedParameters(model, randomPoses(model, poses, seed), unknowns, removed);
}

IdentificationUncertainty identificationUncertainty(const CalibrationResult& fit,
                                                    const BallbarTest& test, int axes) {
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

PriorScaleEvidence priorScaleEvidence(const Eigen::MatrixXd& A, const Eigen::VectorXd& d,
                                      const Eigen::VectorXd& y, double s2) {
  // C = s^2 I + k^2 B B^T, B = A D^(1/2) = U S V^T (thin): C's eigenvalues are s^2 + k^2 S_j^2 on
  // U's columns and s^2 on their complement, so the log evidence costs O(np) per k after one
  // thin SVD (O(m np^2)) instead of a Cholesky of the m x m C (O(m^3)) per k.
  PriorScaleEvidence e;
  const Eigen::Index m = A.rows();
  e.d_root = d.cwiseMax(0.0).cwiseSqrt();
  e.s2 = s2;
  const Eigen::MatrixXd B = A * e.d_root.asDiagonal();
  // JacobiSVD (QR-preconditioned), not BDCSVD: Eigen 3.4.0's BDCSVD reads out of bounds
  // (docs/validation.md).
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(B, Eigen::ComputeThinU | Eigen::ComputeThinV);
  e.S2 = svd.singularValues().cwiseAbs2();
  e.V = svd.matrixV();
  e.c = svd.matrixU().transpose() * y;
  const double rest = std::max(0.0, y.squaredNorm() - e.c.squaredNorm());
  const Eigen::Index r = e.S2.size();
  if (!(s2 > 0.0)) return e;
  double best = -std::numeric_limits<double>::infinity();
  for (int i = 0; i <= 40; ++i) {
    const double k = 0.03 * std::pow(100.0 / 0.03, i / 40.0);
    double quad = rest / s2, logdet = static_cast<double>(m - r) * std::log(s2);
    for (Eigen::Index j = 0; j < r; ++j) {
      const double l = s2 + k * k * e.S2[j];
      quad += e.c[j] * e.c[j] / l;
      logdet += std::log(l);
    }
    const double le = -0.5 * (quad + logdet);
    e.grid_k.push_back(k);
    e.log_evidence.push_back(le);
    if (le > best) {
      best = le;
      e.k = k;
    }
  }
  return e;
}

double evidenceScale(const Eigen::MatrixXd& A, const Eigen::VectorXd& d, const Eigen::VectorXd& y,
                     double s2) {
  return priorScaleEvidence(A, d, y, s2).k;
}

Eigen::MatrixXd PriorScaleEvidence::inflation() const {
  const Eigen::Index np = d_root.size();
  if (grid_k.empty() || np == 0 || !(s2 > 0.0)) return Eigen::MatrixXd::Identity(np, np);
  const double top = *std::max_element(log_evidence.begin(), log_evidence.end());
  std::vector<double> w(grid_k.size());
  double sum = 0;
  for (size_t i = 0; i < w.size(); ++i) sum += (w[i] = std::exp(log_evidence[i] - top));
  // Whitened coordinates phi = D^(-1/2) theta in V's basis, completed when V is not square (the
  // complement has no reading: precision 1 / k^2, mean 0).
  const Eigen::Index r = S2.size();
  Eigen::MatrixXd Vfull = V;
  if (r < np) {
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(V);
    Vfull = qr.householderQ() * Eigen::MatrixXd::Identity(np, np);
    Vfull.leftCols(r) = V;
  }
  Eigen::VectorXd S2full = Eigen::VectorXd::Zero(np), cfull = Eigen::VectorXd::Zero(np);
  S2full.head(r) = S2;
  cfull.head(r) = c;
  const auto precision = [&](double kk) { return (S2full / s2).array() + 1.0 / (kk * kk); };
  const Eigen::ArrayXd prec_best = precision(k);
  const Eigen::ArrayXd mean_best = S2full.cwiseSqrt().array() * cfull.array() / s2 / prec_best;
  // M: the mixture's second moment about the chosen k's mean (V's basis).
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(np, np);
  for (size_t i = 0; i < w.size(); ++i) {
    const Eigen::ArrayXd prec = precision(grid_k[i]);
    const Eigen::VectorXd dm =
        (S2full.cwiseSqrt().array() * cfull.array() / s2 / prec - mean_best).matrix();
    M.diagonal() += (w[i] / sum) * prec.inverse().matrix();
    M += (w[i] / sum) * dm * dm.transpose();
  }
  // T = D^(1/2) V L P*^(1/2) V^T D^(-1/2), L L^T = M: T Sigma* T^T = D^(1/2) V M V^T D^(1/2).
  const Eigen::LLT<Eigen::MatrixXd> llt(M);
  if (llt.info() != Eigen::Success) return Eigen::MatrixXd::Identity(np, np);
  const Eigen::MatrixXd L = llt.matrixL();
  const Eigen::VectorXd p_root = prec_best.sqrt().matrix();
  const Eigen::MatrixXd G = L * p_root.asDiagonal();
  const Eigen::VectorXd inv_root =
      d_root.unaryExpr([](double x) { return x > 0.0 ? 1.0 / x : 0.0; });
  return d_root.asDiagonal() * Vfull * G * Vfull.transpose() * inv_root.asDiagonal();
}

PriorScaleEvidence priorScaleEvidence(const MachineModel& model, const BallbarTest& test,
                                      const CalibrationResult& fit, double unit_linear,
                                      double unit_angular) {
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
  // Project off the ball columns (flat prior): Q^T applied as Householder reflections, its last
  // m - nb rows the complement of their span.
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(J.rightCols(nb));
  Eigen::MatrixXd Ay(m, np + 1);
  Ay.leftCols(np) = J.leftCols(np);
  Ay.col(np) = r + J.leftCols(np) * theta;
  Ay.applyOnTheLeft(qr.householderQ().transpose());
  return priorScaleEvidence(Ay.bottomLeftCorner(m - nb, np), d, Ay.col(np).tail(m - nb),
                            fit.residual_sigma * fit.residual_sigma);
}

double choosePriorScale(const MachineModel& model, const BallbarTest& test,
                        const CalibrationResult& fit, double unit_linear, double unit_angular) {
  return priorScaleEvidence(model, test, fit, unit_linear, unit_angular).k;
}

CalibrationOptions evidencePrior(const MachineModel& model, const BallbarTest& test,
                                 const CalibrationResult& free_fit, CalibrationOptions options,
                                 double* scale, PriorScaleEvidence* evidence) {
  PriorScaleEvidence e =
      priorScaleEvidence(model, test, free_fit, kPriorUnitLinear, kPriorUnitAngular);
  const double k = e.k;
  if (evidence) *evidence = std::move(e);
  options.prior_linear = k * kPriorUnitLinear;
  options.prior_angular = k * kPriorUnitAngular;
  options.prior_noise = std::max(free_fit.residual_sigma, 1e-12);
  if (scale) *scale = k;
  return options;
}

bool marginalisePriorScale(const PriorScaleEvidence& evidence,
                           const std::vector<int>& free_identified, CalibrationResult* fit) {
  if (fit->identified != free_identified || evidence.d_root.size() != fit->covariance.rows())
    return false;
  const Eigen::MatrixXd T = evidence.inflation();
  fit->covariance = T * fit->covariance * T.transpose();
  fit->covariance = 0.5 * (fit->covariance + fit->covariance.transpose()).eval();
  fit->uncertainty = fit->covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  return true;
}

}  // namespace tolver
