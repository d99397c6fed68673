#pragma once
// Homogeneous transforms used by the machine model ([AM01] chapter 3, eq. 20-23).
//
// Conventions, stated once for the whole project:
//  * a_T_b (Eigen::Isometry3d) is the pose of frame b seen from frame a: p_a = a_T_b * p_b.
//  * Lengths are in mm, angles in rad. Degrees appear only at file and user boundaries.
//  * A "twist" here is the 6-vector [ex ey ez gx gy gz]: three small translations (mm)
//    followed by three small rotations (rad) about x, y, z.
#include <Eigen/Geometry>
#include <cmath>

#include "core/numerics/lanes.h"

namespace tolver {

using Vector6d = Eigen::Matrix<double, 6, 1>;

// sin and cos of x to full double precision. Error angles are tiny (micro-radians), where the
// series sin x = x - x^3/6 + x^5/120, cos x = 1 - x^2/2 + x^4/24 - x^6/720 leave truncation errors
// below x^7/5040 and x^8/40320 (under 1e-25 for |x| < 1e-3): exact after rounding, and several
// times cheaper than the library calls, which take the larger angles. Below 1e-4 rad (where
// measured machine errors are) two terms each suffice: the next, x^5/120 and x^4/24, are under
// 1e-18 x and 5e-18, below half a unit in the last place.
inline void sinCosOfSmallAngle(double x, double* s, double* c) {
  const double x2 = x * x;
  if (x2 < 1e-8) {
    *s = x - x * x2 * (1.0 / 6.0);
    *c = 1.0 - 0.5 * x2;
  } else if (x2 < 1e-6) {
    constexpr double k6 = 1.0 / 6.0, k20 = 1.0 / 20.0, k12 = 1.0 / 12.0, k30 = 1.0 / 30.0;
    *s = x * (1.0 - x2 * k6 * (1.0 - x2 * k20));
    *c = 1.0 - 0.5 * x2 * (1.0 - x2 * k12 * (1.0 - x2 * k30));
  } else {
    *s = std::sin(x);
    *c = std::cos(x);
  }
}

// atan t for |t| <= kAtanSeriesMax, by its series t - t^3/3 + ... - t^15/15: the first term left
// out, t^17/17, is below 6e-18 t there, so the result is exact to rounding; a few times cheaper
// than atan2 for the small angles between consecutive poses.
constexpr double kAtanSeriesMax = 0.1;
// L: double, or four lanes (core/numerics/lanes.h), with the same operations.
template <typename L>
TOLVER_LANE_INLINE L atanOfSmallL(L t) {
  const L t2 = t * t;
  return t * (1.0 +
              t2 * (-1.0 / 3.0 +
                    t2 * (1.0 / 5.0 +
                          t2 * (-1.0 / 7.0 +
                                t2 * (1.0 / 9.0 + t2 * (-1.0 / 11.0 +
                                                        t2 * (1.0 / 13.0 - t2 * (1.0 / 15.0))))))));
}
inline double atanOfSmall(double t) { return atanOfSmallL(t); }

// M <- Rot(e_k, theta) M for the coordinate axis k (0, 1, 2 = x, y, z), given c = cos theta and
// s = sin theta: only rows k+1 and k+2 (mod 3) change. M is 3 x n, its columns points or
// directions; the hot loops carry a few vectors this way instead of composing 3x3 matrices.
template <int k, typename Matrix>
inline void rotateRowsAbout(double c, double s, Matrix& M) {
  constexpr int i = (k + 1) % 3, j = (k + 2) % 3;
  for (int col = 0; col < M.cols(); ++col) {
    const double mi = M(i, col), mj = M(j, col);
    M(i, col) = c * mi - s * mj;
    M(j, col) = s * mi + c * mj;
  }
}
template <typename Matrix>
inline void rotateRowsAbout(int k, double c, double s, Matrix& M) {
  if (k == 0)
    rotateRowsAbout<0>(c, s, M);
  else if (k == 1)
    rotateRowsAbout<1>(c, s, M);
  else
    rotateRowsAbout<2>(c, s, M);
}

// trans(dir, d): a pure translation by d (mm) along the unit vector dir.
Eigen::Isometry3d translation(const Eigen::Vector3d& dir, double d);

// rot(dir, angle): a pure rotation by angle (rad) about the unit vector dir through the origin.
Eigen::Isometry3d rotation(const Eigen::Vector3d& dir, double angle);

// The link HTM of [AM01] eq. 21/22, exact (no small-angle approximation):
//   trans(i, tx) trans(j, ty) trans(k, tz) rot(k, rz) rot(j, ry) rot(i, rx)
// with v = [tx ty tz rx ry rz] (mm, rad).
Eigen::Isometry3d linkTransform(const Vector6d& v);

// The rotation part of linkTransform: Rz(rz) * Ry(ry) * Rx(rx).
Eigen::Matrix3d rotationZYX(double rx, double ry, double rz);

// The 6x6 transport matrix of [AM01] eq. 29: maps an error twist expressed in frame A to the
// equivalent twist expressed in frame B, where a_T_b is the pose of B seen from A.
// [ R^T  -R^T [p x] ; 0  R^T ] with R, p the rotation and translation of a_T_b.
Eigen::Matrix<double, 6, 6> transportMatrix(const Eigen::Isometry3d& a_T_b);

}  // namespace tolver
