// Column scaling, rank and condition (core/numerics/scaled_svd.h) against closed forms.
#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <cmath>
#include <cstdlib>

#include "core/numerics/scaled_svd.h"

namespace tolver {
namespace {

// Scaling removes units: diag(1 mm, 1000 urad-as-rad) is perfectly conditioned once scaled,
// 1000 as it is; the divisors undo the scaling.
TEST(ScaledSvd, ScalingRemovesUnitsAndTheDivisorsUndoIt) {
  Eigen::MatrixXd J(3, 2);
  J << 1, 0, 0, 1000, 0, 0;
  Eigen::VectorXd d;
  const Eigen::MatrixXd S = scaleColumns(J, &d);
  EXPECT_NEAR(S.col(0).norm(), 1.0, 1e-15);
  EXPECT_NEAR(S.col(1).norm(), 1.0, 1e-15);
  EXPECT_NEAR(d[1], 1000.0, 1e-12);
  EXPECT_NEAR(scaledCondition(J), 1.0, 1e-12);
  EXPECT_NEAR(unscaledCondition(J), 1000.0, 1e-9);
  EXPECT_TRUE(((S * d.asDiagonal()) - J).isZero(1e-12));
}

// A column of rounding (below 1e-10 of the largest) is no effect: zeroed, divisor 1, and the
// rank counts it out; an exact duplicate column is rank-deficient too.
TEST(ScaledSvd, NegligibleAndDuplicateColumnsCountOut) {
  Eigen::MatrixXd J(4, 3);
  J << 1, 2, 1e-14, 0, 1, -1e-14, 3, 0, 0, 1, 1, 0;
  Eigen::VectorXd d;
  const Eigen::MatrixXd S = scaleColumns(J, &d);
  EXPECT_EQ(columnScales(J)[2], 0.0);
  EXPECT_EQ(d[2], 1.0);
  EXPECT_TRUE(S.col(2).isZero(0.0));
  const SvdSummary s = analyseColumns(J);
  EXPECT_EQ(s.rank, 2);
  EXPECT_TRUE(std::isinf(s.condition));
  Eigen::MatrixXd K(4, 3);
  K << J.col(0), J.col(1), 2.0 * J.col(0);
  EXPECT_EQ(analyseColumns(K).rank, 2);
  // compressRows keeps the singular values.
  EXPECT_NEAR(analyseColumns(J.leftCols(2)).condition, scaledCondition(J.leftCols(2)), 1e-9);
}

// The singular values behind the rank decisions (bidiagonalisation and the Golub-Kahan
// tridiagonal) against Jacobi's, an independent algorithm, on column-scaled matrices: tall,
// square and wide, full rank, with a zero column, with equal columns and with a column at 1e-10
// of the others; each value to within 1e-13 of the largest.
TEST(ScaledSvd, SingularValuesAgreeWithJacobi) {
  std::srand(7);
  for (int trial = 0; trial < 40; ++trial) {
    const int rows = 3 + trial % 7 * 9, cols = 1 + (trial * 5) % 23;
    Eigen::MatrixXd S = Eigen::MatrixXd::Random(rows, cols);
    if (trial % 4 == 1 && cols > 2) S.col(1).setZero();
    if (trial % 4 == 2 && cols > 3) S.col(3) = S.col(0);
    if (trial % 4 == 3 && cols > 2) S.col(2) = S.col(0) + 1e-10 * S.col(1);
    for (int c = 0; c < cols; ++c)
      if (S.col(c).norm() > 0) S.col(c).normalize();
    const Eigen::VectorXd ours = summariseScaled(S, rows).singular_values;
    const Eigen::VectorXd jacobi = Eigen::JacobiSVD<Eigen::MatrixXd>(S).singularValues();
    ASSERT_EQ(ours.size(), jacobi.size()) << rows << "x" << cols;
    for (int k = 0; k < ours.size(); ++k)
      EXPECT_NEAR(ours[k], jacobi[k], 1e-13 * jacobi[0]) << rows << "x" << cols << " value " << k;
    EXPECT_EQ(numericalRank(ours), numericalRank(jacobi)) << rows << "x" << cols;
  }
}

// numericalRank: values above 1e-9 of the largest.
TEST(ScaledSvd, NumericalRankUsesTheRelativeTolerance) {
  Eigen::VectorXd sv(4);
  sv << 10, 1, 2e-8, 5e-9;
  EXPECT_EQ(numericalRank(sv), 3);
}

}  // namespace
}  // namespace tolver
