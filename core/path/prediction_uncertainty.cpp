#include "core/path/prediction_uncertainty.h"

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/kinematics/sensitivity_jacobian.h"
#include "core/numerics/statistics.h"

namespace tolver {

PredictionUncertainty::PredictionUncertainty(const Machine& machine)
    : machine_(machine), fk_(machine.model, machine.params) {
  const IdentificationUncertainty& id = machine.identification;
  if (id.empty())
    throw std::invalid_argument("PredictionUncertainty: the machine has no covariance");
  // A square root that tolerates a semi-definite covariance.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(id.covariance);
  const Eigen::VectorXd d = es.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  root_ = es.eigenvectors() * d.asDiagonal();
  J_.resize(6, machine.model.parameterCount());
  for (const ParameterBlock& b : machine.model.blocks) {
    if (b.kind == BlockKind::WorkpieceSetup)
      for (int c = 0; c < 6; ++c) setup_.push_back(b.offset + c);  // the part's pose
    if (b.kind == BlockKind::ToolSetup)
      for (int c = 0; c < 3; ++c) setup_.push_back(b.offset + c);  // the tool tip's offset
  }
}

Eigen::MatrixXd PredictionUncertainty::tipColumns(const JointVector& q,
                                                  const std::vector<int>& columns) const {
  J_.setZero();
  sensitivityJacobian(fk_, q, J_, nullptr);
  const Eigen::Matrix3d R = fk_.w_T_t(q).linear();
  Eigen::MatrixXd out(3, columns.size());
  for (size_t k = 0; k < columns.size(); ++k) out.col(k) = R * J_.block<3, 1>(0, columns[k]);
  return out;
}

void PredictionUncertainty::setupModulo(const std::vector<JointVector>& poses) {
  const std::vector<int>& id = machine_.identification.parameters;
  if (setup_.empty() || poses.empty()) return;
  Eigen::MatrixXd S(3 * poses.size(), setup_.size()), J(3 * poses.size(), id.size());
  for (size_t i = 0; i < poses.size(); ++i) {
    S.middleRows(3 * i, 3) = tipColumns(poses[i], setup_);
    J.middleRows(3 * i, 3) = tipColumns(poses[i], id);
  }
  B_ = S.completeOrthogonalDecomposition().solve(J);
  modulo_columns_ = setup_;
  modulo_ = true;
}

void PredictionUncertainty::setupModuloProbed(const std::vector<ProbedPoint>& points) {
  Eigen::VectorXd scale;
  const std::vector<int> part = probedSetupColumns(machine_.model, &scale, hasTram(points));
  if (part.empty() || points.empty()) return;
  Eigen::MatrixXd P, J;
  probedRows(machine_, points, part, &P);
  probedRows(machine_, points, machine_.identification.parameters, &J);
  // The same scaling and rank rule as fitProbedSetup: unobserved set-up directions stay fixed.
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(P * scale.cwiseInverse().asDiagonal(),
                                        Eigen::ComputeThinU | Eigen::ComputeThinV);
  svd.setThreshold(1e-6);
  B_ = scale.cwiseInverse().asDiagonal() * svd.solve(J);
  modulo_columns_ = part;
  modulo_ = true;
}

Eigen::VectorXd PredictionUncertainty::removeSetup(const std::vector<JointVector>& poses,
                                                   std::vector<Eigen::Vector3d>& d) const {
  Eigen::MatrixXd S(3 * poses.size(), setup_.size());
  Eigen::VectorXd y(3 * poses.size());
  std::vector<Eigen::MatrixXd> Si(poses.size());
  for (size_t i = 0; i < poses.size(); ++i) {
    Si[i] = tipColumns(poses[i], setup_);
    S.middleRows(3 * i, 3) = Si[i];
    y.segment<3>(3 * i) = d[i];
  }
  const Eigen::VectorXd beta = S.completeOrthogonalDecomposition().solve(y);
  for (size_t i = 0; i < poses.size(); ++i) d[i] -= Si[i] * beta;
  return beta;
}

Eigen::MatrixXd PredictionUncertainty::identifiedRows(const JointVector& q,
                                                      const MotionContext* ctx) const {
  const IdentificationUncertainty& id = machine_.identification;
  J_.setZero();
  sensitivityJacobian(fk_, q, J_, ctx);
  Eigen::MatrixXd Jid(6, id.parameters.size());
  for (size_t k = 0; k < id.parameters.size(); ++k) Jid.col(k) = J_.col(id.parameters[k]);
  if (modulo_) {  // the share a measured set-up leaves (twist rows in t)
    Eigen::MatrixXd Jm(6, modulo_columns_.size());
    for (size_t k = 0; k < modulo_columns_.size(); ++k) Jm.col(k) = J_.col(modulo_columns_[k]);
    Jid -= Jm * B_;
  }
  return Jid;
}

PoseUncertainty PredictionUncertainty::at(const JointVector& q, const MotionContext* ctx) const {
  const IdentificationUncertainty& id = machine_.identification;
  const Eigen::MatrixXd A = identifiedRows(q, ctx) * root_;
  const Eigen::Matrix<double, 6, 6> S = A * A.transpose();
  const Eigen::Matrix3d R = fk_.w_T_t(q, ctx).linear();
  PoseUncertainty u;
  u.tip_covariance_w = R * S.topLeftCorner<3, 3>() * R.transpose();
  u.calibration_tip = std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(
                                                  u.tip_covariance_w, Eigen::EigenvaluesOnly)
                                                  .eigenvalues()[2]));
  // What the covariance does not hold: the model's lack of fit (each coordinate), the spindle's
  // tilt (the tool axis, each direction across it).
  u.tip_covariance_w.diagonal().array() += id.lack_of_fit_mm * id.lack_of_fit_mm;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> tip(u.tip_covariance_w,
                                                           Eigen::EigenvaluesOnly);
  u.tip = std::sqrt(std::max(0.0, tip.eigenvalues()[2]));
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> ax(S.block<2, 2>(3, 3),
                                                          Eigen::EigenvaluesOnly);
  u.calibration_axis = std::sqrt(std::max(0.0, ax.eigenvalues()[1]));
  u.axis = std::sqrt(u.calibration_axis * u.calibration_axis +
                     id.spindle_tilt_rad * id.spindle_tilt_rad);
  u.axis_covariance_t << S(4, 4), -S(4, 3), -S(3, 4), S(3, 3);
  u.axis_covariance_t.diagonal().array() += id.spindle_tilt_rad * id.spindle_tilt_rad;
  u.axis_w = R.col(2);
  u.rotation_covariance_w = R * S.bottomRightCorner<3, 3>() * R.transpose() +
                            id.spindle_tilt_rad * id.spindle_tilt_rad *
                                (Eigen::Matrix3d::Identity() - u.axis_w * u.axis_w.transpose());
  u.tip_rotation_covariance_w = R * S.topRightCorner<3, 3>() * R.transpose();
  if (!id.covered_min.empty()) {
    u.beyond = JointVector::Zero(q.size());
    for (Eigen::Index a = 0; a < q.size() && a < static_cast<Eigen::Index>(id.covered_min.size());
         ++a) {
      const double b = std::max(id.covered_min[a] - q[a], q[a] - id.covered_max[a]);
      if (b > 1e-9) {
        u.beyond[a] = b;
        u.outside = true;
      }
    }
  }
  return u;
}

