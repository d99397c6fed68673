#pragma once
// The largest value of the smallest of m affine functions of a few variables:
//   maximise t(x) = min_k (c_k + g_k . x),   x in R^n (n small, m large),
// a linear programme, solved exactly through its dual
//   minimise c . y  subject to  sum_k y_k = 1,  G^T y = 0,  y >= 0
// by a two-phase revised simplex (the basis has n + 1 rows, so each iteration costs O(m n)).
// The optimum x is the dual's simplex multipliers; y > 0 marks the active functions.
// Used where a margin must be maximised exactly (a set-up's distance to travel limits).
#include <Eigen/Core>

namespace tolver {

enum class MaxMinStatus {
  Optimal,
  Unbounded,       // t grows without limit (no function decreases along some direction)
  IterationLimit,  // did not converge (x is the last feasible iterate's multipliers)
};

struct MaxMinResult {
  MaxMinStatus status = MaxMinStatus::Optimal;
  Eigen::VectorXd x;   // the maximiser
  double value = 0.0;  // min_k (c_k + g_k . x) at x
  int iterations = 0;
};

// g: m x n, c: m. n <= 8.
MaxMinResult maximiseMinOfAffine(const Eigen::MatrixXd& g, const Eigen::VectorXd& c);

}  // namespace tolver
