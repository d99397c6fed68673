#include "core/kinematics/forward_kinematics.h"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "core/model/effects.h"
#include "core/model/rigid_transform.h"
#include "core/numerics/chebyshev.h"
#include "core/numerics/lanes.h"

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
    t.fixed_R_identity = t.fixed_R == Eigen::Matrix3d::Identity();
    t.has_errors = t.max_degree >= 0 || !t.effects.empty();
    t.coef = Eigen::Matrix<double, 6, Eigen::Dynamic>::Zero(6, std::max(t.max_degree + 1, 1));
    for (int c = 0; c < 6; ++c)
      for (int k = 0; k <= t.degree[c]; ++k) t.coef(c, k) = params[t.offset[c] + k];
  }
  batchable_ = true;
  for (size_t a = 0; a < axis_.size(); ++a)
    if (!axis_[a].effects.empty() || (model.axes[a].isRotary() && axis_[a].principal < 0))
      batchable_ = false;
  w_end_ = model.last_T_table * table_T_w_err_;
  w_end_Rt_ = w_end_.linear().transpose();
  t_end_ = model.last_T_spindle * spindle_T_t_err_;
}

Vector6d ForwardKinematics::motionErrors(int a, double s, const MotionContext* ctx) const {
  const AxisTerms& t = axis_[a];
  if (!t.has_errors) return Vector6d::Zero();
  if (!t.effects.empty()) {
    const double x = (s - t.mid) * t.inv_half_range;  // eq. 58
    return motionErrorsWithEffects(t, s, x, ctx);
  }
  Vector6d e;
  motionErrorsL(t, s, e.data());
  return e;
}

