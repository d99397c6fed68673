// Closing the loop: on simulated tests of a machine with one undeclared effect, the
// diagnosis finds that effect (type and axis), its values within three standard uncertainties
// of the truth, and a held-out RMS at the noise level; on clean data it adds nothing.
#include "core/diagnosis/diagnosis.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <random>

#include "core/calibration/ballbar_plan.h"
#include "core/model/effects.h"
#include "io/machine/ballbar_file.h"
#include "io/machine/machine_file.h"
#include "test_support.h"

namespace tolver {
namespace {

// Lack of fit by hand: residuals 1, 3 at one pose, 2, 2 at another, 0 alone; one unknown fitted.
// SS_pe = 2 (df 2), RSS = 18, SS_lof = 16 (df 5 - 1 - 2 = 2), F = 8, and F(2, 2) has the tail
// 1 / (1 + F) = 1/9.
TEST(LackOfFit, ByHandWithTheFTail) {
  BallbarTest t;
  t.setups.resize(1);
  const double x[5] = {1, 1, 2, 2, 3};
  for (double v : x) {
    BallbarReading r;
    r.q = JointVector::Zero(2);
    r.q[0] = v;
    t.readings.push_back(r);
  }
  Eigen::VectorXd res(5);
  res << 1, 3, 2, 2, 0;
  const LackOfFit l = lackOfFit(t, res, 1);
  ASSERT_TRUE(l.tested);
  EXPECT_EQ(l.poses, 2);
  EXPECT_EQ(l.repeats, 4);
  EXPECT_DOUBLE_EQ(l.df_pure, 2);
  EXPECT_DOUBLE_EQ(l.df_lack, 2);
  EXPECT_NEAR(l.s_pure, 1.0, 1e-15);
  EXPECT_NEAR(l.f, 8.0, 1e-12);
  EXPECT_NEAR(l.p_value, 1.0 / 9.0, 1e-12);
  EXPECT_NEAR(l.missing_rms, std::sqrt(18.0 / 4 - 1.0), 1e-12);
  // The same pose in another set-up is another pose; no repeats: not tested.
  t.readings[1].setup = 1;
  t.setups.resize(2);
  t.readings[3].q[0] = 2.5;
  EXPECT_FALSE(lackOfFit(t, res, 1).tested);
}

// Simulated: a straight line fitted to a parabola with replicates fails the test; fitted to a
// line it passes about as often as the level says.
TEST(LackOfFit, DetectsAMissingTermAndNotAnAdequateOne) {
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 1.0);
  int rejected_adequate = 0, rejected_missing = 0;
  for (int run = 0; run < 200; ++run) {
    BallbarTest t;
    t.setups.resize(1);
    Eigen::VectorXd y_line(30), y_curve(30);
    Eigen::MatrixXd X(30, 2);
    for (int i = 0; i < 30; ++i) {
      BallbarReading r;
      r.q = JointVector::Zero(1);
      r.q[0] = i % 10;  // ten poses, three readings each
      t.readings.push_back(r);
      const double xv = r.q[0];
      X(i, 0) = 1;
      X(i, 1) = xv;
      y_line[i] = 2 + 0.5 * xv + noise(rng);
      y_curve[i] = 2 + 0.5 * xv + 0.15 * (xv - 4.5) * (xv - 4.5) + noise(rng);
    }
    const Eigen::MatrixXd H = X * (X.transpose() * X).inverse() * X.transpose();
    const Eigen::VectorXd r_line = y_line - H * y_line, r_curve = y_curve - H * y_curve;
    rejected_adequate += lackOfFit(t, r_line, 2).p_value < 0.05;
    rejected_missing += lackOfFit(t, r_curve, 2).p_value < 0.05;
  }
  EXPECT_LE(rejected_adequate, 20);  // about 5 % of 200
  EXPECT_GE(rejected_missing, 180);
}

constexpr double kNoiseMm = 0.5e-3;

struct Dataset {
  Machine nominal, truth;
  BallbarFile readings;
};

Dataset load(const std::string& name) {
  Dataset d;
  d.nominal = readMachineFile(test::sourcePath("resources/machines/matsuura_mc760vx.xml"));
  d.truth = readMachineFile(test::sourcePath("samples/ballbar/truth_" + name + ".xml"));
  d.readings =
      readBallbarFile(test::sourcePath("samples/ballbar/" + name + ".csv"), d.nominal.model, true);
  return d;
}

void printResult(const std::string& name, const DiagnosisResult& r, double seconds) {
  std::printf("[ %s ] %.2f s: rms %.3f -> %.3f um, held-out %.3f -> %.3f um\n", name.c_str(),
              seconds, r.rms_before * 1e3, r.rms_after * 1e3, r.cv_rms_before * 1e3,
              r.cv_rms_after * 1e3);
  for (const AddedEffect& a : r.added) {
    std::printf("    added %s:", a.label.c_str());
    for (Eigen::Index k = 0; k < a.values.size(); ++k)
      std::printf(" %.3g+-%.2g", a.values[k] * 1e3, a.uncertainty[k] * 1e3);
    if (std::isfinite(a.hyperparameter))
      std::printf(" hyper %.4g+-%.2g", a.hyperparameter, a.hyperparameter_uncertainty);
    std::printf("\n");
  }
  std::vector<CandidateScore> c = r.candidates;
  std::sort(c.begin(), c.end(), [](auto& a, auto& b) { return a.delta_ic > b.delta_ic; });
  for (size_t i = 0; i < std::min<size_t>(4, c.size()); ++i)
    std::printf("    r%d %-40s dIC %8.1f p %.2g info %.3f cv %.3f->%.3f %s\n", c[i].round,
                c[i].label.c_str(), c[i].delta_ic, c[i].p_value, c[i].new_information,
                c[i].cv_rms_before * 1e3, c[i].cv_rms_after * 1e3, verdictName(c[i].verdict));
  std::printf("    residual follows: '%s' (%.2f)\n", r.analysis_before.follows.c_str(),
              r.analysis_before.follows_strength);
}

// The effects of the truth machine (type, axis, component) and their values.
struct TruthEffect {
  EffectSpec spec;
  Eigen::VectorXd values;
};

std::vector<TruthEffect> truthEffects(const Machine& truth) {
  std::vector<TruthEffect> out;
  for (const ParameterBlock& b : truth.model.blocks)
    if (b.kind == BlockKind::Effect)
      out.push_back({truth.model.effects[b.effect], truth.params.segment(b.offset, b.size)});
  return out;
}

bool sameKind(const EffectSpec& a, const EffectSpec& b) {
  return a.type == b.type && a.axis == b.axis && a.component == b.component;
}

void expectFindsTruth(const std::string& name) {
  SCOPED_TRACE(name);
  const Dataset d = load(name);
  const auto t0 = std::chrono::steady_clock::now();
  const DiagnosisResult r = diagnose(d.nominal, d.readings.test);
  printResult(name, r,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  ASSERT_TRUE(r.ok) << r.message;
  const std::vector<TruthEffect> truth = truthEffects(d.truth);
  ASSERT_FALSE(truth.empty());
  // Exactly the truth's effects, each with the right type, axis and component.
  ASSERT_EQ(r.added.size(), truth.size());
  for (const TruthEffect& t : truth) {
    const auto it = std::find_if(r.added.begin(), r.added.end(),
                                 [&](const AddedEffect& a) { return sameKind(a.spec, t.spec); });
    ASSERT_NE(it, r.added.end()) << describeEffect(d.truth.model, t.spec) << " not found";
    // Values within three standard uncertainties of the truth. A varying reversal found for a
    // constant one also counts when its slope is zero within its uncertainty.
    ASSERT_GE(it->values.size(), t.values.size());
    for (Eigen::Index k = 0; k < it->values.size(); ++k) {
      const double truth_value = k < t.values.size() ? t.values[k] : 0.0;
      EXPECT_LE(std::abs(it->values[k] - truth_value), 3 * it->uncertainty[k])
          << it->label << " coefficient " << k << ": " << it->values[k] << " +- "
          << it->uncertainty[k] << " vs " << truth_value;
    }
    const double h = hyperparameterValue(t.spec);
    if (std::isfinite(h))
      EXPECT_LE(std::abs(it->hyperparameter - h), 3 * it->hyperparameter_uncertainty)
          << it->label << ": " << it->hyperparameter << " +- " << it->hyperparameter_uncertainty
          << " vs " << h;
  }
  // The held-out error after is at the noise level and below the one before.
  EXPECT_LE(r.cv_rms_after, 1.5 * kNoiseMm);
  EXPECT_LT(r.cv_rms_after, r.cv_rms_before);
  EXPECT_LT(r.rms_after, r.rms_before);
  // Every candidate of every round was scored and kept in the result.
  EXPECT_GT(r.candidates.size(), 50u);
}

TEST(Diagnosis, FindsAHigherChebyshevDegree) { expectFindsTruth("chebyshev"); }
TEST(Diagnosis, FindsReversal) { expectFindsTruth("reversal"); }
TEST(Diagnosis, FindsACyclicErrorAndItsPeriod) { expectFindsTruth("periodic"); }
TEST(Diagnosis, FindsRotaryHarmonics) { expectFindsTruth("harmonics"); }
TEST(Diagnosis, FindsLinearThermalDrift) { expectFindsTruth("drift"); }
TEST(Diagnosis, FindsAThermalWarmUpAndItsTimeConstant) { expectFindsTruth("warmup"); }
TEST(Diagnosis, FindsTheBarLengthError) { expectFindsTruth("bar_length"); }
TEST(Diagnosis, FindsTwoEffectsAtOnce) { expectFindsTruth("two_effects"); }

TEST(Diagnosis, CleanDataGetsNothingAdded) {
  const Dataset d = load("clean");
  const DiagnosisResult r = diagnose(d.nominal, d.readings.test);
  ASSERT_TRUE(r.ok);
  EXPECT_TRUE(r.added.empty());
  EXPECT_EQ(r.rms_after, r.rms_before);
  EXPECT_LE(r.cv_rms_after, 1.5 * kNoiseMm);
  EXPECT_TRUE(r.analysis_before.follows.empty()) << r.analysis_before.follows;
  for (const CandidateScore& c : r.candidates) EXPECT_NE(c.verdict, CandidateVerdict::Added);
}

// Simulated readings of a machine for a plan: noise and ball position errors from a seed.
BallbarTest simulate(const Machine& truth, BallbarTest plan, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, kNoiseMm), ball(0.0, 0.010);
  std::vector<BallErrors> balls(plan.setups.size());
  for (BallErrors& b : balls) {
    b.table_w = Eigen::Vector3d(ball(rng), ball(rng), ball(rng));
    b.tool_t = Eigen::Vector3d(ball(rng), ball(rng), ball(rng));
  }
  const ForwardKinematics fk(truth.model, truth.params);
  for (BallbarReading& r : plan.readings)
    r.length =
        ballbarLength(fk, r.q, plan.setups[r.setup], balls[r.setup], &r.context) + noise(rng);
  return plan;
}

TEST(Diagnosis, OverTwentyNoiseSeedsCleanDataAddsAtMostOnce) {
  const Dataset d = load("clean");
  const std::vector<int> unknowns = defaultCalibrationUnknowns(d.nominal.model);
  DiagnosisOptions opt;
  opt.base_unknowns = unknowns;
  int runs_adding = 0;
  for (unsigned seed = 100; seed < 120; ++seed) {
    const DiagnosisResult r = diagnose(d.nominal, simulate(d.truth, d.readings.test, seed), opt);
    ASSERT_TRUE(r.ok);
    if (!r.added.empty()) {
      ++runs_adding;
      std::printf("[ seed %u ] added %s\n", seed, r.added[0].label.c_str());
    }
  }
  std::printf("[ clean ] 20 noise seeds: %d runs added an effect\n", runs_adding);
  EXPECT_LE(runs_adding, 1);
}

// One bar length: the bar's own length error cannot be told from a uniform machine scale (and
// the ball positions), so it is reported confounded and not added.
TEST(Diagnosis, BarLengthWithOneBarIsReportedConfounded) {
  const Dataset d = load("bar_length");
  BallbarPlanOptions po;
  po.poses = 150;
  const std::vector<int> unknowns = defaultCalibrationUnknowns(d.nominal.model);
  const BallbarPlan plan = planBallbarTest(d.nominal.model, unknowns, po);
  DiagnosisOptions opt;
  opt.base_unknowns = unknowns;
  opt.types = {EffectType::BarLength};
  const DiagnosisResult r = diagnose(d.nominal, simulate(d.truth, plan.test, 7), opt);
  ASSERT_TRUE(r.ok);
  EXPECT_TRUE(r.added.empty());
  ASSERT_EQ(r.candidates.size(), 1u);
  EXPECT_EQ(r.candidates[0].verdict, CandidateVerdict::Confounded);
  EXPECT_LT(r.candidates[0].new_information, 1e-3);
}

TEST(Diagnosis, FoldsAreContiguousRunsWithinSetUps) {
  const Dataset d = load("clean");
  int folds = 0;
  const std::vector<int> f = contiguousFolds(d.readings.test, 6, &folds);
  EXPECT_EQ(folds, 18);
  std::vector<int> count(folds, 0);
  for (size_t i = 0; i < f.size(); ++i) {
    ++count[f[i]];
    if (i > 0) EXPECT_GE(f[i], f[i - 1]);  // each fold one contiguous run
    EXPECT_EQ(f[i] / 6, d.readings.test.readings[i].setup);
  }
  for (int c : count) EXPECT_EQ(c, 20);
}

}  // namespace
}  // namespace tolver
