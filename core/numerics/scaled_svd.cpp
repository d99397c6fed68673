#include "core/numerics/scaled_svd.h"

#include <Eigen/QR>
#include <Eigen/SVD>
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

// Singular values by one-sided Jacobi rotations. Not Eigen 3.4.0's BDCSVD: its perturbCol0 reads
// perm(l - 1) at l = 0, before its buffer (AddressSanitizer: heap-buffer-overflow), on the
// column-scaled identification matrices with exactly zero columns and equal columns that rank
// decisions meet; Jacobi is also accurate to the last bits of the small singular values that
// decide a rank. These matrices are at most a few hundred columns square (compressRows).
Eigen::VectorXd singularValuesOf(const Eigen::MatrixXd& A) {
  return Eigen::JacobiSVD<Eigen::MatrixXd>(A).singularValues();
}

double conditionOf(const Eigen::VectorXd& sv) {
  if (sv.size() == 0) return 0.0;
  return sv[sv.size() - 1] > 0 ? sv[0] / sv[sv.size() - 1] : std::numeric_limits<double>::infinity();
}

}  // namespace

SvdSummary summariseScaled(const Eigen::MatrixXd& S, int rows) {
  SvdSummary out;
  out.rows = rows;
  out.cols = static_cast<int>(S.cols());
  if (S.cols() == 0) return out;
  out.singular_values = singularValuesOf(S);
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
  return conditionOf(singularValuesOf(compressRows(J)));
}

double scaledCondition(const Eigen::MatrixXd& J) {
  if (J.cols() == 0) return 0.0;
  return conditionOf(singularValuesOf(compressRows(scaleColumns(J))));
}

}  // namespace tolver
