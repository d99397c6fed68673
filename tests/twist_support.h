#pragma once
// Body twist between two poses, for finite-difference checks of Jacobians.
#include <Eigen/Geometry>

#include "core/model/rigid_transform.h"

namespace tolver::test {

// Body twist of b relative to a, to first order: vee(a^-1 b), [d; theta].
inline Vector6d twistBetween(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  const Eigen::Isometry3d M = a.inverse(Eigen::Isometry) * b;
  const Eigen::Matrix3d S = 0.5 * (M.linear() - M.linear().transpose());
  Vector6d t;
  t << M.translation(), S(2, 1), S(0, 2), S(1, 0);
  return t;
}

}  // namespace tolver::test
