#include "core/kinematics/sensitivity_jacobian.h"

#include <array>
#include <cassert>

#include "core/model/effects.h"
#include "core/numerics/chebyshev.h"

namespace tolver {

Eigen::Matrix<double, 6, 6> linkTwistMap(const Vector6d& v) {
  // linkTransform(v) = trans(t) Rz(rz) Ry(ry) Rx(rx). A change dt of t moves the frame by
  // R^T dt in its own axes; the angular rates give the spatial velocity
  // w = k drz + Rz j dry + Rz Ry i drx, i.e. R^T w in the frame's axes.
  const Eigen::Matrix3d R = rotationZYX(v[3], v[4], v[5]);
  const Eigen::Matrix3d Rz = rotationZYX(0, 0, v[5]);
  const Eigen::Matrix3d RzRy = rotationZYX(0, v[4], v[5]);
  Eigen::Matrix<double, 6, 6> M = Eigen::Matrix<double, 6, 6>::Zero();
  M.topLeftCorner<3, 3>() = R.transpose();
  M.block<3, 1>(3, 3) = R.transpose() * (RzRy * Eigen::Vector3d::UnitX());
  M.block<3, 1>(3, 4) = R.transpose() * (Rz * Eigen::Vector3d::UnitY());
  M.block<3, 1>(3, 5) = R.transpose() * Eigen::Vector3d::UnitZ();
  return M;
}

namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

// The columns of the sensitivity Jacobian at q, block by block, to a sink: block(offset, M) for
// six columns M, scaled(offset, count, col, f) for `count` columns col * f[k], zero(offset,
// count). The twist map of each axis's motion errors is composed once per axis and shared by
// its six component blocks and its effects.
template <class Sink>
void forEachSensitivity(const ForwardKinematics& fk, const JointVector& q, const MotionContext* ctx,
                        Sink& sink) {
  const MachineModel& m = fk.model();
  const Eigen::VectorXd& p = fk.params();
  ForwardKinematics::ChainFrames fr;
  fk.chainFrames(q, &fr, ctx);
  auto sideOf = [&](int axis) { return m.axes[axis].branch == Branch::Tool ? 1.0 : -1.0; };
  // C(A_T_t) for a frame A given as F_T_A.
  auto transportToTool = [&](const Eigen::Isometry3d& F_T_A) {
    return transportMatrix(F_T_A.inverse(Eigen::Isometry) * fr.F_T_t);
  };
  // Per axis: the twist per unit additive change of each motion-error component (acting after
  // E(s)), composed when first needed.
  std::array<Matrix6d, kMaxAxes> motion;
  std::array<bool, kMaxAxes> composed{};
  auto motionMap = [&](int a) -> const Matrix6d& {
    if (!composed[a]) {
      motion[a] = sideOf(a) * transportToTool(fr.after_joint[a]) *
                  linkTwistMap(fk.motionErrors(a, q[a], ctx));
      composed[a] = true;
    }
    return motion[a];
  };
  for (const ParameterBlock& b : m.blocks) {
    switch (b.kind) {
      case BlockKind::LinkError: {
        const Vector6d v = p.segment<6>(b.offset);
        sink.block(b.offset,
                   sideOf(b.axis) * transportToTool(fr.after_link[b.axis]) * linkTwistMap(v));
        break;
      }
      case BlockKind::MotionError: {
        const Axis& ax = m.axes[b.axis];
        double T[32];
        chebyshevBasis(normalisedCoordinate(q[b.axis], ax.travel_min, ax.travel_max), b.degree, T);
        sink.scaled(b.offset, b.degree + 1, motionMap(b.axis).col(b.component), T);
        break;
      }
      case BlockKind::WorkpieceSetup:
        sink.block(b.offset, -transportToTool(fr.F_T_w) * linkTwistMap(p.segment<6>(b.offset)));
        break;
      case BlockKind::ToolSetup:
        sink.block(b.offset, linkTwistMap(p.segment<6>(b.offset)));
        break;
      case BlockKind::Effect: {
        const EffectSpec& spec = m.effects[b.effect];
        if (spec.axis < 0) {  // the instrument: no motion of the tool
          sink.zero(b.offset, b.size);
          break;
        }
        const Axis& ax = m.axes[spec.axis];
        double phi[8];
        traitsOf(spec.type).basis(spec, q[spec.axis],
                                  normalisedCoordinate(q[spec.axis], ax.travel_min, ax.travel_max),
                                  ctx, phi);
        sink.scaled(b.offset, b.size, motionMap(spec.axis).col(spec.component), phi);
        break;
      }
    }
  }
}

}  // namespace

void sensitivityJacobian(const ForwardKinematics& fk, const JointVector& q,
                         Eigen::Ref<Eigen::MatrixXd> J, const MotionContext* ctx) {
  assert(J.rows() == 6 && J.cols() == fk.model().parameterCount());
  struct {
    Eigen::Ref<Eigen::MatrixXd>& J;
    void block(int offset, const Matrix6d& M) { J.middleCols<6>(offset) = M; }
    void scaled(int offset, int count, const Vector6d& col, const double* f) {
      for (int k = 0; k < count; ++k) J.col(offset + k) = col * f[k];
    }
    void zero(int offset, int count) { J.middleCols(offset, count).setZero(); }
  } sink{J};
  forEachSensitivity(fk, q, ctx, sink);
}

void sensitivityRow(const ForwardKinematics& fk, const JointVector& q,
                    const Eigen::Matrix<double, 1, 6>& w, Eigen::Ref<Eigen::RowVectorXd> row,
                    const MotionContext* ctx) {
  assert(row.size() == fk.model().parameterCount());
  struct {
    const Eigen::Matrix<double, 1, 6>& w;
    Eigen::Ref<Eigen::RowVectorXd>& row;
    void block(int offset, const Matrix6d& M) { row.segment<6>(offset) = w * M; }
    void scaled(int offset, int count, const Vector6d& col, const double* f) {
      const double s = w.dot(col.transpose());
      for (int k = 0; k < count; ++k) row[offset + k] = s * f[k];
    }
    void zero(int offset, int count) { row.segment(offset, count).setZero(); }
  } sink{w, row};
  forEachSensitivity(fk, q, ctx, sink);
}

void componentSensitivities(const ForwardKinematics& fk, const JointVector& q,
                            Eigen::Ref<Eigen::MatrixXd> J, const MotionContext* ctx) {
  const MachineModel& m = fk.model();
  const int n = static_cast<int>(m.axes.size());
  assert(J.rows() == 6 && J.cols() == 6 * n);
  ForwardKinematics::ChainFrames fr;
  fk.chainFrames(q, &fr, ctx);
  for (int a = 0; a < n; ++a) {
    const double side = m.axes[a].branch == Branch::Tool ? 1.0 : -1.0;
    const Vector6d e = fk.motionErrors(a, q[a], ctx);
    J.middleCols<6>(6 * a) =
        side * transportMatrix(fr.after_joint[a].inverse(Eigen::Isometry) * fr.F_T_t) *
        linkTwistMap(e);
  }
}

}  // namespace tolver
