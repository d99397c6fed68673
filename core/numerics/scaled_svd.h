#pragma once
// Column scaling for rank and condition decisions, one policy for the whole core
// (identifiability, identification, gross readings, test plans, diagnosis):
//   * each column is divided by its Euclidean norm, so millimetres and radians do not mix;
//   * a column whose norm is at most kNegligibleColumn of the largest is numerically zero (its
//     entries are rounding): it is not scaled up but set to zero, and counts as no effect;
//   * a singular value counts towards the rank when it exceeds kRankTolerance times the largest.
#include <Eigen/Core>

namespace tolver {

constexpr double kRankTolerance = 1e-9;
constexpr double kNegligibleColumn = 1e-10;

// Column norms of J, with numerically zero columns set to 0.
Eigen::VectorXd columnScales(const Eigen::MatrixXd& J);

// J with each column divided by its norm, numerically zero columns set to zero. `divisors`
// (optional) receives what each column was divided by, 1 for a zero column, so that a solution
// x_s of the scaled problem is x = x_s ./ divisors in the original units.
Eigen::MatrixXd scaleColumns(const Eigen::MatrixXd& J, Eigen::VectorXd* divisors = nullptr);

// The number of singular values (decreasing) above kRankTolerance times the largest.
int numericalRank(const Eigen::VectorXd& singular_values);

struct SvdSummary {
  int rows = 0, cols = 0;
  int rank = 0;
  double condition = 0.0;           // sigma_max / sigma_min; infinity when rank < cols
  double condition_unscaled = 0.0;  // the same without column scaling (mm, rad), as the
                                    // [AM01] reports it
  Eigen::VectorXd singular_values;  // of the column-scaled matrix, decreasing
};

// Rank, condition and singular values of J after scaleColumns (zero columns count as
// rank-deficient); condition_unscaled of J as it is.
SvdSummary analyseColumns(const Eigen::MatrixXd& J);

// The summary of a matrix already scaled (scaleColumns, or columns of its compressRows) that
// stands for `rows` rows.
SvdSummary summariseScaled(const Eigen::MatrixXd& S, int rows);

// sigma_max / sigma_min of scaleColumns(J); infinity when sigma_min is zero.
double scaledCondition(const Eigen::MatrixXd& J);
// The same of J as it is (mm and rad mixed, as [AM01] reports it).
double unscaledCondition(const Eigen::MatrixXd& J);

// The normal matrix N = A^T A of a matrix A (its lower triangle, all that is read) scaled in
// place as A's columns would be by scaleColumns: unit diagonal. `scale` receives the column
// norms, sqrt(diag N). False (N left part-scaled) when a column is numerically zero.
bool scaleNormalMatrix(Eigen::MatrixXd& N, Eigen::VectorXd* scale);
// kappa(A)^2 = the ratio of the extreme eigenvalues of N = A^T A (lower triangle); infinity when
// N is not positive definite.
double normalConditionSquared(const Eigen::MatrixXd& N);

// True when scaleColumns(J) has no zero column and a condition number below 1e5, judged by the
// eigenvalues of its normal matrix (their ratio below 1e10: each is then accurate to well within
// the ratio, so full rank needs no singular value decomposition). False says nothing: decide by
// summariseScaled.
bool clearlyFullRank(const Eigen::MatrixXd& J);

// The upper-triangular factor R of J = QR: the same singular values as J for any subset of its
// columns, at a fraction of the size (J itself when it has no more rows than columns).
Eigen::MatrixXd compressRows(const Eigen::MatrixXd& J);

}  // namespace tolver
