#pragma once
// Statistics for residual analysis and model selection: distribution tails, the Lomb-Scargle
// periodogram of unevenly sampled data, the runs test, autocorrelation.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace tolver {

// Quantiles of a long stream of values >= 0 in bounded memory (a program's per-point bands read
// block by block): each value counted in a bin of relative width 2^-16, its double's exponent and
// first 16 mantissa bits, the bins of an exponent allocated when a value of it first comes (256 kB
// each; values within a factor of 2^k of each other need k + 1). A quantile is its bin's
// midpoint, within 1.6e-5 of the value (relative); zeros are exact. Negative and NaN values count
// as zero, infinite ones as the largest finite.
class StreamQuantiles {
 public:
  StreamQuantiles();
  ~StreamQuantiles();
  StreamQuantiles(StreamQuantiles&&) noexcept;
  StreamQuantiles& operator=(StreamQuantiles&&) noexcept;
  void add(double v);
  size_t count() const { return count_; }
  // The value of rank k (0-based, in sorted order; k < count()), e.g. k = count() / 2 for the
  // median as nth_element takes it.
  double ranked(size_t k) const;

 private:
  size_t count_ = 0, zeros_ = 0;
  std::vector<std::unique_ptr<std::uint32_t[]>> exponent_;  // per exponent, 65536 bins or none
};

// Regularised incomplete beta function I_x(a, b), a, b > 0, 0 <= x <= 1 (Boost.Math ibeta).
double incompleteBeta(double a, double b, double x);
// P(F > f) for an F distribution with d1, d2 degrees of freedom (Boost.Math fisher_f; 1 when
// f, d1 or d2 is not positive).
double fSurvival(double f, double d1, double d2);
// P(Z > z) for a standard normal Z.
double normalSurvival(double z);
// The p-quantile of a chi-square distribution with dof > 0 degrees of freedom (Boost.Math).
double chiSquareQuantile(double p, double dof);
// The radius r with P(|e| <= r) = p for a Gaussian e ~ N(0, C) in n dimensions, given C's
// eigenvalues: |e|^2 = sum_k lambda_k z_k^2, matched in mean and variance to g chi2_h
// (Welch-Satterthwaite: g = sum lambda^2 / sum lambda, h = (sum lambda)^2 / sum lambda^2), exact
// when one eigenvalue holds all the variance or all are equal. 0 when C is zero.
double gaussianRadiusQuantile(const double* eigenvalues, int n, double p);
// The mean of x and its standard error when x falls in correlated blocks (block[i] in 0..blocks-1,
// -1: left out): the clustered (ratio) estimator over the blocks' sums, se^2 = B / (B - 1)
// sum_b (S_b - mean n_b)^2 / N^2. One element per block gives the ordinary standard error of
// the mean. se is infinite with fewer than two non-empty blocks.
double blockMean(const std::vector<double>& x, const std::vector<int>& block, int blocks,
                 double* standard_error);

// Lomb-Scargle periodogram (Lomb 1976, Scargle 1982) of y(t), unevenly sampled, at angular
// frequencies omega (rad per unit of t), normalised by the variance of y: a pure sinusoid fit
// at omega explains the fraction 2 P / (n - 1) of the variance. y's mean is removed.
std::vector<double> lombScargle(const std::vector<double>& t, const std::vector<double>& y,
                                const std::vector<double>& omega);
// False-alarm probability of a normalised periodogram peak P among `independent` frequencies.
double periodogramFalseAlarm(double power, double independent);

// Wald-Wolfowitz runs test on the signs of x (zeros skipped): z < 0 when there are fewer runs
// than chance would give (correlated, structured residuals). p: two-sided.
struct RunsTest {
  int runs = 0, positive = 0, negative = 0;
  double z = 0.0, p_value = 1.0;
};
RunsTest runsTest(const std::vector<double>& x);

// Lag-1 autocorrelation of x over the consecutive pairs (i - 1, i) with same_run[i] true.
double lagOneAutocorrelation(const std::vector<double>& x, const std::vector<bool>& same_run);

}  // namespace tolver
