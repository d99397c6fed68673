#include "pipeline/parallel_prediction.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "io/machine/machine_file.h"
#include "test_support.h"

namespace tolver {
namespace {

// A long five-axis path (a spiral on a hemisphere, the tool normal to it) with a few points
// beyond the stroke and a few tool axes turned over, so that failures fall in several blocks.
std::vector<ClPoint> longPath(int n, std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<ClPoint> out(n);
  for (int i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / n, polar = 0.05 + 0.9 * t, az = 60.0 * M_PI * t;
    const Eigen::Vector3d u(std::sin(polar) * std::cos(az), std::sin(polar) * std::sin(az),
                            std::cos(polar));
    out[i].p_w = 50.0 * u;
    out[i].u_w = u;
    out[i].line = i + 1;
    const double odd = unit(rng);
    if (odd < 0.002)
      out[i].p_w.x() += 1e4;
    else if (odd < 0.004)
      out[i].u_w = -u;
  }
  return out;
}

bool same(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

// Every number of every point, the failures and the summary, bit for bit.
void expectSameBits(const PredictionResult& r, const PredictionResult& one,
                    const std::string& what) {
  ASSERT_EQ(r.points.size(), one.points.size()) << what;
  for (size_t i = 0; i < r.points.size(); ++i) {
    const PredictedPoint &x = r.points[i], &y = one.points[i];
    const std::string where = what + " point " + std::to_string(i);
    ASSERT_EQ(x.q.size(), y.q.size()) << where;
    for (int k = 0; k < x.q.size(); ++k) ASSERT_TRUE(same(x.q[k], y.q[k])) << where;
    for (int k = 0; k < 3; ++k) {
      ASSERT_TRUE(same(x.p_pred_w[k], y.p_pred_w[k])) << where;
      ASSERT_TRUE(same(x.u_pred_w[k], y.u_pred_w[k])) << where;
      ASSERT_TRUE(same(x.deviation_w[k], y.deviation_w[k])) << where;
    }
    ASSERT_TRUE(same(x.along_axis, y.along_axis) && same(x.across_axis, y.across_axis) &&
                same(x.axis_angle, y.axis_angle))
        << where;
    ASSERT_EQ(x.singular, y.singular) << where;
  }
  EXPECT_EQ(r.failed_points, one.failed_points) << what;
  ASSERT_EQ(r.failures.size(), one.failures.size()) << what;
  for (size_t k = 0; k < r.failures.size(); ++k) {
    EXPECT_EQ(r.failures[k].index, one.failures[k].index) << what;
    EXPECT_EQ(r.failures[k].message, one.failures[k].message) << what;
  }
  EXPECT_EQ(r.failures_per_axis, one.failures_per_axis) << what;
  EXPECT_EQ(r.summary.max_deviation, one.summary.max_deviation) << what;
  EXPECT_EQ(r.summary.max_index, one.summary.max_index) << what;
  EXPECT_EQ(r.summary.rms_deviation, one.summary.rms_deviation) << what;
  EXPECT_EQ(r.summary.rms_axis_angle, one.summary.rms_axis_angle) << what;
  EXPECT_EQ(r.summary.singular_points, one.summary.singular_points) << what;
  EXPECT_EQ(r.summary.first_singular_line, one.summary.first_singular_line) << what;
}

Machine machineWithErrors(const char* file, std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Machine m = readMachineFile(test::sourcePath(file));
  m.model.setup.gauge_length = 100;
  for (int i = 0; i < m.model.parameterCount(); ++i)
    m.params[i] = n(rng) * (m.model.parameters[i].angular ? 30e-6 : 0.01);
  return m;
}

// On several threads, the same bits as on one: every point, the failures and the summary, for
// one, two and four threads (more threads than cores still keeps the order of the choices),
// against the batch path and the one-point-at-a-time reference.
TEST(ParallelPrediction, EqualsTheSingleThreadedPredictionBitForBit) {
  std::mt19937 rng(5);
  for (const char* file : {test::shippedMachines()[0], test::shippedMachines()[5]}) {
    const Machine m = machineWithErrors(file, rng);
    const std::vector<ClPoint> path = longPath(20011, rng);
    const PredictionResult one = predictToolPath(m.model, m.params, path, 7);
    PredictionResult reference;
    predictToolPath(m.model, m.params, path, reference, 7, nullptr, false);
    expectSameBits(one, reference, std::string(file) + " batch against one by one");
    ASSERT_GT(one.failed_points, 10) << file;
    for (int threads : {1, 2, 4}) {
      PredictionResult r;
      ParallelPredictionStats stats;
      predictToolPathParallel(m.model, m.params, path, r, 7, nullptr, threads, &stats);
      expectSameBits(r, one, std::string(file) + " " + std::to_string(threads) + " threads");
      if (threads > 1) {
        EXPECT_GT(stats.stretches, 1) << file;
      }
    }
  }
}

// The path's stretches one after another: its points into one result, for comparing with the
// whole path predicted at once. predict(stretch, result, carry) predicts one stretch.
template <typename Predict>
PredictionResult inStretches(const std::vector<ClPoint>& path, const std::vector<size_t>& sizes,
                             int axes, Predict&& predict) {
  PredictionCarry carry;
  PredictionResult whole, part;
  whole.points.resize(path.size(), axes);
  size_t at = 0;
  for (size_t k = 0; at < path.size(); ++k) {
    const size_t n = std::min(k < sizes.size() ? sizes[k] : path.size(), path.size() - at);
    const std::vector<ClPoint> stretch(path.begin() + at, path.begin() + at + n);
    predict(stretch, part, carry);
    EXPECT_EQ(part.points.size(), n);
    EXPECT_EQ(carry.points(), at + n);
    for (size_t i = 0; i < n; ++i) whole.points.set(at + i, part.points[i]);
    at += n;
  }
  whole.failures = part.failures;  // the whole path's so far, after the last stretch
  whole.failed_points = part.failed_points;
  whole.failures_per_axis = part.failures_per_axis;
  whole.summary = part.summary;
  return whole;
}

// A program read and predicted block by block (PredictionCarry) gives the whole path's
// prediction bit for bit when its stretches hold multiples of kExactEvery points: the batch path
// on one and two threads, the one-point path, commanded joints, and a direction-dependent effect
// (reversal), whose approach directions cross the stretches. A stretch of another length still
// gives the same joints and deviations (its first point is solved with exact angles).
TEST(ParallelPrediction, AProgramPredictedInStretchesIsThePathPredictedAtOnce) {
  std::mt19937 rng(11);
  const size_t e = BlockPrediction::kExactEvery;
  const std::vector<size_t> sizes = {2 * e, e, 3 * e, 4 * e};
  for (const char* file : {test::shippedMachines()[0], test::shippedMachines()[5]}) {
    const Machine m = machineWithErrors(file, rng);
    const int axes = static_cast<int>(m.model.axes.size());
    const std::vector<ClPoint> path = longPath(12 * static_cast<int>(e) + 333, rng);
    const PredictionResult one = predictToolPath(m.model, m.params, path, 7);
    ASSERT_GT(one.failed_points, 10) << file;
    for (int threads : {1, 2}) {
      const PredictionResult r = inStretches(path, sizes, axes, [&](auto& s, auto& res, auto& c) {
        predictToolPathParallel(m.model, m.params, s, res, 7, nullptr, threads, nullptr, &c);
      });
      expectSameBits(r, one, std::string(file) + " stretches, " + std::to_string(threads));
      EXPECT_EQ(r.summary.max_line, path[one.summary.max_index].line);
    }
    PredictionResult reference;
    predictToolPath(m.model, m.params, path, reference, 7, nullptr, false);
    const PredictionResult r = inStretches(path, sizes, axes, [&](auto& s, auto& res, auto& c) {
      predictToolPath(m.model, m.params, s, res, 7, nullptr, false, &c);
    });
    expectSameBits(r, reference, std::string(file) + " one by one in stretches");
    // Commanded joints: the whole path's own solution as the commands.
    std::vector<JointVector> commanded(path.size());
    for (size_t i = 0; i < path.size(); ++i) {
      commanded[i] = one.points[i].q;
      if (!commanded[i].allFinite()) commanded[i] = JointVector::Zero(axes);
    }
    const PredictionResult cmd = predictToolPath(m.model, m.params, path, 7, &commanded);
    size_t at = 0;
    const PredictionResult rc = inStretches(path, sizes, axes, [&](auto& s, auto& res, auto& c) {
      const std::vector<JointVector> part(commanded.begin() + at,
                                          commanded.begin() + at + s.size());
      at += s.size();
      predictToolPath(m.model, m.params, s, res, 7, &part, true, &c);
    });
    expectSameBits(rc, cmd, std::string(file) + " commanded, in stretches");
    // Stretches of any length: the same numbers to the rounding of the exact angles.
    const PredictionResult odd =
        inStretches(path, {5000, 7777, 64}, axes, [&](auto& s, auto& res, auto& c) {
          predictToolPath(m.model, m.params, s, res, 7, nullptr, true, &c);
        });
    EXPECT_EQ(odd.failed_points, one.failed_points);
    double most = 0.0;
    for (size_t i = 0; i < path.size(); ++i)
      if (std::isfinite(one.points[i].deviation_w.x()))
        most = std::max(most, (odd.points[i].deviation_w - one.points[i].deviation_w).norm());
    EXPECT_LT(most, 1e-12) << file;
  }
  // A reversal (backlash) on X: the approach directions are carried across the stretches.
  Machine m = machineWithErrors(test::shippedMachines()[0], rng);
  EffectSpec rev;
  rev.type = EffectType::Reversal;
  rev.axis = 0;
  rev.component = 0;
  const int first = m.model.parameterCount();
  m.model.addEffect(rev);
  m.params.conservativeResize(m.model.parameterCount());
  for (int k = first; k < m.model.parameterCount(); ++k) m.params[k] = 4e-3;
  std::vector<ClPoint> path = longPath(3 * static_cast<int>(e) + 17, rng);
  const PredictionResult one = predictToolPath(m.model, m.params, path, 7);
  const PredictionResult r = inStretches(
      path, {e, e}, static_cast<int>(m.model.axes.size()), [&](auto& s, auto& res, auto& c) {
        predictToolPathParallel(m.model, m.params, s, res, 7, nullptr, 2, nullptr, &c);
      });
  expectSameBits(r, one, "reversal in stretches");
  // (the effect shows: without the carried directions the stretches' first points differ)
  PredictionResult cold;
  const std::vector<ClPoint> second(path.begin() + e, path.begin() + 2 * e);
  predictToolPath(m.model, m.params, second, cold, 7);
  bool differs = false;
  for (size_t i = 0; i < 64 && i < second.size(); ++i)
    differs = differs || !same(cold.points[i].deviation_w.x(), one.points[e + i].deviation_w.x());
  EXPECT_TRUE(differs);
}

// A smooth path: each speculative stretch agrees with the true one after its first block.
TEST(ParallelPrediction, ASmoothPathIsPredictedAgainOneBlockPerStretch) {
  std::mt19937 rng(8);
  const Machine m = machineWithErrors(test::shippedMachines()[0], rng);
  std::vector<ClPoint> path(30000);
  for (size_t i = 0; i < path.size(); ++i) {
    const double t = static_cast<double>(i) / path.size(), polar = 0.3 + 0.5 * t,
                 az = 12.0 * M_PI * t;
    const Eigen::Vector3d u(std::sin(polar) * std::cos(az), std::sin(polar) * std::sin(az),
                            std::cos(polar));
    path[i].p_w = 60.0 * u;
    path[i].u_w = u;
    path[i].line = static_cast<int>(i) + 1;
  }
  const PredictionResult one = predictToolPath(m.model, m.params, path);
  for (int threads : {2, 4}) {
    PredictionResult r;
    ParallelPredictionStats stats;
    predictToolPathParallel(m.model, m.params, path, r, 20, nullptr, threads, &stats);
    expectSameBits(r, one, std::to_string(threads) + " threads");
    EXPECT_EQ(stats.stretches, threads);
    EXPECT_EQ(stats.blocks_again, static_cast<size_t>(threads - 1));
  }
}

// A speculation on the wrong candidate: a tool axis that both candidates of the Matsuura's A/C
// table reach (tilt 10 deg, A = -10 or +10 deg), approached on one branch from a steep tilt
// that only it reaches, while a start from nothing takes the other. The stretch is predicted
// again to its end, and the result is still the single thread's.
TEST(ParallelPrediction, ASpeculationOnTheOtherCandidateIsPredictedAgain) {
  std::mt19937 rng(9);
  const Machine m = machineWithErrors(test::shippedMachines()[0], rng);
  size_t most_again = 0;
  for (const double azimuth : {0.0, 0.5 * M_PI, M_PI, 1.5 * M_PI}) {
    std::vector<ClPoint> path(3 * BlockPrediction::kExactEvery + 100);
    for (size_t i = 0; i < path.size(); ++i) {
      const double t = std::min(1.0, static_cast<double>(i) / BlockPrediction::kExactEvery);
      const double polar = (50.0 - 40.0 * t) * M_PI / 180.0;
      const double az = azimuth + 0.05 * std::sin(1e-3 * i);
      const Eigen::Vector3d u(std::sin(polar) * std::cos(az), std::sin(polar) * std::sin(az),
                              std::cos(polar));
      path[i].p_w = Eigen::Vector3d(20.0 * std::sin(1e-3 * i), 10.0, 30.0) + 40.0 * u;
      path[i].u_w = u;
      path[i].line = static_cast<int>(i) + 1;
    }
    const PredictionResult one = predictToolPath(m.model, m.params, path);
    ASSERT_EQ(one.failed_points, 0);
    PredictionResult r;
    ParallelPredictionStats stats;
    predictToolPathParallel(m.model, m.params, path, r, 20, nullptr, 2, &stats);
    expectSameBits(r, one, "azimuth " + std::to_string(azimuth));
    EXPECT_EQ(stats.stretches, 2);
    most_again = std::max(most_again, stats.blocks_again);
  }
  EXPECT_GT(most_again, 16u);  // (a stretch of these paths: 96 blocks or more)
}

}  // namespace
}  // namespace tolver