// e = sum_k C_k T_k(x) with x = s normalised by eq. 58, the six components, T_k by the
// recurrence of eq. 57 (the default cubic written out). Chebyshev terms only (no effects).
template <typename L>
TOLVER_LANE_INLINE void ForwardKinematics::motionErrorsL(const AxisTerms& t, L s, L e[6]) const {
  const L x = (s - t.mid) * t.inv_half_range;
  const double* C = t.coef.data();  // column-major 6 x (degree + 1): C[6 k + c]
  switch (t.max_degree) {
    case 0:
      for (int c = 0; c < 6; ++c) e[c] = lanes::splat<L>(C[c]);
      return;
    case 1:
      for (int c = 0; c < 6; ++c) e[c] = C[c] + x * C[6 + c];
      return;
    case 2: {
      const L t2 = 2.0 * x * x - 1.0;
      for (int c = 0; c < 6; ++c) e[c] = C[c] + x * C[6 + c] + t2 * C[12 + c];
      return;
    }
    case 3: {
      const L t2 = 2.0 * x * x - 1.0;
      const L t3 = 2.0 * x * t2 - x;
      for (int c = 0; c < 6; ++c) e[c] = C[c] + x * C[6 + c] + t2 * C[12 + c] + t3 * C[18 + c];
      return;
    }
    default: {
      for (int c = 0; c < 6; ++c) e[c] = C[c] + x * C[6 + c];
      L t_prev = lanes::splat<L>(1.0), t_cur = x;
      for (int k = 2; k <= t.max_degree; ++k) {
        const L t_next = 2.0 * x * t_cur - t_prev;
        for (int c = 0; c < 6; ++c) e[c] += t_next * C[6 * k + c];
        t_prev = t_cur;
        t_cur = t_next;
      }
      return;
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

ForwardKinematics::Pose ForwardKinematics::chain(const std::vector<int>& axes, const JointVector& q,
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

// sinCosOfSmallAngle of three angles over lanes: the same two series, chosen per lane; big: the
// lanes beyond them (|x| >= 1e-3 rad, or NaN), which the caller recomputes with the scalar form.
TOLVER_LANE_INLINE void sinCosSmall3(const double* x, double* s, double* c, bool*) {
  for (int k = 0; k < 3; ++k) sinCosOfSmallAngle(x[k], &s[k], &c[k]);
}
template <typename L, typename M>
TOLVER_LANE_INLINE void sinCosSmall3(const L* x, L* s, L* c, M* big) {
  constexpr double k6 = 1.0 / 6.0, k20 = 1.0 / 20.0, k12 = 1.0 / 12.0, k30 = 1.0 / 30.0;
  L x2[3];
  M short_form[3];
  for (int k = 0; k < 3; ++k) {
    x2[k] = x[k] * x[k];
    short_form[k] = lanes::maskOf(x2[k] < 1e-8);
  }
  // The usual case: every angle of every lane under 0.1 mrad (one test for the three).
  if (lanes::all(short_form[0] & short_form[1] & short_form[2])) {
    for (int k = 0; k < 3; ++k) {
      s[k] = x[k] - x[k] * x2[k] * (1.0 / 6.0);
      c[k] = 1.0 - 0.5 * x2[k];
    }
    return;
  }
  for (int k = 0; k < 3; ++k) {
    s[k] = lanes::select(short_form[k], x[k] - x[k] * x2[k] * (1.0 / 6.0),
                         x[k] * (1.0 - x2[k] * k6 * (1.0 - x2[k] * k20)));
    c[k] = lanes::select(short_form[k], 1.0 - 0.5 * x2[k],
                         1.0 - 0.5 * x2[k] * (1.0 - x2[k] * k12 * (1.0 - x2[k] * k30)));
    *big |= lanes::maskOf(!(x2[k] < 1e-6));
  }
}

// M <- Rot(e_k, theta) M on rows k+1, k+2 (rotateRowsAbout), M 3 x 2 of L.
template <int k, typename L>
TOLVER_LANE_INLINE void rotateRows(L c, L s, L M[3][2]) {
  constexpr int i = (k + 1) % 3, j = (k + 2) % 3;
  for (int col = 0; col < 2; ++col) {
    const L mi = M[i][col], mj = M[j][col];
    M[i][col] = c * mi - s * mj;
    M[j][col] = s * mi + c * mj;
  }
}
template <typename L>
TOLVER_LANE_INLINE void rotateRows(int k, L c, L s, L M[3][2]) {
  if (k == 0)
    rotateRows<0>(c, s, M);
  else if (k == 1)
    rotateRows<1>(c, s, M);
  else
    rotateRows<2>(c, s, M);
}

// M <- R M (R 3 x 3, column-major doubles).
template <typename L>
TOLVER_LANE_INLINE void multiply(const double* R, L M[3][2]) {
  for (int col = 0; col < 2; ++col) {
    const L m0 = M[0][col], m1 = M[1][col], m2 = M[2][col];
    for (int i = 0; i < 3; ++i) M[i][col] = R[i] * m0 + R[3 + i] * m1 + R[6 + i] * m2;
  }
}

}  // namespace

template <typename L>
TOLVER_LANE_INLINE auto ForwardKinematics::carry(const L* q, const L* c, const L* sn, L M[3][2],
                                                 const MotionContext* ctx) const {
  using Mask = decltype(q[0] < q[0]);
  Mask big{};
  constexpr bool scalar = sizeof(L) == sizeof(double);
  // E(s): M <- Rz Ry Rx M + e (eq. 22's rotation of the error angles), or its inverse.
  auto errors = [&](const AxisTerms& t, int a, bool inverse) TOLVER_LANE_LAMBDA {
    L e[6];
    if constexpr (scalar) {
      if (!t.effects.empty()) {
        const Vector6d v = motionErrors(a, q[a], ctx);
        for (int k = 0; k < 6; ++k) e[k] = v[k];
      } else {
        motionErrorsL(t, q[a], e);
      }
    } else {
      motionErrorsL(t, q[a], e);
    }
    L ce[3], se[3];
    sinCosSmall3(e + 3, se, ce, &big);
    if (!inverse) {
      rotateRows<0>(ce[0], se[0], M);
      rotateRows<1>(ce[1], se[1], M);
      rotateRows<2>(ce[2], se[2], M);
      for (int k = 0; k < 3; ++k) M[k][0] += e[k];
    } else {
      for (int k = 0; k < 3; ++k) M[k][0] -= e[k];
      rotateRows<2>(ce[2], -se[2], M);
      rotateRows<1>(ce[1], -se[1], M);
      rotateRows<0>(ce[0], -se[0], M);
    }
  };
  // D2(s): the nominal motion, or its inverse.
  auto motion = [&](const Axis& ax, const AxisTerms& t, int a, bool inverse) TOLVER_LANE_LAMBDA {
    if (ax.type == JointType::Prismatic) {
      for (int k = 0; k < 3; ++k) {
        if (inverse)
          M[k][0] -= ax.direction[k] * q[a];
        else
          M[k][0] += ax.direction[k] * q[a];
      }
    } else if (t.principal >= 0) {
      rotateRows(t.principal, c[a], inverse ? -sn[a] : sn[a], M);
    } else if constexpr (scalar) {
      const Eigen::Matrix3d R =
          Eigen::AngleAxisd(inverse ? -q[a] : q[a], ax.direction).toRotationMatrix();
      multiply(R.data(), M);
    }
  };
  for (int k = 0; k < 3; ++k) {
    M[k][0] = lanes::splat<L>(t_end_.translation()[k]);
    M[k][1] = lanes::splat<L>(t_end_.linear()(k, 2));
  }
  // F_p_t = D_1 ... D_m t_end 0: from the last tool joint back to the foundation.
  const auto& tool = model_->tool_chain;
  for (auto it = tool.rbegin(); it != tool.rend(); ++it) {
    const int a = *it;
    const AxisTerms& t = axis_[a];
    if (t.has_errors) errors(t, a, false);
    motion(model_->axes[a], t, a, false);
    if (!t.fixed_identity) {  // D1 L
      if (!t.fixed_R_identity) multiply(t.fixed_R.data(), M);
      for (int k = 0; k < 3; ++k) M[k][0] += t.fixed_p[k];
    }
  }
  // w_p = w_end^-1 D_n^-1 ... D_1^-1 F_p.
  for (int a : model_->workpiece_chain) {
    const AxisTerms& t = axis_[a];
    if (!t.fixed_identity) {
      for (int k = 0; k < 3; ++k) M[k][0] -= t.fixed_p[k];
      if (!t.fixed_R_identity) multiply(t.fixed_Rt.data(), M);
    }
    motion(model_->axes[a], t, a, true);
    if (t.has_errors) errors(t, a, true);
  }
  for (int k = 0; k < 3; ++k) M[k][0] -= w_end_.translation()[k];
  multiply(w_end_Rt_.data(), M);
  return big;
}

void ForwardKinematics::tipAndAxis(const JointVector& q, Eigen::Vector3d* p_w, Eigen::Vector3d* u_w,
                                   const double* cos_q, const double* sin_q,
                                   const MotionContext* ctx) const {
  const int n = static_cast<int>(q.size());
  double c[kMaxAxes], s[kMaxAxes];
  for (int a = 0; a < n; ++a) {
    if (!model_->axes[a].isRotary()) continue;
    c[a] = cos_q ? cos_q[a] : std::cos(q[a]);
    s[a] = sin_q ? sin_q[a] : std::sin(q[a]);
  }
  double M[3][2];
  carry(q.data(), c, s, M, ctx);
  *p_w = Eigen::Vector3d(M[0][0], M[1][0], M[2][0]);
  *u_w = Eigen::Vector3d(M[0][1], M[1][1], M[2][1]);
}

struct FkLaneKernels {
  template <typename V>
  TOLVER_LANE_INLINE static void tipAndAxis(const ForwardKinematics& fk, int n,
                                            const double* const q[], const double* const cq[],
                                            const double* const sq[], double* const p_w[3],
                                            double* const u_w[3]);
  static void tipAndAxis4(const ForwardKinematics& fk, int n, const double* const q[],
                          const double* const cq[], const double* const sq[], double* const p_w[3],
                          double* const u_w[3]);
  static void tipAndAxis8(const ForwardKinematics& fk, int n, const double* const q[],
                          const double* const cq[], const double* const sq[], double* const p_w[3],
                          double* const u_w[3]);
};

// V's width of configurations at a time; the lanes flagged by carry, and a tail shorter than
// the width, one at a time.
template <typename V>
TOLVER_LANE_INLINE void FkLaneKernels::tipAndAxis(const ForwardKinematics& fk, int n,
                                                  const double* const q[], const double* const cq[],
                                                  const double* const sq[], double* const p_w[3],
                                                  double* const u_w[3]) {
  using lanes::loadL;
  using lanes::storeL;
  constexpr int width = lanes::widthOf<V>();
  const int axes = static_cast<int>(fk.model_->axes.size());
  auto one = [&](int i) {
    double qs[kMaxAxes], cs[kMaxAxes], ss[kMaxAxes], M[3][2];
    for (int a = 0; a < axes; ++a) {
      qs[a] = q[a][i];
      if (fk.model_->axes[a].isRotary()) {
        cs[a] = cq[a][i];
        ss[a] = sq[a][i];
      }
    }
    fk.carry(qs, cs, ss, M, nullptr);
    for (int k = 0; k < 3; ++k) {
      p_w[k][i] = M[k][0];
      u_w[k][i] = M[k][1];
    }
  };
  int i = 0;
  for (; i + width <= n; i += width) {
    V qv[kMaxAxes], cv[kMaxAxes], sv[kMaxAxes];
    for (int a = 0; a < axes; ++a) {
      qv[a] = loadL<V>(q[a] + i);
      if (fk.model_->axes[a].isRotary()) {
        cv[a] = loadL<V>(cq[a] + i);
        sv[a] = loadL<V>(sq[a] + i);
      }
    }
    V M[3][2];
    const auto big = fk.carry(qv, cv, sv, M, nullptr);
    for (int k = 0; k < 3; ++k) {
      storeL<V>(p_w[k] + i, M[k][0]);
      storeL<V>(u_w[k] + i, M[k][1]);
    }
    if (lanes::any(big))
      for (int l = 0; l < width; ++l)
        if (lanes::lane(big, l)) one(i + l);
  }
  for (; i < n; ++i) one(i);
}

// Cloned for AVX2 (one register per Lane4) with the portable SSE2 default.
TOLVER_LANE_CLONES
void FkLaneKernels::tipAndAxis4(const ForwardKinematics& fk, int n, const double* const q[],
                                const double* const cq[], const double* const sq[],
                                double* const p_w[3], double* const u_w[3]) {
  tipAndAxis<lanes::Lane4>(fk, n, q, cq, sq, p_w, u_w);
}

#if TOLVER_HAS_WIDE_LANES
TOLVER_LANE_WIDE
void FkLaneKernels::tipAndAxis8(const ForwardKinematics& fk, int n, const double* const q[],
                                const double* const cq[], const double* const sq[],
                                double* const p_w[3], double* const u_w[3]) {
  tipAndAxis<lanes::Lane8>(fk, n, q, cq, sq, p_w, u_w);
}
#else
void FkLaneKernels::tipAndAxis8(const ForwardKinematics& fk, int n, const double* const q[],
                                const double* const cq[], const double* const sq[],
                                double* const p_w[3], double* const u_w[3]) {
  tipAndAxis4(fk, n, q, cq, sq, p_w, u_w);
}
#endif

void ForwardKinematics::tipAndAxisBatch(int n, const double* const q[], const double* const cq[],
                                        const double* const sq[], double* const p_w[3],
                                        double* const u_w[3]) const {
  assert(batchable_);
  if (lanes::wideLanes())
    FkLaneKernels::tipAndAxis8(*this, n, q, cq, sq, p_w, u_w);
  else
    FkLaneKernels::tipAndAxis4(*this, n, q, cq, sq, p_w, u_w);
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
    if (b == 0)
      out->F_T_w = T * w_end_;
    else
      out->F_T_t = T * t_end_;
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
