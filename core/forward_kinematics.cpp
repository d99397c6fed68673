#include "core/forward_kinematics.h"

#include <algorithm>
#include <cassert>

#include "core/chebyshev.h"

namespace tolver {

ForwardKinematics::ForwardKinematics(const MachineModel& model, const Eigen::VectorXd& params)
    : model_(&model), params_(params), axis_(model.axes.size()) {
  assert(params.size() == model.parameterCount());
  for (size_t a = 0; a < axis_.size(); ++a) {
    axis_[a].fixed = model.axes[a].parent_T_joint;
    axis_[a].offset.fill(-1);
    axis_[a].degree.fill(-1);
  }
  table_T_w_err_ = model.table_T_w();
  spindle_T_t_err_ = model.spindle_T_t();
  for (const ParameterBlock& b : model.blocks) {
    const Vector6d six = b.size == 6 ? Vector6d(params.segment<6>(b.offset)) : Vector6d::Zero();
    switch (b.kind) {
      case BlockKind::LinkError:
        axis_[b.axis].fixed = axis_[b.axis].fixed * linkTransform(six);
        break;
      case BlockKind::MotionError: {
        AxisTerms& t = axis_[b.axis];
        t.offset[b.component] = b.offset;
        t.degree[b.component] = b.degree;
        t.max_degree = std::max(t.max_degree, b.degree);
        break;
      }
      case BlockKind::WorkpieceSetup:
        table_T_w_err_ = table_T_w_err_ * linkTransform(six);
        break;
      case BlockKind::ToolSetup:
        spindle_T_t_err_ = spindle_T_t_err_ * linkTransform(six);
        break;
    }
  }
}

Vector6d ForwardKinematics::motionErrors(int a, double s) const {
  const AxisTerms& t = axis_[a];
  Vector6d e = Vector6d::Zero();
  if (t.max_degree < 0) return e;
  const Axis& ax = model_->axes[a];
  const double x = normalisedCoordinate(s, ax.travel_min, ax.travel_max);
  constexpr int kMaxDegree = 31;
  double T[kMaxDegree + 1];
  chebyshevBasis(x, std::min(t.max_degree, kMaxDegree), T);
  for (int c = 0; c < 6; ++c) {
    if (t.offset[c] < 0) continue;
    const double* coef = params_.data() + t.offset[c];
    double v = 0.0;
    for (int k = 0; k <= t.degree[c]; ++k) v += coef[k] * T[k];
    e[c] = v;
  }
  return e;
}

Eigen::Isometry3d ForwardKinematics::jointTransform(int a, double s) const {
  const Axis& ax = model_->axes[a];
  const AxisTerms& t = axis_[a];
  Eigen::Isometry3d D = t.fixed;
  if (ax.type == JointType::Prismatic) {
    D.translation() += D.linear() * (ax.direction * s);
  } else {
    D.linear() = D.linear() * Eigen::AngleAxisd(s, ax.direction).toRotationMatrix();
  }
  if (t.max_degree >= 0) D = D * linkTransform(motionErrors(a, s));
  return D;
}

Eigen::Isometry3d ForwardKinematics::F_T_w(const JointVector& q) const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int a : model_->workpiece_chain) T = T * jointTransform(a, q[a]);
  return T * model_->last_T_table * table_T_w_err_;
}

Eigen::Isometry3d ForwardKinematics::F_T_t(const JointVector& q) const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int a : model_->tool_chain) T = T * jointTransform(a, q[a]);
  return T * model_->last_T_spindle * spindle_T_t_err_;
}

Eigen::Isometry3d ForwardKinematics::w_T_t(const JointVector& q) const {
  return F_T_w(q).inverse(Eigen::Isometry) * F_T_t(q);
}

}  // namespace tolver
