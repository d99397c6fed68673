// Column scaling, rank and condition (core/numerics/scaled_svd.h) against closed forms.
#include "core/numerics/scaled_svd.h"

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <cmath>
#include <cstdlib>

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
// The normal-matrix shortcut: its condition number squared agrees with Jacobi's singular values
// of the column-scaled matrix; clearlyFullRank says yes below kappa 1e5 only, and no for a zero
// column or a rank-deficient matrix.
TEST(ScaledSvd, NormalMatrixConditionAgreesWithJacobi) {
  std::srand(5);
  int clear = 0, unclear = 0;  // both answers met
  for (const double kappa : {1.0e1, 1.0e3, 3.0e4, 1.0e6, 1.0e8}) {
    // Columns in mm and rad (scales 1 and 1e-4), with singular values spread to kappa.
    const Eigen::MatrixXd U =
        Eigen::HouseholderQR<Eigen::MatrixXd>(Eigen::MatrixXd::Random(300, 40)).householderQ() *
        Eigen::MatrixXd::Identity(300, 40);
    const Eigen::MatrixXd V =
        Eigen::HouseholderQR<Eigen::MatrixXd>(Eigen::MatrixXd::Random(40, 40)).householderQ();
    Eigen::VectorXd sv(40);
    for (int k = 0; k < 40; ++k) sv[k] = std::pow(kappa, -k / 39.0);
    Eigen::MatrixXd J = U * sv.asDiagonal() * V.transpose();
    for (int c = 0; c < 40; c += 2) J.col(c) *= 1e-4;
    const Eigen::VectorXd truth =
        Eigen::JacobiSVD<Eigen::MatrixXd>(scaleColumns(J)).singularValues();
    const double truth2 = std::pow(truth[0] / truth[39], 2);
    Eigen::MatrixXd N = Eigen::MatrixXd::Zero(40, 40);
    N.selfadjointView<Eigen::Lower>().rankUpdate(J.transpose());
    Eigen::VectorXd scale;
    ASSERT_TRUE(scaleNormalMatrix(N, &scale));
    EXPECT_LT((scale - J.colwise().norm().transpose()).norm(), 1e-12 * scale.norm());
    if (truth2 < 1e10) EXPECT_NEAR(normalConditionSquared(N), truth2, 1e-6 * truth2) << kappa;
    EXPECT_EQ(clearlyFullRank(J), truth2 < 1e10) << kappa;
    (truth2 < 1e10 ? clear : unclear) += 1;
  }
  EXPECT_EQ(clear, 3);
  EXPECT_EQ(unclear, 2);
  Eigen::MatrixXd Z = Eigen::MatrixXd::Random(50, 6);
  Z.col(3).setZero();
  EXPECT_FALSE(clearlyFullRank(Z));
  Eigen::MatrixXd D = Eigen::MatrixXd::Random(50, 6);
  D.col(5) = D.col(0) + D.col(1);
  EXPECT_FALSE(clearlyFullRank(D));
}

TEST(ScaledSvd, NumericalRankUsesTheRelativeTolerance) {
  Eigen::VectorXd sv(4);
  sv << 10, 1, 2e-8, 5e-9;
  EXPECT_EQ(numericalRank(sv), 3);
}

}  // namespace
}  // namespace tolver
