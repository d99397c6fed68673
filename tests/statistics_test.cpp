// Statistics for residual analysis and selection against closed forms and synthetic data.
#include "core/numerics/statistics.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "core/diagnosis/residual_analysis.h"
#include "io/machine/ballbar_file.h"
#include "io/machine/machine_file.h"

namespace tolver {
namespace {

TEST(Statistics, IncompleteBetaClosedForms) {
  EXPECT_NEAR(incompleteBeta(2, 3, 0.5), 0.6875, 1e-14);  // 11/16
  for (double x : {0.1, 0.4, 0.9}) {
    EXPECT_NEAR(incompleteBeta(1, 1, x), x, 1e-14);
    EXPECT_NEAR(incompleteBeta(1, 4, x), 1 - std::pow(1 - x, 4), 1e-14);
    EXPECT_NEAR(incompleteBeta(3, 1, x), std::pow(x, 3), 1e-14);
  }
}

TEST(Statistics, FSurvivalClosedForms) {
  // d1 = 2: P(F > f) = (1 + 2 f / d2)^(-d2 / 2).
  for (double f : {0.5, 3.0, 12.0})
    EXPECT_NEAR(fSurvival(f, 2, 10), std::pow(1 + 2 * f / 10, -5), 1e-13);
  // d1 = 1, d2 large: F = Z^2.
  EXPECT_NEAR(fSurvival(4.0, 1, 1e7), 2 * normalSurvival(2.0), 1e-6);
  EXPECT_EQ(fSurvival(0.0, 3, 10), 1.0);
  EXPECT_NEAR(normalSurvival(1.959963984540054), 0.025, 1e-12);
}

// Chi-square quantiles against tables (closed form for 2 degrees of freedom: -2 ln(1 - p)), and
// the Gaussian radius against its cases of exact form and a Monte Carlo draw of an anisotropic one.
TEST(Statistics, ChiSquareQuantileAndGaussianRadius) {
  EXPECT_NEAR(chiSquareQuantile(0.95, 1), 1.959964 * 1.959964, 1e-5);
  EXPECT_NEAR(chiSquareQuantile(0.95, 2), -2 * std::log(0.05), 1e-10);
  EXPECT_NEAR(chiSquareQuantile(0.95, 3), 7.814728, 1e-5);
  const double one[3] = {4.0, 0.0, 0.0}, equal[2] = {1.0, 1.0}, zero[2] = {0.0, 0.0};
  EXPECT_NEAR(gaussianRadiusQuantile(one, 3, 0.95), 2 * 1.959964, 1e-5);
  EXPECT_NEAR(gaussianRadiusQuantile(equal, 2, 0.95), std::sqrt(-2 * std::log(0.05)), 1e-10);
  EXPECT_EQ(gaussianRadiusQuantile(zero, 2, 0.95), 0.0);
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  for (const auto& l : {std::vector<double>{4.0, 1.0, 0.25}, std::vector<double>{1.0, 0.3, 0.0},
                        std::vector<double>{2.0, 2.0, 0.1}}) {
    const double r = gaussianRadiusQuantile(l.data(), 3, 0.95);
    int inside = 0;
    const int draws = 200000;
    for (int k = 0; k < draws; ++k) {
      double s = 0;
      for (double v : l) s += v * std::pow(n(rng), 2);
      inside += std::sqrt(s) <= r;
    }
    EXPECT_NEAR(inside / double(draws), 0.95, 0.006) << l[0] << " " << l[1] << " " << l[2];
  }
}

// The blocks' standard error: the ordinary one with one element per block (closed form), and on
// correlated blocks the spread of the mean over repeated draws (Monte Carlo), which the
// ordinary standard error understates.
TEST(Statistics, BlockMeanStandardErrorFollowsTheSpreadOfCorrelatedBlocks) {
  const std::vector<double> x = {1.0, 2.0, 4.0, 7.0};
  double se = 0;
  EXPECT_DOUBLE_EQ(blockMean(x, {0, 1, 2, 3}, 4, &se), 3.5);
  // Deviations -2.5 -1.5 0.5 3.5: sum of squares 21, ordinary se = sqrt(21 / 3 / 4).
  EXPECT_NEAR(se, std::sqrt(21.0 / 12.0), 1e-12);
  blockMean(x, {0, 0, 0, 0}, 1, &se);
  EXPECT_TRUE(std::isinf(se));
  EXPECT_DOUBLE_EQ(blockMean(x, {0, -1, 1, -1}, 2, &se), 2.5);  // -1: left out
  // 12 blocks of 20 elements sharing a block effect (sd 1) over independent noise (sd 1).
  std::mt19937 rng(17);
  std::normal_distribution<double> n(0.0, 1.0);
  const int blocks = 12, per = 20, draws = 4000;
  std::vector<int> block(blocks * per);
  for (int i = 0; i < blocks * per; ++i) block[i] = i / per;
  double sum_mean2 = 0, sum_se2 = 0, sum_naive2 = 0;
  std::vector<double> y(blocks * per);
  for (int d = 0; d < draws; ++d) {
    for (int b = 0; b < blocks; ++b) {
      const double shared = n(rng);
      for (int i = 0; i < per; ++i) y[b * per + i] = shared + n(rng);
    }
    const double m = blockMean(y, block, blocks, &se);
    sum_mean2 += m * m;
    sum_se2 += se * se;
    double ss = 0;
    for (double v : y) ss += (v - m) * (v - m);
    sum_naive2 += ss / (y.size() - 1) / y.size();
  }
  // The true variance of the mean: (1 + 1/20) / 12.
  EXPECT_NEAR(sum_mean2 / draws, 1.05 / 12, 0.006);
  EXPECT_NEAR(sum_se2 / draws, 1.05 / 12, 0.006);
  EXPECT_LT(sum_naive2 / draws, 0.2 * 1.05 / 12);
}

TEST(Statistics, LombScargleFindsThePeriodOfUnevenSamples) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(0, 300);
  std::normal_distribution<double> n(0, 0.5);
  std::vector<double> t(200), y(200);
  for (int i = 0; i < 200; ++i) {
    t[i] = u(rng);
    y[i] = 2.0 * std::sin(2 * M_PI * t[i] / 12.0 + 0.3) + n(rng);
  }
  std::vector<double> omega;
  for (double f = 1.0 / 100; f <= 0.5; f += 1.0 / 1500) omega.push_back(2 * M_PI * f);
  const std::vector<double> P = lombScargle(t, y, omega);
  const size_t k = std::max_element(P.begin(), P.end()) - P.begin();
  EXPECT_NEAR(2 * M_PI / omega[k], 12.0, 0.05);
  // The sinusoid carries 2 / (2 + 0.25) of the variance.
  EXPECT_NEAR(2 * P[k] / 199, 2.0 / 2.25, 0.05);
  EXPECT_LT(periodogramFalseAlarm(P[k], 150), 1e-20);
  // Pure noise: no significant peak.
  for (double& v : y) v = n(rng);
  const std::vector<double> Q = lombScargle(t, y, omega);
  EXPECT_GT(periodogramFalseAlarm(*std::max_element(Q.begin(), Q.end()), 150), 0.01);
}

// The periodogram by its definition (Scargle 1982, eq. 10), four trigonometric calls a sample.
std::vector<double> lombScargleByDefinition(const std::vector<double>& t,
                                            const std::vector<double>& y,
                                            const std::vector<double>& omega) {
  const size_t n = t.size();
  double mean = 0, var = 0;
  for (double v : y) mean += v / static_cast<double>(n);
  for (double v : y) var += (v - mean) * (v - mean) / static_cast<double>(n - 1);
  std::vector<double> P;
  for (double w : omega) {
    double s2 = 0, c2 = 0;
    for (double ti : t) s2 += std::sin(2 * w * ti), c2 += std::cos(2 * w * ti);
    const double tau = std::atan2(s2, c2) / (2 * w);
    double yc = 0, ys = 0, cc = 0, ss = 0;
    for (size_t i = 0; i < n; ++i) {
      const double c = std::cos(w * (t[i] - tau)), s = std::sin(w * (t[i] - tau));
      yc += (y[i] - mean) * c, ys += (y[i] - mean) * s, cc += c * c, ss += s * s;
    }
    P.push_back(0.5 * (yc * yc / cc + ys * ys / ss) / var);
  }
  return P;
}

TEST(Statistics, LombScargleByRotationsEqualsItsDefinition) {
  // Uneven samples over 600 mm; a grid made by adding its step (as the residual analysis makes
  // it: the step repeats to rounding), one with a jump in it, and an uneven one.
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(-300, 300);
  std::normal_distribution<double> n(0, 1);
  std::vector<double> t(3000), y(3000);
  for (size_t i = 0; i < t.size(); ++i) {
    t[i] = u(rng);
    y[i] = std::sin(2 * M_PI * t[i] / 37.0) + n(rng);
  }
  std::vector<double> added, jump, uneven;
  for (double f = 0.01; f <= 0.5; f += 1.0 / 3000) added.push_back(2 * M_PI * f);
  jump = added;
  for (size_t k = 100; k < jump.size(); ++k) jump[k] += 1e-3;
  for (int k = 1; k < 200; ++k) uneven.push_back(0.01 * k * k);
  for (const std::vector<double>* omega : {&added, &jump, &uneven}) {
    const std::vector<double> P = lombScargle(t, y, *omega);
    const std::vector<double> Q = lombScargleByDefinition(t, y, *omega);
    ASSERT_EQ(P.size(), Q.size());
    double worst = 0;
    for (size_t k = 0; k < P.size(); ++k)
      worst = std::max(worst, std::abs(P[k] - Q[k]) / std::max(1.0, Q[k]));
    EXPECT_LT(worst, 1e-9) << omega->size() << " frequencies";
  }
}

TEST(Statistics, RunsTestAndAutocorrelation) {
  std::vector<double> blocks(100), alternating(100);
  for (int i = 0; i < 100; ++i) {
    blocks[i] = i < 50 ? 1 : -1;
    alternating[i] = i % 2 ? 1 : -1;
  }
  const RunsTest b = runsTest(blocks);
  EXPECT_EQ(b.runs, 2);
  EXPECT_LT(b.z, -9);
  EXPECT_LT(b.p_value, 1e-15);
  const RunsTest a = runsTest(alternating);
  EXPECT_EQ(a.runs, 100);
  EXPECT_GT(a.z, 9);
  const std::vector<bool> same(100, true);
  EXPECT_NEAR(lagOneAutocorrelation(alternating, same), -0.99, 1e-12);
  EXPECT_NEAR(lagOneAutocorrelation(blocks, same), 0.97, 1e-12);  // (98 - 1) / 100
}

// Residual analysis on the poses of the clean sample test with planted structure.
class Analysis : public ::testing::Test {
 protected:
  void SetUp() override {
    machine_ = readMachineFile(std::string(TOLVER_SOURCE_DIR) +
                               "/resources/machines/matsuura_mc760vx.xml");
    test_ = readBallbarFile(std::string(TOLVER_SOURCE_DIR) + "/samples/ballbar/clean.csv",
                            machine_.model, true)
                .test;
    std::mt19937 rng(9);
    std::normal_distribution<double> n(0, 0.5e-3);
    noise_.resize(test_.readings.size());
    for (Eigen::Index i = 0; i < noise_.size(); ++i) noise_[i] = n(rng);
  }
  Machine machine_;
  BallbarTest test_;
  Eigen::VectorXd noise_;
};

TEST_F(Analysis, WhiteNoiseFollowsNothing) {
  const ResidualAnalysis a = analyseResiduals(machine_.model, test_, noise_);
  EXPECT_TRUE(a.follows.empty()) << a.follows;
  EXPECT_NEAR(a.rms, 0.5e-3, 0.06e-3);
  EXPECT_FALSE(a.repeats.empty());  // the plan's returns to a reference pose
}

TEST_F(Analysis, ACyclicResidualFollowsItsAxisAndPeriod) {
  Eigen::VectorXd r = noise_;
  for (size_t i = 0; i < test_.readings.size(); ++i)
    r[i] += 2e-3 * std::sin(2 * M_PI * test_.readings[i].q[1] / 15.0);
  const ResidualAnalysis a = analyseResiduals(machine_.model, test_, r);
  EXPECT_EQ(a.follows, "Y");
  EXPECT_EQ(a.findings[0].test, "periodogram");
  EXPECT_NEAR(a.findings[0].period, 15.0, 0.1);
  EXPECT_GT(a.follows_strength, 0.7);
}

TEST_F(Analysis, AReversalResidualFollowsTheApproachDirection) {
  Eigen::VectorXd r = noise_;
  for (size_t i = 0; i < test_.readings.size(); ++i)
    r[i] += 1.5e-3 * test_.readings[i].context.direction[0];
  const ResidualAnalysis a = analyseResiduals(machine_.model, test_, r);
  EXPECT_EQ(a.follows, "X direction");
}

TEST_F(Analysis, ADriftFollowsTime) {
  Eigen::VectorXd r = noise_;
  for (size_t i = 0; i < test_.readings.size(); ++i)
    r[i] += 2e-3 * test_.readings[i].context.time_s / 7200.0;
  const ResidualAnalysis a = analyseResiduals(machine_.model, test_, r);
  EXPECT_EQ(a.follows, "time");
  double span = 0;
  for (const RepeatedPose& p : a.repeats) span = std::max(span, p.span_mm);
  EXPECT_GT(span, 0.5e-3);  // the reference pose drifts
}

}  // namespace
}  // namespace tolver

