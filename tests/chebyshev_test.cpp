#include "core/numerics/chebyshev.h"

#include <gtest/gtest.h>

#include <cmath>

namespace tolver {
namespace {

TEST(Chebyshev, RecurrenceMatchesCosineDefinition) {
  // eq. 54: T_n(x) = cos(n arccos x) on [-1, 1].
  double T[16];
  for (double x = -1.0; x <= 1.0; x += 0.01) {
    chebyshevBasis(x, 15, T);
    for (int n = 0; n <= 15; ++n) EXPECT_NEAR(T[n], std::cos(n * std::acos(x)), 1e-12) << n;
  }
}

TEST(Chebyshev, ExplicitLowDegreesOfEquation56) {
  double T[4];
  for (double x : {-1.0, -0.3, 0.0, 0.25, 0.9, 1.0}) {
    chebyshevBasis(x, 3, T);
    EXPECT_DOUBLE_EQ(T[0], 1.0);
    EXPECT_DOUBLE_EQ(T[1], x);
    EXPECT_NEAR(T[2], 2 * x * x - 1, 1e-15);
    EXPECT_NEAR(T[3], 4 * x * x * x - 3 * x, 1e-15);
  }
}

TEST(Chebyshev, SeriesIsTheWeightedSumOfTheBasis) {
  const double c[5] = {0.5, -1.25, 2.0, 0.75, -0.1};
  double T[5];
  for (double x = -1.0; x <= 1.0; x += 0.05) {
    chebyshevBasis(x, 4, T);
    double expect = 0;
    for (int k = 0; k < 5; ++k) expect += c[k] * T[k];
    EXPECT_NEAR(chebyshevSeries(c, 4, x), expect, 1e-14);
  }
  EXPECT_DOUBLE_EQ(chebyshevSeries(c, 0, 0.3), 0.5);
}

TEST(Chebyshev, NormalisationOfEquation58MapsTravelOntoUnitInterval) {
  EXPECT_DOUBLE_EQ(normalisedCoordinate(-150, -150, 360), -1.0);
  EXPECT_DOUBLE_EQ(normalisedCoordinate(360, -150, 360), 1.0);
  EXPECT_DOUBLE_EQ(normalisedCoordinate(105, -150, 360), 0.0);
  EXPECT_DOUBLE_EQ(normalisedCoordinate(0, -2.0943951, 0.5235988), (0 + 0.78539815) / 1.30899695);
}

}  // namespace
}  // namespace tolver
