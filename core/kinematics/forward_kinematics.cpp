#include "core/kinematics/forward_kinematics.h"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "core/numerics/chebyshev.h"
#include "core/model/effects.h"

namespace tolver {

ForwardKinematics::ForwardKinematics(const MachineModel& model, const Eigen::VectorXd& params)
    : model_(&model), params_(params), axis_(model.axes.size()) {
  assert(params.size() == model.parameterCount());
  for (size_t a = 0; a < axis_.size(); ++a) {
    axis_[a].fixed = model.axes[a].parent_T_joint;
    axis_[a].offset.fill(-1);
    axis_[a].mid = 0.5 * (model.axes[a].travel_min + model.axes[a].travel_max);
    axis_[a].inv_half_range = 2.0 / (model.axes[a].travel_max - model.axes[a].travel_min);
    for (int k = 0; k < 3; ++k)
      if (model.axes[a].direction[k] == 1.0) axis_[a].principal = k;
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
      case BlockKind::Effect: {
        const EffectSpec& spec = model.effects[b.effect];
        if (spec.axis < 0) {  // the instrument
          bar_length_error_ += params[b.offset];
          break;
        }
        AxisTerms::Effect e{&spec, spec.component, b.size, {}};
        assert(b.size <= static_cast<int>(e.coef.size()));
        for (int k = 0; k < b.size; ++k) e.coef[k] = params[b.offset + k];
        axis_[spec.axis].effects.push_back(e);
        break;
      }
    }
  }
  for (AxisTerms& t : axis_) {
    t.fixed_R = t.fixed.linear();
    t.fixed_Rt = t.fixed_R.transpose();
    t.fixed_p = t.fixed.translation();
    t.fixed_identity = t.fixed.isApprox(Eigen::Isometry3d::Identity(), 0.0);
    t.has_errors = t.max_degree >= 0 || !t.effects.empty();
    t.coef = Eigen::Matrix<double, 6, Eigen::Dynamic>::Zero(6, std::max(t.max_degree + 1, 1));
    for (int c = 0; c < 6; ++c)
      for (int k = 0; k <= t.degree[c]; ++k) t.coef(c, k) = params[t.offset[c] + k];
  }
  w_end_ = model.last_T_table * table_T_w_err_;
  t_end_ = model.last_T_spindle * spindle_T_t_err_;
}

Vector6d ForwardKinematics::motionErrors(int a, double s, const MotionContext* ctx) const {
  const AxisTerms& t = axis_[a];
  if (!t.has_errors) return Vector6d::Zero();
  const double x = (s - t.mid) * t.inv_half_range;  // eq. 58
  if (!t.effects.empty()) return motionErrorsWithEffects(t, s, x, ctx);
  // e = sum_k C_k T_k(x), the six components at once, T_k by the recurrence of eq. 57 (the
  // default cubic written out).
  const auto C = [&](int k) { return t.coef.col(k); };
  switch (t.max_degree) {
    case 0:
      return C(0);
    case 1:
      return C(0) + x * C(1);
    case 2:
      return C(0) + x * C(1) + (2.0 * x * x - 1.0) * C(2);
    case 3: {
      const double t2 = 2.0 * x * x - 1.0;
      return C(0) + x * C(1) + t2 * C(2) + (2.0 * x * t2 - x) * C(3);
    }
    default: {
      Vector6d e = C(0) + x * C(1);
      double t_prev = 1.0, t_cur = x;
      for (int k = 2; k <= t.max_degree; ++k) {
        const double t_next = 2.0 * x * t_cur - t_prev;
        e += t_next * C(k);
        t_prev = t_cur;
        t_cur = t_next;
      }
      return e;
    }
  }
}

Vector6d ForwardKinematics::motionErrorsWithEffects(const AxisTerms& t, double s, double x,
                                                    const MotionContext* ctx) const {
  Vector6d e = Vector6d::Zero();
  if (t.max_degree >= 0) {
    double T[32];
    chebyshevBasis(x, t.max_degree, T);
    for (int k = 0; k <= t.max_degree; ++k) e += T[k] * t.coef.col(k);
  }
  for (const AxisTerms::Effect& f : t.effects) {
    double phi[8];
    traitsOf(f.spec->type).basis(*f.spec, s, x, ctx, phi);
    for (int k = 0; k < f.size; ++k) e[f.component] += f.coef[k] * phi[k];
  }
  return e;
}

