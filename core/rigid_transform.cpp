#include "core/rigid_transform.h"

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

namespace {
// sin and cos to full double precision. Error angles are tiny (micro-radians), where the series
// sin x = x - x^3/6 + x^5/120, cos x = 1 - x^2/2 + x^4/24 - x^6/720 have truncation errors below
// x^7/5040 and x^8/40320, i.e. under 1e-25 for |x| < 1e-3: exact after rounding, and several
// times cheaper than the library calls. Larger angles go to the library.
inline void sinCos(double x, double* s, double* c) {
  if (std::abs(x) < 1e-3) {
    constexpr double k6 = 1.0 / 6.0, k20 = 1.0 / 20.0, k12 = 1.0 / 12.0, k30 = 1.0 / 30.0;
    const double x2 = x * x;
    *s = x * (1.0 - x2 * k6 * (1.0 - x2 * k20));
    *c = 1.0 - 0.5 * x2 * (1.0 - x2 * k12 * (1.0 - x2 * k30));
  } else {
    *s = std::sin(x);
    *c = std::cos(x);
  }
}
}  // namespace

Eigen::Matrix3d rotationZYX(double rx, double ry, double rz) {
  double cx, sx, cy, sy, cz, sz;
  sinCos(rx, &sx, &cx);
  sinCos(ry, &sy, &cy);
  sinCos(rz, &sz, &cz);
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