namespace tolver {
namespace {

// The streamed quantiles against the sorted values: within half a bin (2^-17 of the value) over
// twelve decades, zeros exact, negative and NaN values counted as zeros, the count kept.
TEST(Statistics, StreamQuantilesMatchTheSortedValuesToTheirBinWidth) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> decade(-9.0, 3.0);
  std::vector<double> v;
  StreamQuantiles q;
  for (int i = 0; i < 200000; ++i) {
    const double x = i % 50 == 0 ? 0.0 : std::pow(10.0, decade(rng));
    v.push_back(x);
    q.add(x);
  }
  for (const double bad : {-1.0, std::nan("")}) {
    v.push_back(0.0);
    q.add(bad);
  }
  ASSERT_EQ(q.count(), v.size());
  std::sort(v.begin(), v.end());
  std::vector<size_t> ranks = {v.size() / 50, v.size() / 50 + 1, v.size() / 2, v.size() - 1};
  for (size_t k = 0; k < v.size(); k += 997) ranks.push_back(k);
  for (size_t k : ranks) {
    const double got = q.ranked(k), want = v[k];
    if (want == 0.0)
      EXPECT_EQ(got, 0.0) << k;
    else
      EXPECT_LE(std::abs(got - want), std::ldexp(want, -17)) << k << ": " << got << " " << want;
  }
}

}  // namespace
}  // namespace tolver
