#include "core/model/rigid_transform.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace tolver {
namespace {

TEST(RigidTransform, LinkTransformIsTheProductOfEquation22) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (int n = 0; n < 100; ++n) {
    Vector6d v;
    for (int k = 0; k < 6; ++k) v[k] = u(rng);
    const Eigen::Isometry3d expect =
        translation(Eigen::Vector3d::UnitX(), v[0]) * translation(Eigen::Vector3d::UnitY(), v[1]) *
        translation(Eigen::Vector3d::UnitZ(), v[2]) * rotation(Eigen::Vector3d::UnitZ(), v[5]) *
        rotation(Eigen::Vector3d::UnitY(), v[4]) * rotation(Eigen::Vector3d::UnitX(), v[3]);
    EXPECT_TRUE(linkTransform(v).isApprox(expect, 1e-14));
  }
}

// A small twist at frame A, seen from a frame B rigidly attached to A: B' = A_T_B^-1 E(dA) A_T_B
// must equal E(C dA) to first order ([AM01] eq. 28-29).
TEST(RigidTransform, TransportMatrixPropagatesSmallTwists) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int n = 0; n < 50; ++n) {
    Vector6d pose;
    for (int k = 0; k < 6; ++k) pose[k] = u(rng) * (k < 3 ? 300.0 : 3.0);
    const Eigen::Isometry3d a_T_b = linkTransform(pose);
    Vector6d dA;
    for (int k = 0; k < 6; ++k) dA[k] = u(rng) * 1e-7;
    const Eigen::Isometry3d M = a_T_b.inverse() * linkTransform(dA) * a_T_b;
    Vector6d dB;
    dB.head<3>() = M.translation();
    dB[3] = M.linear()(2, 1);
    dB[4] = M.linear()(0, 2);
    dB[5] = M.linear()(1, 0);
    const Vector6d predicted = transportMatrix(a_T_b) * dA;
    EXPECT_LT((predicted - dB).norm(), 1e-11) << n;
  }
}

// The series branch agrees with the library to one unit in the last place, up to and across
// its switch-over.
TEST(RigidTransform, SmallAngleSinCosIsExactToRounding) {
  auto ulp = [](double v) { return std::abs(std::nextafter(v, 2.0 * v + 1.0) - v); };
  for (double x = -2e-3; x <= 2e-3; x += 1.37e-6) {
    double s, c;
    sinCosOfSmallAngle(x, &s, &c);
    EXPECT_LE(std::abs(s - std::sin(x)), ulp(std::sin(x))) << x;
    EXPECT_LE(std::abs(c - std::cos(x)), ulp(std::cos(x))) << x;
  }
  double s, c;
  sinCosOfSmallAngle(0.7, &s, &c);
  EXPECT_EQ(s, std::sin(0.7));
}

// atan's series agrees with the library to rounding over its whole range, and the helper that
// rotates rows matches the rotation matrix.
TEST(RigidTransform, SmallAtanSeriesIsExactToRounding) {
  auto ulp = [](double v) { return std::abs(std::nextafter(v, 2.0 * v + 1.0) - v); };
  int checked = 0;
  for (double t = -kAtanSeriesMax; t <= kAtanSeriesMax; t += 1.3e-4, ++checked)
    EXPECT_LE(std::abs(atanOfSmall(t) - std::atan(t)), 2.0 * ulp(std::atan(t))) << t;
  EXPECT_GT(checked, 1500);
  EXPECT_EQ(atanOfSmall(0.0), 0.0);
  // One more term's worth: at twice the range the series is visibly off, so the bound is real.
  EXPECT_GT(std::abs(atanOfSmall(0.2) - std::atan(0.2)), 1e-14);
}

TEST(RigidTransform, RotateRowsAboutMatchesTheRotationMatrix) {
  Eigen::Matrix<double, 3, 2> M;
  M << 1, -2, 3, 0.5, -4, 7;
  for (int k = 0; k < 3; ++k) {
    const double angle = 0.3 + k;
    Eigen::Matrix<double, 3, 2> R = M;
    rotateRowsAbout(k, std::cos(angle), std::sin(angle), R);
    const Eigen::Matrix<double, 3, 2> expected =
        Eigen::AngleAxisd(angle, Eigen::Vector3d::Unit(k)).toRotationMatrix() * M;
    EXPECT_LT((R - expected).norm(), 1e-14) << k;
  }
}

}  // namespace
}  // namespace tolver
