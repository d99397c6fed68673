#pragma once
// The sensitivity Jacobian ([AM01] eq. 28-37, 61-72): how the pose of the tool frame t seen
// from the workpiece frame w changes with each error parameter.
//
// The error twist dt = [d; theta] (mm, rad) is expressed in t: w_T_t(p + dp) = w_T_t(p) E(dt),
// E(dt) ~ [I + [theta x], d]. A parameter that acts as a right perturbation dv of a frame A
// (A = the frame after D1 L for link errors, the joint frame after E(s) for motion errors, w or
// t for set-up errors) moves the tool by  dt = +C(A_T_t) M(v) dv  when A is on the tool branch
// and by  dt = -C(A_T_t) M(v) dv  when A is on the workpiece branch, where C is the transport
// matrix of eq. 29 (transportMatrix), A_T_t the tool pose seen from A, and M(v) maps a change of
// the six numbers v = [tx ty tz rx ry rz] of linkTransform(v) to the body twist of that frame
// (exact, so the Jacobian is exact at non-zero parameters too). Chebyshev coefficients enter
// through T_k(s_N) (eq. 71-72).
#include <Eigen/Core>

#include "core/kinematics/forward_kinematics.h"

namespace tolver {

// M(v): body twist of linkTransform(v) per unit change of v (6x6).
Eigen::Matrix<double, 6, 6> linkTwistMap(const Vector6d& v);

// J_twist_params: 6 x parameterCount(), rows [dx dy dz thx thy thz] of the twist in t (mm, rad),
// one column per parameter of fk.model() (mm or rad). J must already have that size.
void sensitivityJacobian(const ForwardKinematics& fk, const JointVector& q,
                         Eigen::Ref<Eigen::MatrixXd> J_twist_params,
                         const MotionContext* ctx = nullptr);

// The same contracted with a row w (1 x 6, e.g. a reading's change per tool twist):
// row = w * J_twist_params, without the 6 x parameterCount() matrix. row must have that size.
void sensitivityRow(const ForwardKinematics& fk, const JointVector& q,
                    const Eigen::Matrix<double, 1, 6>& w, Eigen::Ref<Eigen::RowVectorXd> row,
                    const MotionContext* ctx = nullptr);

// Twist in t per unit additive change of each motion-error component of each axis at q (the
// derivative an effect's coefficient scales by its basis value): J_twist_components is
// 6 x (6 * axes), column 6 a + c for axis a, component c (ex .. gz).
void componentSensitivities(const ForwardKinematics& fk, const JointVector& q,
                            Eigen::Ref<Eigen::MatrixXd> J_twist_components,
                            const MotionContext* ctx = nullptr);

}  // namespace tolver