Eigen::RowVectorXd PredictionUncertainty::alongRoot(const JointVector& q,
                                                    const Eigen::Vector3d& n_w) const {
  const Eigen::Vector3d n_t = fk_.w_T_t(q).linear().transpose() * n_w;
  return n_t.transpose() * identifiedRows(q, nullptr).topRows<3>() * root_;
}

double PredictionUncertainty::alongContact(const PoseUncertainty& u, const Eigen::Vector3d& n_w,
                                           const Eigen::Vector3d& r_w) {
  Eigen::Vector3d m = r_w.cross(n_w);
  m -= m.dot(u.axis_w) * u.axis_w;
  const double v = n_w.dot(u.tip_covariance_w * n_w) +
                   2.0 * n_w.dot(u.tip_rotation_covariance_w * m) +
                   m.dot(u.rotation_covariance_w * m);
  return std::sqrt(std::max(0.0, v));
}

double PredictionUncertainty::tipRadius95(const PoseUncertainty& u) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(u.tip_covariance_w,
                                                          Eigen::EigenvaluesOnly);
  return gaussianRadiusQuantile(es.eigenvalues().data(), 3, 0.95);
}

double PredictionUncertainty::axisRadius95(const PoseUncertainty& u) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(u.axis_covariance_t,
                                                          Eigen::EigenvaluesOnly);
  return gaussianRadiusQuantile(es.eigenvalues().data(), 2, 0.95);
}

Eigen::VectorXd applyMeasuredSetup(Machine& machine, const std::vector<JointVector>& q,
                                   const std::vector<Eigen::Vector3d>& deviations_w,
                                   size_t max_poses) {
  std::vector<JointVector> sub;
  std::vector<Eigen::Vector3d> d;
  const size_t step = std::max<size_t>(1, q.size() / std::max<size_t>(1, max_poses));
  for (size_t i = 0; i < q.size(); i += step) {
    sub.push_back(q[i]);
    d.push_back(deviations_w[i]);
  }
  const PredictionUncertainty pu(machine);
  const Eigen::VectorXd beta = pu.removeSetup(sub, d);
  const std::vector<int> setup = pu.setupParameters();
  for (size_t k = 0; k < setup.size(); ++k) machine.params[setup[k]] -= beta[k];
  return beta;
}

}  // namespace tolver
