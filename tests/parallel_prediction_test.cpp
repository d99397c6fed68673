#include "pipeline/parallel_prediction.h"

#include <gtest/gtest.h>

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
    if (odd < 0.002) out[i].p_w.x() += 1e4;
    else if (odd < 0.004) out[i].u_w = -u;
  }
  return out;
}

// On several threads, the same bits as on one: every point, the failures and the summary, for
// one, two and four threads (more threads than cores still keeps the order of the choices).
TEST(ParallelPrediction, EqualsTheSingleThreadedPredictionBitForBit) {
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  for (const char* file : {test::shippedMachines()[0], test::shippedMachines()[5]}) {
    Machine m = readMachineFile(test::sourcePath(file));
    m.model.setup.gauge_length = 100;
    for (int i = 0; i < m.model.parameterCount(); ++i)
      m.params[i] = n(rng) * (m.model.parameters[i].angular ? 30e-6 : 0.01);
    const std::vector<ClPoint> path = longPath(20011, rng);
    const PredictionResult one = predictToolPath(m.model, m.params, path, 7);
    ASSERT_GT(one.failed_points, 10) << file;
    for (int threads : {1, 2, 4}) {
      const PredictionResult r = predictToolPathParallel(m.model, m.params, path, 7, nullptr, threads);
      ASSERT_EQ(r.points.size(), one.points.size());
      for (size_t i = 0; i < path.size(); ++i) {
        const PredictedPoint &x = r.points[i], &y = one.points[i];
        const std::string where = std::string(file) + " point " + std::to_string(i);
        ASSERT_EQ(x.q.size(), y.q.size()) << where;
        for (int k = 0; k < x.q.size(); ++k)
          ASSERT_TRUE(x.q[k] == y.q[k] || (std::isnan(x.q[k]) && std::isnan(y.q[k]))) << where;
        for (int k = 0; k < 3; ++k) {
          ASSERT_TRUE(x.p_pred_w[k] == y.p_pred_w[k] || std::isnan(y.p_pred_w[k])) << where;
          ASSERT_TRUE(x.deviation_w[k] == y.deviation_w[k] || std::isnan(y.deviation_w[k])) << where;
        }
        ASSERT_TRUE(x.axis_angle == y.axis_angle || std::isnan(y.axis_angle)) << where;
      }
      EXPECT_EQ(r.failed_points, one.failed_points);
      ASSERT_EQ(r.failures.size(), one.failures.size());
      for (size_t k = 0; k < r.failures.size(); ++k) EXPECT_EQ(r.failures[k].index, one.failures[k].index);
      EXPECT_EQ(r.failures_per_axis, one.failures_per_axis);
      EXPECT_EQ(r.summary.max_deviation, one.summary.max_deviation);
      EXPECT_EQ(r.summary.max_index, one.summary.max_index);
      EXPECT_EQ(r.summary.rms_deviation, one.summary.rms_deviation);
      EXPECT_EQ(r.summary.rms_axis_angle, one.summary.rms_axis_angle);
    }
  }
}

}  // namespace
}  // namespace tolver
