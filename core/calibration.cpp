#include "core/calibration.h"

#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/identifiability.h"

namespace tolver {
namespace {

bool isSetupParameter(const MachineModel& m, int p) {
  const BlockKind k = m.blocks[m.parameters[p].block].kind;
  return k == BlockKind::WorkpieceSetup || k == BlockKind::ToolSetup;
}

// Residuals (measured - model) and the identification Jacobian over the unknowns:
// columns [params..., per set-up: table ball xyz, tool ball xyz].
void linearise(const MachineModel& m, const Eigen::VectorXd& params, const BallbarTest& test,
               const std::vector<BallErrors>& balls, const std::vector<int>& unknowns,
               Eigen::VectorXd* r, Eigen::MatrixXd* J) {
  const ForwardKinematics fk(m, params);
  const int np = static_cast<int>(unknowns.size());
  const int n = np + 6 * static_cast<int>(test.setups.size());
  r->resize(test.readings.size());
  J->setZero(test.readings.size(), n);
  Eigen::MatrixXd scratch(6, m.parameterCount());
  Eigen::RowVectorXd row(m.parameterCount());
  for (size_t i = 0; i < test.readings.size(); ++i) {
    const BallbarReading& rd = test.readings[i];
    const BallbarSetup& s = test.setups[rd.setup];
    Eigen::RowVector3d jt, jb;
    ballbarGradient(fk, rd.q, s, balls[rd.setup], row, &jt, &jb, scratch);
    for (int k = 0; k < np; ++k) (*J)(i, k) = row[unknowns[k]];
    J->block<1, 3>(i, np + 6 * rd.setup) = jt;
    J->block<1, 3>(i, np + 6 * rd.setup + 3) = jb;
    (*r)[i] = rd.length - ballbarLength(fk, rd.q, s, balls[rd.setup]);
  }
}

}  // namespace

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
  std::vector<int> unknowns = unknown_params;
  {
    Eigen::VectorXd r;
    Eigen::MatrixXd J;
    linearise(model, prior, test, res.ball_errors, unknowns, &r, &J);
    const int np = static_cast<int>(unknowns.size());
    std::vector<int> cols(J.cols());
    std::vector<bool> protect(J.cols(), false);
    for (int c = 0; c < J.cols(); ++c) {
      cols[c] = c;
      protect[c] = c >= np;
    }
    const MinimalSet ms = selectMinimalSet(J, cols, protect, {});
    for (int c : ms.removed) {
      if (c >= np) {
        res.status = CalibrationStatus::Unobservable;
        res.message = "the readings cannot see the ball positions of every set-up";
        return res;
      }
      res.held.push_back(unknowns[c]);
    }
    std::sort(res.held.begin(), res.held.end());
    if (!res.held.empty() && opt.strict) {
      res.status = CalibrationStatus::Unobservable;
      res.message = std::to_string(res.held.size()) + " parameters cannot be identified from these readings";
      return res;
    }
    std::vector<int> keep;
    for (int p : unknowns)
      if (!std::binary_search(res.held.begin(), res.held.end(), p)) keep.push_back(p);
    unknowns = keep;
  }
  res.identified = unknowns;
  const int np = static_cast<int>(unknowns.size());
  const int n = np + 6 * static_cast<int>(test.setups.size());
  res.unknowns = n;
  if (static_cast<int>(test.readings.size()) <= n) {
    res.status = CalibrationStatus::Unobservable;
    res.message = "fewer readings than unknowns";
    return res;
  }
  // 2. Gauss-Newton with the pseudo-inverse of the column-scaled Jacobian.
  Eigen::VectorXd r, scale;
  Eigen::MatrixXd J;
  Eigen::BDCSVD<Eigen::MatrixXd> svd;
  res.status = CalibrationStatus::NotConverged;
  double previous_step = std::numeric_limits<double>::infinity();
  for (int it = 0; it < opt.max_iterations; ++it) {
    linearise(model, res.params, test, res.ball_errors, unknowns, &r, &J);
    scale = J.colwise().norm().transpose();
    for (int c = 0; c < n; ++c)
      if (scale[c] == 0) scale[c] = 1;
    const Eigen::MatrixXd Js = J * scale.cwiseInverse().asDiagonal();
    // QR first: the SVD then works on an n x n triangle instead of m x n.
    Eigen::HouseholderQR<Eigen::MatrixXd> qr(Js);
    const Eigen::MatrixXd R = qr.matrixQR().topRows(n).triangularView<Eigen::Upper>();
    const Eigen::VectorXd Qtr = (qr.householderQ().transpose() * r).head(n);
    svd.compute(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::VectorXd& sv = svd.singularValues();
    res.rank = 0;
    for (int k = 0; k < sv.size(); ++k)
      if (sv[k] > kRankTolerance * sv[0]) ++res.rank;
    res.condition = sv[0] / sv[res.rank - 1];
    Eigen::VectorXd inv = Eigen::VectorXd::Zero(sv.size());
    for (int k = 0; k < res.rank; ++k) inv[k] = 1.0 / sv[k];
    const Eigen::VectorXd step_s =
        svd.matrixV() * (inv.asDiagonal() * (svd.matrixU().transpose() * Qtr));
    const Eigen::VectorXd step = step_s.cwiseQuotient(scale);
    for (int k = 0; k < np; ++k) res.params[unknowns[k]] += step[k];
    for (size_t s = 0; s < test.setups.size(); ++s) {
      res.ball_errors[s].table_w += step.segment<3>(np + 6 * s);
      res.ball_errors[s].tool_t += step.segment<3>(np + 6 * s + 3);
    }
    res.iterations = it + 1;
    // Scaled step: a change of the model readings, in mm, that the step would make at most.
    const double sn = step_s.norm();
    if (sn < opt.step_tolerance || (sn < opt.floor_tolerance && sn > 0.5 * previous_step)) {
      res.status = CalibrationStatus::Converged;
      break;
    }
    previous_step = sn;
  }
  // 3. Final residuals and uncertainties: cov = s^2 (J^T J)^-1.
  linearise(model, res.params, test, res.ball_errors, unknowns, &r, &J);
  res.residuals = r;
  const int m = static_cast<int>(r.size());
  res.rms_residual = std::sqrt(r.squaredNorm() / m);
  res.max_residual = r.cwiseAbs().maxCoeff();
  res.residual_sigma = std::sqrt(r.squaredNorm() / std::max(1, m - n));
  scale = J.colwise().norm().transpose();
  for (int c = 0; c < n; ++c)
    if (scale[c] == 0) scale[c] = 1;
  const Eigen::MatrixXd Js = J * scale.cwiseInverse().asDiagonal();
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(Js);
  const Eigen::MatrixXd R = qr.matrixQR().topRows(n).triangularView<Eigen::Upper>();
  svd.compute(R, Eigen::ComputeFullV);
  const Eigen::VectorXd& sv = svd.singularValues();
  Eigen::VectorXd inv2 = Eigen::VectorXd::Zero(sv.size());
  for (int k = 0; k < sv.size(); ++k)
    if (sv[k] > kRankTolerance * sv[0]) inv2[k] = 1.0 / (sv[k] * sv[k]);
  const Eigen::MatrixXd& V = svd.matrixV();
  // diag(V diag(inv2) V^T): with unit-norm columns this is the variance inflation factor.
  const Eigen::VectorXd vif = (V.array().square().matrix() * inv2);
  Eigen::VectorXd sd(n);
  for (int c = 0; c < n; ++c) sd[c] = res.residual_sigma * std::sqrt(vif[c]) / scale[c];
  res.uncertainty = sd.head(np);
  res.observability = vif.head(np).cwiseInverse().cwiseSqrt();
  for (size_t s = 0; s < test.setups.size(); ++s) {
    res.ball_uncertainty[s].table_w = sd.segment<3>(np + 6 * s);
    res.ball_uncertainty[s].tool_t = sd.segment<3>(np + 6 * s + 3);
  }
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

}  // namespace tolver
