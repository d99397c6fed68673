// maximiseMinOfAffine against an independent truth: the optimum of a max-min of affine functions
// in n variables lies where n + 1 of them are equal, so enumerating every (n+1)-subset, solving
// for its common point and keeping the best feasible value gives the answer by brute force.
#include "core/numerics/max_min_affine.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <functional>
#include <random>

namespace tolver {
namespace {

double bruteForce(const Eigen::MatrixXd& g, const Eigen::VectorXd& c) {
  const int m = static_cast<int>(g.rows()), n = static_cast<int>(g.cols());
  double best = -1e300;
  std::vector<int> idx(n + 1);
  // All (n+1)-subsets by a counter.
  std::function<void(int, int)> rec = [&](int start, int depth) {
    if (depth == n + 1) {
      // c_k + g_k x - t = 0 for k in the subset.
      Eigen::MatrixXd a(n + 1, n + 1);
      Eigen::VectorXd b(n + 1);
      for (int i = 0; i <= n; ++i) {
        a.row(i).head(n) = g.row(idx[i]);
        a(i, n) = -1.0;
        b[i] = -c[idx[i]];
      }
      Eigen::FullPivLU<Eigen::MatrixXd> lu(a);
      if (lu.rank() < n + 1) return;
      const Eigen::VectorXd z = lu.solve(b);
      best = std::max(best, (c + g * z.head(n)).minCoeff());
      return;
    }
    for (int k = start; k < m; ++k) {
      idx[depth] = k;
      rec(k + 1, depth + 1);
    }
  };
  rec(0, 0);
  return best;
}

TEST(MaxMinAffine, OneVariableAnalytic) {
  // min(x, 10 - x) is largest at x = 5, value 5.
  Eigen::MatrixXd g(2, 1);
  g << 1, -1;
  Eigen::VectorXd c(2);
  c << 0, 10;
  const MaxMinResult r = maximiseMinOfAffine(g, c);
  ASSERT_EQ(r.status, MaxMinStatus::Optimal);
  EXPECT_NEAR(r.x[0], 5.0, 1e-12);
  EXPECT_NEAR(r.value, 5.0, 1e-12);
}

TEST(MaxMinAffine, UnboundedWhenEveryFunctionRises) {
  Eigen::MatrixXd g(2, 2);
  g << 1, 0, 1, 1;  // both rise along x0
  Eigen::VectorXd c(2);
  c << 0, 3;
  EXPECT_EQ(maximiseMinOfAffine(g, c).status, MaxMinStatus::Unbounded);
}

TEST(MaxMinAffine, BoxMarginInThreeDimensionsIsTheHalfWidth) {
  // Points shifted by x inside a box [-a_j, a_j] with one point at p: margin = a_j - |p_j + x_j|.
  Eigen::MatrixXd g(6, 3);
  Eigen::VectorXd c(6);
  const Eigen::Vector3d a(380, 255, 255), p(100, -40, 7);
  for (int j = 0; j < 3; ++j) {
    g.row(2 * j).setZero();
    g(2 * j, j) = 1;  // p_j + x_j + a_j
    c[2 * j] = p[j] + a[j];
    g.row(2 * j + 1).setZero();
    g(2 * j + 1, j) = -1;  // a_j - p_j - x_j
    c[2 * j + 1] = a[j] - p[j];
  }
  const MaxMinResult r = maximiseMinOfAffine(g, c);
  ASSERT_EQ(r.status, MaxMinStatus::Optimal);
  EXPECT_NEAR(r.value, 255.0, 1e-9);
  EXPECT_NEAR(r.x[0], -100.0, 125.0 + 1e-9);  // x0 free within the slack of the widest axis
}

TEST(MaxMinAffine, MatchesBruteForceOnRandomProblems) {
  std::mt19937 rng(2026);
  std::normal_distribution<double> nd(0.0, 1.0);
  int optimal = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 1 + trial % 3;
    const int m = n + 2 + static_cast<int>(rng() % 9);
    Eigen::MatrixXd g(m, n);
    Eigen::VectorXd c(m);
    for (int k = 0; k < m; ++k) {
      for (int j = 0; j < n; ++j) g(k, j) = nd(rng);
      c[k] = 100.0 * nd(rng);
    }
    // Degenerate copies: repeated and scaled rows.
    if (trial % 5 == 0) {
      g.row(m - 1) = g.row(0);
      c[m - 1] = c[0];
    }
    const MaxMinResult r = maximiseMinOfAffine(g, c);
    if (r.status == MaxMinStatus::Unbounded) {
      // Then some direction raises every function: the value keeps growing along it, so a
      // point far out beats every vertex the enumeration finds.
      continue;
    }
    ASSERT_EQ(r.status, MaxMinStatus::Optimal) << trial;
    ++optimal;
    const double truth = bruteForce(g, c);
    EXPECT_NEAR(r.value, truth, 1e-7 * (1.0 + std::abs(truth))) << trial;
  }
  EXPECT_GT(optimal, 100);  // the comparison ran on most problems
}

TEST(MaxMinAffine, BoundedProblemsAreNeverCalledUnbounded) {
  // Every direction has a decreasing function when the rows span a box in both signs.
  std::mt19937 rng(7);
  std::normal_distribution<double> nd(0.0, 1.0);
  for (int trial = 0; trial < 50; ++trial) {
    const int n = 3, m = 20;
    Eigen::MatrixXd g(m + 2 * n, n);
    Eigen::VectorXd c(m + 2 * n);
    for (int k = 0; k < m; ++k) {
      for (int j = 0; j < n; ++j) g(k, j) = nd(rng);
      c[k] = 500.0 * nd(rng);
    }
    g.bottomRows(2 * n).setZero();
    for (int j = 0; j < n; ++j) {
      g(m + 2 * j, j) = 1.0;
      g(m + 2 * j + 1, j) = -1.0;
      c[m + 2 * j] = c[m + 2 * j + 1] = 1000.0;
    }
    const MaxMinResult r = maximiseMinOfAffine(g, c);
    ASSERT_EQ(r.status, MaxMinStatus::Optimal) << trial;
    EXPECT_NEAR(r.value, bruteForce(g, c), 1e-7 * 1000.0) << trial;
  }
}

}  // namespace
}  // namespace tolver
