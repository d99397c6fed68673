#include "core/kinematics/sensitivity_jacobian.h"

#include <cassert>

#include "core/numerics/chebyshev.h"
#include "core/model/effects.h"

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

void sensitivityJacobian(const ForwardKinematics& fk, const JointVector& q,
                         Eigen::Ref<Eigen::MatrixXd> J, const MotionContext* ctx) {
  const MachineModel& m = fk.model();
  const Eigen::VectorXd& p = fk.params();
  assert(J.rows() == 6 && J.cols() == m.parameterCount());
  ForwardKinematics::ChainFrames fr;
  fk.chainFrames(q, &fr, ctx);
  auto sideOf = [&](int axis) { return m.axes[axis].branch == Branch::Tool ? 1.0 : -1.0; };
  // C(A_T_t) for a frame A given as F_T_A.
  auto transportToTool = [&](const Eigen::Isometry3d& F_T_A) {
    return transportMatrix(F_T_A.inverse(Eigen::Isometry) * fr.F_T_t);
  };
  // Twist per unit additive change of motion-error component c of axis a (acting after E(s)).
  auto componentColumn = [&](int a, int c) -> Eigen::Matrix<double, 6, 1> {
    return sideOf(a) * transportToTool(fr.after_joint[a]) *
           linkTwistMap(fk.motionErrors(a, q[a], ctx)).col(c);
  };
  for (const ParameterBlock& b : m.blocks) {
    switch (b.kind) {
      case BlockKind::LinkError: {
        const Vector6d v = p.segment<6>(b.offset);
        J.middleCols<6>(b.offset) =
            sideOf(b.axis) * transportToTool(fr.after_link[b.axis]) * linkTwistMap(v);
        break;
      }
      case BlockKind::MotionError: {
        const Eigen::Matrix<double, 6, 1> col = componentColumn(b.axis, b.component);
        const Axis& ax = m.axes[b.axis];
        double T[32];
        chebyshevBasis(normalisedCoordinate(q[b.axis], ax.travel_min, ax.travel_max), b.degree, T);
        for (int k = 0; k <= b.degree; ++k) J.col(b.offset + k) = col * T[k];
        break;
      }
      case BlockKind::WorkpieceSetup:
        J.middleCols<6>(b.offset) = -transportToTool(fr.F_T_w) * linkTwistMap(p.segment<6>(b.offset));
        break;
      case BlockKind::ToolSetup:
        J.middleCols<6>(b.offset) = linkTwistMap(p.segment<6>(b.offset));
        break;
      case BlockKind::Effect: {
        const EffectSpec& spec = m.effects[b.effect];
        if (spec.axis < 0) {  // the instrument: no motion of the tool
          J.middleCols(b.offset, b.size).setZero();
          break;
        }
        const Eigen::Matrix<double, 6, 1> col = componentColumn(spec.axis, spec.component);
        const Axis& ax = m.axes[spec.axis];
        double phi[8];
        traitsOf(spec.type).basis(spec, q[spec.axis],
                                  normalisedCoordinate(q[spec.axis], ax.travel_min, ax.travel_max),
                                  ctx, phi);
        for (int k = 0; k < b.size; ++k) J.col(b.offset + k) = col * phi[k];
        break;
      }
    }
  }
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
