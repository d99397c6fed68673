#include "core/model/rigid_transform.h"

#include <cmath>

namespace tolver {

Eigen::Isometry3d translation(const Eigen::Vector3d& dir, double d) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = dir * d;
  return T;
}

Eigen::Isometry3d rotation(const Eigen::Vector3d& dir, double angle) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(angle, dir.normalized()).toRotationMatrix();
  return T;
}

Eigen::Matrix3d rotationZYX(double rx, double ry, double rz) {
  double cx, sx, cy, sy, cz, sz;
  sinCosOfSmallAngle(rx, &sx, &cx);
  sinCosOfSmallAngle(ry, &sy, &cy);
  sinCosOfSmallAngle(rz, &sz, &cz);
  Eigen::Matrix3d R;
  R << cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx,  //
      sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx,   //
      -sy, cy * sx, cy * cx;
  return R;
}

Eigen::Isometry3d linkTransform(const Vector6d& v) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = rotationZYX(v[3], v[4], v[5]);
  T.translation() = v.head<3>();
  return T;
}

Eigen::Matrix<double, 6, 6> transportMatrix(const Eigen::Isometry3d& a_T_b) {
  const Eigen::Matrix3d Rt = a_T_b.linear().transpose();
  const Eigen::Vector3d p = a_T_b.translation();
  Eigen::Matrix3d px;
  px << 0, -p.z(), p.y(), p.z(), 0, -p.x(), -p.y(), p.x(), 0;
  Eigen::Matrix<double, 6, 6> C = Eigen::Matrix<double, 6, 6>::Zero();
  C.topLeftCorner<3, 3>() = Rt;
  C.topRightCorner<3, 3>() = -Rt * px;
  C.bottomRightCorner<3, 3>() = Rt;
  return C;
}

}  // namespace tolver