void ForwardKinematics::composeJoint(int a, double s, Pose& T, const MotionContext* ctx) const {
  const Axis& ax = model_->axes[a];
  const AxisTerms& t = axis_[a];
  // T * fixed
  T.p += T.R * t.fixed.translation();
  T.R = T.R * t.fixed.linear();
  // * D2(s): nominal motion
  if (ax.type == JointType::Prismatic) {
    T.p += T.R * (ax.direction * s);
  } else if (t.principal >= 0) {
    // Rotation about a coordinate axis: only the two other columns of R change.
    const int i = (t.principal + 1) % 3, j = (t.principal + 2) % 3;
    const double c = std::cos(s), sn = std::sin(s);
    const Eigen::Vector3d ci = T.R.col(i), cj = T.R.col(j);
    T.R.col(i) = c * ci + sn * cj;
    T.R.col(j) = c * cj - sn * ci;
  } else {
    T.R = T.R * Eigen::AngleAxisd(s, ax.direction).toRotationMatrix();
  }
  // * E(s): motion errors
  if (t.has_errors) {
    const Vector6d e = motionErrors(a, s, ctx);
    T.p += T.R * e.head<3>();
    T.R = T.R * rotationZYX(e[3], e[4], e[5]);
  }
}

ForwardKinematics::Pose ForwardKinematics::chain(const std::vector<int>& axes,
                                                 const JointVector& q,
                                                 const MotionContext* ctx) const {
  Pose T{Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero()};
  for (int a : axes) composeJoint(a, q[a], T, ctx);
  return T;
}

Eigen::Isometry3d ForwardKinematics::jointTransform(int a, double s) const {
  Pose T{Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero()};
  composeJoint(a, s, T, nullptr);
  Eigen::Isometry3d D = Eigen::Isometry3d::Identity();
  D.linear() = T.R;
  D.translation() = T.p;
  return D;
}

Eigen::Isometry3d ForwardKinematics::F_T_w(const JointVector& q) const {
  const Pose T = chain(model_->workpiece_chain, q, nullptr);
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = T.R * w_end_.linear();
  out.translation() = T.p + T.R * w_end_.translation();
  return out;
}

Eigen::Isometry3d ForwardKinematics::F_T_t(const JointVector& q) const {
  const Pose T = chain(model_->tool_chain, q, nullptr);
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = T.R * t_end_.linear();
  out.translation() = T.p + T.R * t_end_.translation();
  return out;
}

namespace {

// M <- Rz(rz) Ry(ry) Rx(rx) M (eq. 22's rotation) for the error angles of e, or its transpose.
inline void rotateZYX(const Vector6d& e, bool inverse, ForwardKinematics::Carry& M) {
  double c[3], s[3];
  for (int k = 0; k < 3; ++k) sinCosOfSmallAngle(e[3 + k], &s[k], &c[k]);
  if (!inverse) {
    rotateRowsAbout<0>(c[0], s[0], M);
    rotateRowsAbout<1>(c[1], s[1], M);
    rotateRowsAbout<2>(c[2], s[2], M);
  } else {
    rotateRowsAbout<2>(c[2], -s[2], M);
    rotateRowsAbout<1>(c[1], -s[1], M);
    rotateRowsAbout<0>(c[0], -s[0], M);
  }
}

}  // namespace

void ForwardKinematics::applyJoint(int a, double s, double c, double sn, Carry& M,
                                   const MotionContext* ctx) const {
  const Axis& ax = model_->axes[a];
  const AxisTerms& t = axis_[a];
  if (t.has_errors) {  // E(s)
    const Vector6d e = motionErrors(a, s, ctx);
    rotateZYX(e, false, M);
    M.col(0) += e.head<3>();
  }
  if (ax.type == JointType::Prismatic) {  // D2(s)
    M.col(0) += ax.direction * s;
  } else if (t.principal >= 0) {
    rotateRowsAbout(t.principal, c, sn, M);
  } else {
    M = Eigen::AngleAxisd(s, ax.direction).toRotationMatrix() * M;
  }
  if (!t.fixed_identity) {  // D1 L
    M = t.fixed_R * M;
    M.col(0) += t.fixed_p;
  }
}

