#include "geometry/cutter.h"

#include <gtest/gtest.h>

#include <cmath>

namespace tolver {
namespace {

TEST(Cutter, ClassifiesAptAndTldataShapes) {
  Cutter c;
  ASSERT_TRUE(cutterFromApt("CUTTER", {10}, &c));
  EXPECT_EQ(c.type, CutterType::FlatEnd);
  ASSERT_TRUE(cutterFromApt("CUTTER", {10, 5}, &c));
  EXPECT_EQ(c.type, CutterType::BallEnd);
  ASSERT_TRUE(cutterFromApt("TLDATA", {32, 5, 75, 0, 0}, &c));
  EXPECT_EQ(c.type, CutterType::BullNose);
  EXPECT_EQ(c.length, 75);
  ASSERT_TRUE(cutterFromApt("CUTTER", {6, 0, 0, 0, 0, 10, 30}, &c));
  EXPECT_EQ(c.type, CutterType::Tapered);
  EXPECT_FALSE(cutterFromApt("CUTTER", {10, 6}, &c));  // corner radius larger than the radius
  EXPECT_FALSE(cutterFromApt("CUTTER", {}, &c));
}

TEST(Cutter, RadiusProfileFollowsTheShape) {
  Cutter ball;
  ASSERT_TRUE(cutterFromApt("CUTTER", {10, 5}, &ball));
  EXPECT_NEAR(ball.radiusAt(0), 0, 1e-12);
  EXPECT_NEAR(ball.radiusAt(1), std::sqrt(25 - 16), 1e-12);  // sphere of radius 5 centred at 5
  EXPECT_NEAR(ball.radiusAt(5), 5, 1e-12);
  EXPECT_NEAR(ball.radiusAt(20), 5, 1e-12);
  Cutter taper;
  ASSERT_TRUE(cutterFromApt("TLDATA", {6, 0, 40, 10}, &taper));
  EXPECT_NEAR(taper.radiusAt(10), 3 + 10 * std::tan(10 * M_PI / 180), 1e-12);
  EXPECT_LT(taper.radiusAt(-1), 0);
}

}  // namespace
}  // namespace tolver
