#include "core/numerics/scaled_svd.h"

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <functional>
#include <limits>

namespace tolver {

Eigen::VectorXd columnScales(const Eigen::MatrixXd& J) {
  Eigen::VectorXd n = J.colwise().norm().transpose();
  const double largest = n.size() ? n.maxCoeff() : 0.0;
  for (Eigen::Index c = 0; c < n.size(); ++c)
    if (n[c] <= kNegligibleColumn * largest) n[c] = 0.0;
  return n;
}

Eigen::MatrixXd scaleColumns(const Eigen::MatrixXd& J, Eigen::VectorXd* divisors) {
  Eigen::MatrixXd S = J;
  Eigen::VectorXd d = columnScales(J);
  for (Eigen::Index c = 0; c < S.cols(); ++c) {
    if (d[c] > 0) {
      S.col(c) /= d[c];
    } else {
      S.col(c).setZero();
      d[c] = 1.0;
    }
  }
  if (divisors) *divisors = d;
  return S;
}

int numericalRank(const Eigen::VectorXd& sv) {
  int rank = 0;
  const double smax = sv.size() ? sv[0] : 0.0;
  for (Eigen::Index i = 0; i < sv.size(); ++i)
    if (sv[i] > kRankTolerance * smax) ++rank;
  return rank;
}

Eigen::MatrixXd compressRows(const Eigen::MatrixXd& J) {
  if (J.rows() <= J.cols()) return J;
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(J);
  return qr.matrixQR().topRows(J.cols()).triangularView<Eigen::Upper>();
}

namespace {

// Singular values for the rank decisions of column-scaled matrices: Householder
// bidiagonalisation, then the eigenvalues of the Golub-Kahan matrix [0 B; B^T 0] (symmetric
// tridiagonal after a perfect shuffle, eigenvalues +-sigma) by the tridiagonal QR of
// SelfAdjointEigenSolver. Both steps are backward stable: each singular value to within a few
// units of rounding of the largest, ample for kRankTolerance = 1e-9 on matrices whose columns
// are scaled to unit norm, and about ten times faster than Jacobi on the 110-column matrices of a
// calibration. Not Eigen 3.4.0's BDCSVD: its perturbCol0 reads perm(l - 1) at l = 0, before its
// buffer (AddressSanitizer: heap-buffer-overflow), on the column-scaled identification matrices
// with exactly zero columns and equal columns that rank decisions meet.
Eigen::VectorXd scaledSingularValues(const Eigen::MatrixXd& A) {
  if (A.rows() < A.cols()) return scaledSingularValues(A.transpose());
  const Eigen::Index n = A.cols();
  if (n == 0) return Eigen::VectorXd();
  if (n == 1) return Eigen::VectorXd::Constant(1, A.norm());
  const Eigen::internal::UpperBidiagonalization<Eigen::MatrixXd> bid(A);
  auto B = bid.bidiagonal();  // a copy (2 x n): Eigen 3.4 has no const diagonal<1>()
  Eigen::VectorXd diagonal = Eigen::VectorXd::Zero(2 * n), off(2 * n - 1);
  for (Eigen::Index i = 0; i < n; ++i) {
    off[2 * i] = B.diagonal()[i];
    if (i + 1 < n) off[2 * i + 1] = B.diagonal<1>()[i];
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es;
  es.computeFromTridiagonal(diagonal, off, Eigen::EigenvaluesOnly);
  // Ascending +-sigma: the upper half, largest first.
  Eigen::VectorXd sv = es.eigenvalues().tail(n).reverse().cwiseAbs();
  std::sort(sv.data(), sv.data() + n, std::greater<double>());
  return sv;
}

// Singular values by Jacobi rotations, accurate relative to each value (not only to the
// largest) when the column-scaled matrix is well conditioned: for the unscaled condition numbers
// (mm and rad mixed, 1e10 and more), which are reported, never decided on.
Eigen::VectorXd unscaledSingularValues(const Eigen::MatrixXd& A) {
  // Eigen 3.4's JacobiSVD reads out of bounds on an empty matrix, and NaNs have no singular
  // values: none are returned (condition 0, rank 0).
  if (A.rows() == 0 || A.cols() == 0 || !A.allFinite()) return Eigen::VectorXd();
  return Eigen::JacobiSVD<Eigen::MatrixXd>(A).singularValues();
}

double conditionOf(const Eigen::VectorXd& sv) {
  if (sv.size() == 0) return 0.0;
  return sv[sv.size() - 1] > 0 ? sv[0] / sv[sv.size() - 1]
                               : std::numeric_limits<double>::infinity();
}

}  // namespace

SvdSummary summariseScaled(const Eigen::MatrixXd& S, int rows) {
  SvdSummary out;
  out.rows = rows;
  out.cols = static_cast<int>(S.cols());
  if (S.cols() == 0) return out;
  out.singular_values = scaledSingularValues(S);
  out.rank = numericalRank(out.singular_values);
  out.condition = out.rank < out.cols ? std::numeric_limits<double>::infinity()
                                      : conditionOf(out.singular_values);
  return out;
}

SvdSummary analyseColumns(const Eigen::MatrixXd& J) {
  SvdSummary s = summariseScaled(compressRows(scaleColumns(J)), static_cast<int>(J.rows()));
  s.condition_unscaled = unscaledCondition(J);
  return s;
}

double unscaledCondition(const Eigen::MatrixXd& J) {
  if (J.cols() == 0) return 0.0;
  return conditionOf(unscaledSingularValues(compressRows(J)));
}

double scaledCondition(const Eigen::MatrixXd& J) {
  if (J.cols() == 0) return 0.0;
  return conditionOf(scaledSingularValues(compressRows(scaleColumns(J))));
}

bool scaleNormalMatrix(Eigen::MatrixXd& N, Eigen::VectorXd* scale) {
  const Eigen::Index n = N.cols();
  *scale = N.diagonal().cwiseSqrt();
  if (n == 0 || !(scale->minCoeff() > kNegligibleColumn * scale->maxCoeff())) return false;
  const Eigen::VectorXd inv = scale->cwiseInverse();
  for (Eigen::Index c = 0; c < n; ++c)
    N.col(c).tail(n - c).array() *= inv[c] * inv.tail(n - c).array();
  return true;
}

double normalConditionSquared(const Eigen::MatrixXd& N) {
  const Eigen::VectorXd ev =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(N, Eigen::EigenvaluesOnly).eigenvalues();
  return ev[0] > 0 ? ev[ev.size() - 1] / ev[0] : std::numeric_limits<double>::infinity();
}

bool clearlyFullRank(const Eigen::MatrixXd& J) {
  const Eigen::Index n = J.cols();
  if (n == 0 || J.rows() < n) return false;
  Eigen::MatrixXd N = Eigen::MatrixXd::Zero(n, n);
  N.selfadjointView<Eigen::Lower>().rankUpdate(J.transpose());
  Eigen::VectorXd scale;
  return scaleNormalMatrix(N, &scale) && normalConditionSquared(N) < 1e10;
}

}  // namespace tolver
