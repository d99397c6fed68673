#include "core/numerics/max_min_affine.h"

#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace tolver {
namespace {

// The dual in standard form: columns j < m are [1; -g_j] with cost c_j, columns m + i are the
// artificial unit columns e_i; b = e_0.
class DualSimplex {
 public:
  DualSimplex(const Eigen::MatrixXd& g, const Eigen::VectorXd& c)
      : g_(g), c_(c), m_(static_cast<int>(g.rows())), r_(static_cast<int>(g.cols()) + 1) {
    scale_ = 1.0;
    for (int k = 0; k < m_; ++k) scale_ = std::max(scale_, std::abs(c_[k]));
    basis_.resize(r_);
    for (int i = 0; i < r_; ++i) basis_[i] = m_ + i;
    in_basis_.assign(m_ + r_, false);
    for (int i = 0; i < r_; ++i) in_basis_[m_ + i] = true;
    refactor();
  }

  // Runs one phase; false when the iteration limit was reached.
  bool run(bool phase1, int* iterations) {
    int degenerate = 0;
    const double tol = 1e-10 * scale_;
    while (*iterations < kMaxIterations) {
      const Eigen::VectorXd pi = multipliers(phase1);
      // Pricing: Dantzig's rule, Bland's (smallest index) after a run of degenerate pivots.
      const bool bland = degenerate > 30;
      int enter = -1;
      double best = -tol;
      for (int j = 0; j < m_; ++j) {
        if (in_basis_[j]) continue;
        const double d = cost(j, phase1) - pi[0] + g_.row(j).dot(pi.tail(r_ - 1));
        if (d < best) {
          best = d;
          enter = j;
          if (bland) break;
        }
      }
      if (enter < 0) return true;
      const Eigen::VectorXd w = binv_ * column(enter);
      int leave = -1;
      double theta = std::numeric_limits<double>::infinity();
      for (int i = 0; i < r_; ++i) {
        if (w[i] <= 1e-12) continue;
        const double t = xb_[i] / w[i];
        if (t < theta - 1e-15 || (t <= theta + 1e-15 && leave >= 0 && basis_[i] < basis_[leave])) {
          theta = t;
          leave = i;
        }
      }
      if (leave < 0) return true;  // cannot happen: the dual is bounded below by the primal
      degenerate = theta < 1e-13 ? degenerate + 1 : 0;
      pivot(leave, enter);
      ++*iterations;
    }
    return false;
  }

  double artificialSum() const {
    double s = 0.0;
    for (int i = 0; i < r_; ++i)
      if (basis_[i] >= m_) s += std::abs(xb_[i]);
    return s;
  }

  // After phase 1: artificials still basic (at zero) leave for any real column with a non-zero
  // entry in their row; a row with none is redundant and its artificial stays at zero.
  void driveOutArtificials() {
    for (int i = 0; i < r_; ++i) {
      if (basis_[i] < m_) continue;
      for (int j = 0; j < m_; ++j) {
        if (in_basis_[j]) continue;
        const double wi = binv_.row(i).dot(column(j));
        if (std::abs(wi) > 1e-9) {
          pivot(i, j);
          break;
        }
      }
    }
  }

  Eigen::VectorXd multipliers(bool phase1) const {
    Eigen::VectorXd cb(r_);
    for (int i = 0; i < r_; ++i) cb[i] = cost(basis_[i], phase1);
    return binv_.transpose() * cb;
  }

 private:
  static constexpr int kMaxIterations = 20000;

  double cost(int j, bool phase1) const {
    if (j >= m_) return phase1 ? 1.0 : 0.0;
    return phase1 ? 0.0 : c_[j];
  }
  Eigen::VectorXd column(int j) const {
    Eigen::VectorXd a(r_);
    if (j >= m_) {
      a.setZero();
      a[j - m_] = 1.0;
    } else {
      a[0] = 1.0;
      a.tail(r_ - 1) = -g_.row(j).transpose();
    }
    return a;
  }
  void pivot(int leave, int enter) {
    in_basis_[basis_[leave]] = false;
    basis_[leave] = enter;
    in_basis_[enter] = true;
    refactor();
  }
  void refactor() {
    Eigen::MatrixXd b(r_, r_);
    for (int i = 0; i < r_; ++i) b.col(i) = column(basis_[i]);
    binv_ = b.partialPivLu().inverse();
    xb_ = binv_.col(0);  // B^-1 e_0
    for (int i = 0; i < r_; ++i) xb_[i] = std::max(0.0, xb_[i]);
  }

  const Eigen::MatrixXd& g_;
  const Eigen::VectorXd& c_;
  int m_, r_;
  double scale_;
  std::vector<int> basis_;
  std::vector<bool> in_basis_;
  Eigen::MatrixXd binv_;
  Eigen::VectorXd xb_;
};

}  // namespace

MaxMinResult maximiseMinOfAffine(const Eigen::MatrixXd& g, const Eigen::VectorXd& c) {
  if (g.rows() != c.size() || g.cols() < 1 || g.cols() > 8)
    throw std::invalid_argument("maximiseMinOfAffine: g must be m x n (1 <= n <= 8), c of size m");
  MaxMinResult out;
  const int n = static_cast<int>(g.cols());
  out.x = Eigen::VectorXd::Zero(n);
  if (g.rows() == 0) {
    out.status = MaxMinStatus::Unbounded;
    out.value = std::numeric_limits<double>::infinity();
    return out;
  }
  DualSimplex s(g, c);
  int iterations = 0;
  bool converged = s.run(true, &iterations);
  if (converged && s.artificialSum() > 1e-9) {
    // The dual has no feasible point: some direction raises every function.
    out.status = MaxMinStatus::Unbounded;
    out.value = std::numeric_limits<double>::infinity();
    out.iterations = iterations;
    return out;
  }
  if (converged) {
    s.driveOutArtificials();
    converged = s.run(false, &iterations);
  }
  const Eigen::VectorXd pi = s.multipliers(false);
  out.x = pi.tail(n);
  out.value = (c + g * out.x).minCoeff();
  out.iterations = iterations;
  out.status = converged ? MaxMinStatus::Optimal : MaxMinStatus::IterationLimit;
  return out;
}

}  // namespace tolver
