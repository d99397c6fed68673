#include "core/path/arc_interpolation.h"

#include <gtest/gtest.h>

#include <cmath>

namespace tolver {
namespace {

TEST(ArcInterpolation, QuarterCircleCounterClockwiseAboutTheAxis) {
  std::vector<Eigen::Vector3d> pts;
  ASSERT_TRUE(interpolateArc({10, 0, 0}, {0, 10, 0}, {0, 0, 0}, {0, 0, 1}, 0.001, 1e-6, pts));
  // Sagitta r(1 - cos(d/2)) <= tol gives n = ceil((pi/2) / (2 acos(1 - 1e-4))).
  const int n = static_cast<int>(std::ceil((M_PI / 2) / (2 * std::acos(1 - 0.001 / 10))));
  ASSERT_EQ(static_cast<int>(pts.size()), n);
  for (const auto& p : pts) {
    EXPECT_NEAR(p.head<2>().norm(), 10.0, 1e-12);
    EXPECT_GE(p.x(), -1e-12);
    EXPECT_GE(p.y(), -1e-12);
  }
  EXPECT_EQ(pts.back(), Eigen::Vector3d(0, 10, 0));
}

TEST(ArcInterpolation, NegativeAxisGoesTheOtherWayRound) {
  std::vector<Eigen::Vector3d> pts;
  ASSERT_TRUE(interpolateArc({10, 0, 0}, {0, 10, 0}, {0, 0, 0}, {0, 0, -1}, 0.01, 1e-6, pts));
  // Clockwise seen from +z: three quarters of the circle, through (0, -10) and (-10, 0).
  bool through_third_quadrant = false;
  for (const auto& p : pts) through_third_quadrant |= (p.x() < -5 && p.y() < -5);
  EXPECT_TRUE(through_third_quadrant);
}

TEST(ArcInterpolation, HelixRisesLinearlyAndMismatchedRadiusIsRefused) {
  std::vector<Eigen::Vector3d> pts;
  ASSERT_TRUE(interpolateArc({5, 0, 0}, {-5, 0, 2}, {0, 0, 0}, {0, 0, 1}, 0.01, 1e-6, pts));
  EXPECT_NEAR(pts[pts.size() / 2].z(), 2.0 * (pts.size() / 2 + 1) / pts.size(), 1e-12);
  std::vector<Eigen::Vector3d> none;
  EXPECT_FALSE(interpolateArc({5, 0, 0}, {0, 6, 0}, {0, 0, 0}, {0, 0, 1}, 0.01, 0.1, none));
  EXPECT_TRUE(none.empty());
}

}  // namespace
}  // namespace tolver