void ForwardKinematics::applyJointInverse(int a, double s, double c, double sn, Carry& M,
                                          const MotionContext* ctx) const {
  const Axis& ax = model_->axes[a];
  const AxisTerms& t = axis_[a];
  if (!t.fixed_identity) {
    M.col(0) -= t.fixed_p;
    M = t.fixed_Rt * M;
  }
  if (ax.type == JointType::Prismatic) {
    M.col(0) -= ax.direction * s;
  } else if (t.principal >= 0) {
    rotateRowsAbout(t.principal, c, -sn, M);
  } else {
    M = Eigen::AngleAxisd(-s, ax.direction).toRotationMatrix() * M;
  }
  if (t.has_errors) {
    const Vector6d e = motionErrors(a, s, ctx);
    M.col(0) -= e.head<3>();
    rotateZYX(e, true, M);
  }
}

void ForwardKinematics::tipAndAxis(const JointVector& q, Eigen::Vector3d* p_w,
                                   Eigen::Vector3d* u_w, const double* cos_q,
                                   const double* sin_q, const MotionContext* ctx) const {
  auto trig = [&](int a, double* c, double* s) {
    if (!model_->axes[a].isRotary()) return;
    if (cos_q) {
      *c = cos_q[a];
      *s = sin_q[a];
    } else {
      *c = std::cos(q[a]);
      *s = std::sin(q[a]);
    }
  };
  double c = 1.0, s = 0.0;
  // F_p_t = D_1 ... D_m t_end 0: apply from the last tool joint back to the foundation.
  Carry M;
  M.col(0) = t_end_.translation();
  M.col(1) = t_end_.linear().col(2);
  const auto& tool = model_->tool_chain;
  for (auto it = tool.rbegin(); it != tool.rend(); ++it) {
    trig(*it, &c, &s);
    applyJoint(*it, q[*it], c, s, M, ctx);
  }
  // w_p = w_end^-1 D_n^-1 ... D_1^-1 F_p.
  for (int a : model_->workpiece_chain) {
    trig(a, &c, &s);
    applyJointInverse(a, q[a], c, s, M, ctx);
  }
  M.col(0) -= w_end_.translation();
  M = w_end_.linear().transpose() * M;
  *p_w = M.col(0);
  *u_w = M.col(1);
}

void ForwardKinematics::chainFrames(const JointVector& q, ChainFrames* out,
                                    const MotionContext* ctx) const {
  const size_t n = model_->axes.size();
  out->after_link.resize(n);
  out->after_joint.resize(n);
  for (int b = 0; b < 2; ++b) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    for (int a : b == 0 ? model_->workpiece_chain : model_->tool_chain) {
      T = T * axis_[a].fixed;
      out->after_link[a] = T;
      const Axis& ax = model_->axes[a];
      if (ax.type == JointType::Prismatic) {
        T.translation() += T.linear() * (ax.direction * q[a]);
      } else {
        T.linear() = T.linear() * Eigen::AngleAxisd(q[a], ax.direction).toRotationMatrix();
      }
      if (axis_[a].has_errors) T = T * linkTransform(motionErrors(a, q[a], ctx));
      out->after_joint[a] = T;
    }
    if (b == 0) out->F_T_w = T * w_end_;
    else out->F_T_t = T * t_end_;
  }
}

Eigen::Isometry3d ForwardKinematics::w_T_t(const JointVector& q, const MotionContext* ctx) const {
  const Pose W = chain(model_->workpiece_chain, q, ctx);
  const Pose T = chain(model_->tool_chain, q, ctx);
  // w_T_t = (W * w_end)^-1 * (T * t_end)
  const Eigen::Matrix3d Rw = W.R * w_end_.linear();
  const Eigen::Vector3d pw = W.p + W.R * w_end_.translation();
  const Eigen::Matrix3d Rt = T.R * t_end_.linear();
  const Eigen::Vector3d pt = T.p + T.R * t_end_.translation();
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Rw.transpose() * Rt;
  out.translation() = Rw.transpose() * (pt - pw);
  return out;
}

}  // namespace tolver
