#include "core/path/tool_path_prediction.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "core/kinematics/forward_kinematics.h"
#include "core/kinematics/inverse_kinematics.h"
#include "core/numerics/lanes.h"
#include "io/machine/machine_file.h"
#include "io/program/apt_reader.h"
#include "io/program/apt_writer.h"
#include "test_support.h"

namespace tolver {
namespace {

std::vector<ClPoint> hemisphere(int n) {
  std::vector<ClPoint> out(n);
  for (int i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / n, polar = 0.05 + 0.9 * t, az = 20.0 * M_PI * t;
    const Eigen::Vector3d u(std::sin(polar) * std::cos(az), std::sin(polar) * std::sin(az),
                            std::cos(polar));
    out[i].p_w = 50.0 * u;
    out[i].u_w = u;
    out[i].line = i + 1;
  }
  return out;
}

// The batch path (four points side by side) gives the reference path's bits, point by point
// (joint values and their count, predicted tip and axis, deviations, flags), and the same
// failures and summary, on every shipped machine with errors everywhere and a path that mixes
// smooth stretches, jumps, near-singular axes, unreachable axes and points beyond the stroke.
TEST(ToolPathPrediction, BatchEqualsOneByOneBitForBit) {
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (const char* file : test::shippedMachines()) {
    Machine m = readMachineFile(test::sourcePath(file));
    m.model.setup.gauge_length = 100;
    for (int i = 0; i < m.model.parameterCount(); ++i)
      m.params[i] = n(rng) * (m.model.parameters[i].angular ? 30e-6 : 0.01);
    std::vector<ClPoint> path = hemisphere(1500);
    for (size_t i = 0; i < path.size(); ++i) {
      const double odd = unit(rng);
      if (odd < 0.01)
        path[i].p_w.x() += 1e4;
      else if (odd < 0.02)
        path[i].u_w = -path[i].u_w;
      else if (odd < 0.03)
        path[i].u_w = Eigen::Vector3d(std::pow(10.0, -9 * unit(rng)), 0, 1);
      else if (odd < 0.04)
        path[i].u_w = 2.5 * path[(i * 7919) % path.size()].u_w;  // a jump
    }
    PredictionResult b;
    predictToolPath(m.model, m.params, path, b, 5, nullptr, false);
    // Both lane widths where the processor runs the eight-lane (AVX-512) kernels.
    for (const bool wide : {false, true}) {
      lanes::setWideLanes(wide);
      if (wide && !lanes::wideLanes()) break;
      PredictionResult a;
      predictToolPath(m.model, m.params, path, a, 5, nullptr, true);
      lanes::setWideLanes(true);
      ASSERT_EQ(a.points.size(), b.points.size());
      for (size_t i = 0; i < path.size(); ++i) {
        const PredictedPoint &x = a.points[i], &y = b.points[i];
        const std::string where =
            std::string(file) + (wide ? " wide" : " narrow") + " point " + std::to_string(i);
        ASSERT_EQ(x.q.size(), static_cast<Eigen::Index>(m.model.axes.size())) << where;
        ASSERT_EQ(x.q.size(), y.q.size()) << where;
        for (int k = 0; k < x.q.size(); ++k)
          ASSERT_TRUE(x.q[k] == y.q[k] || (std::isnan(x.q[k]) && std::isnan(y.q[k]))) << where;
        const double xs[] = {x.p_pred_w.x(),    x.p_pred_w.y(),    x.p_pred_w.z(),
                             x.u_pred_w.x(),    x.u_pred_w.y(),    x.u_pred_w.z(),
                             x.deviation_w.x(), x.deviation_w.y(), x.deviation_w.z(),
                             x.along_axis,      x.across_axis,     x.axis_angle};
        const double ys[] = {y.p_pred_w.x(),    y.p_pred_w.y(),    y.p_pred_w.z(),
                             y.u_pred_w.x(),    y.u_pred_w.y(),    y.u_pred_w.z(),
                             y.deviation_w.x(), y.deviation_w.y(), y.deviation_w.z(),
                             y.along_axis,      y.across_axis,     y.axis_angle};
        for (int k = 0; k < 12; ++k)
          ASSERT_TRUE(xs[k] == ys[k] || (std::isnan(xs[k]) && std::isnan(ys[k])))
              << where << " field " << k;
        ASSERT_EQ(x.singular, y.singular) << where;
      }
      EXPECT_GT(a.failed_points, 0) << file;
      EXPECT_EQ(a.failed_points, b.failed_points);
      EXPECT_EQ(a.failures_per_axis, b.failures_per_axis);
      ASSERT_EQ(a.failures.size(), b.failures.size());
      for (size_t k = 0; k < a.failures.size(); ++k) {
        EXPECT_EQ(a.failures[k].index, b.failures[k].index);
        EXPECT_EQ(a.failures[k].message, b.failures[k].message);
      }
      EXPECT_EQ(a.summary.max_deviation, b.summary.max_deviation);
      EXPECT_EQ(a.summary.rms_deviation, b.summary.rms_deviation);
      EXPECT_EQ(a.summary.max_index, b.summary.max_index);
      EXPECT_EQ(a.summary.rms_axis_angle, b.summary.rms_axis_angle);
      EXPECT_EQ(a.summary.singular_points, b.summary.singular_points);
    }
  }
}

// Each predicted point is the forward model with errors at the IK joints, and the reported
// deviation components and tool-axis angle match their definitions computed the slow way.
// The structure-of-arrays result: every number of a point read back as set, NaN for a failed
// point, whole aligned lines per array, and its storage kept when a result is reused for a path
// as long or shorter (no allocation).
TEST(PredictedPoints, ReadsBackWhatWasSetInAlignedReusedArrays) {
  PredictedPoints pts;
  pts.resize(130, 5);
  ASSERT_EQ(pts.size(), 130u);
  ASSERT_EQ(pts.axes(), 5);
  for (int a = 0; a < 5; ++a) EXPECT_EQ(reinterpret_cast<uintptr_t>(pts.q(a)) % 64, 0u) << a;
  for (int f = 0; f < PredictedPoints::kFields; ++f)
    EXPECT_EQ(reinterpret_cast<uintptr_t>(pts.field(f)) % 64, 0u) << f;
  EXPECT_EQ(reinterpret_cast<uintptr_t>(pts.singular()) % 64, 0u);
  // Arrays do not overlap: each point's numbers are distinct and read back.
  for (size_t i = 0; i < pts.size(); ++i) {
    PredictedPoint p;
    p.q = JointVector::LinSpaced(5, 1000.0 * i, 1000.0 * i + 4);
    p.p_pred_w = Eigen::Vector3d(i + 0.1, i + 0.2, i + 0.3);
    p.u_pred_w = Eigen::Vector3d(i + 0.4, i + 0.5, i + 0.6);
    p.deviation_w = Eigen::Vector3d(i + 0.7, i + 0.8, i + 0.9);
    p.along_axis = -1.0 * i;
    p.across_axis = -2.0 * i;
    p.axis_angle = -3.0 * i;
    p.singular = i % 3 == 0;
    pts.set(i, p);
  }
  pts.setFailed(7);
  size_t count = 0;
  for (const PredictedPoint& p : pts) {
    const size_t i = count++;
    ASSERT_EQ(p.q.size(), 5);
    if (i == 7) {
      EXPECT_TRUE(p.q.array().isNaN().all());
      EXPECT_TRUE(std::isnan(p.p_pred_w.y()) && std::isnan(p.u_pred_w.z()) &&
                  std::isnan(p.deviation_w.x()) && std::isnan(p.along_axis) &&
                  std::isnan(p.across_axis) && std::isnan(p.axis_angle));
      EXPECT_FALSE(p.singular);
      continue;
    }
    EXPECT_EQ(p.q[4], 1000.0 * i + 4) << i;
    EXPECT_EQ(p.p_pred_w.z(), i + 0.3) << i;
    EXPECT_EQ(p.u_pred_w.x(), i + 0.4) << i;
    EXPECT_EQ(p.deviation_w.y(), i + 0.8) << i;
    EXPECT_EQ(p.along_axis, -1.0 * i);
    EXPECT_EQ(p.across_axis, -2.0 * i);
    EXPECT_EQ(p.axis_angle, -3.0 * i);
    EXPECT_EQ(p.singular, i % 3 == 0) << i;
  }
  EXPECT_EQ(count, 130u);
  EXPECT_EQ(pts.back().q[0], 1000.0 * 129);
  const double* storage = pts.q(0);
  pts.resize(130, 5);
  EXPECT_EQ(pts.q(0), storage);
  pts.resize(64, 5);
  EXPECT_EQ(pts.q(0), storage);
  EXPECT_EQ(pts.size(), 64u);
}

// A result reused for a shorter path, then a longer one, holds what a new result would.
TEST(ToolPathPrediction, ReusedResultEqualsANewOne) {
  Machine m = readMachineFile(test::sourcePath("resources/machines/matsuura_mc760vx.xml"));
  m.model.setup.gauge_length = 100;
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < m.model.parameterCount(); ++i)
    m.params[i] = n(rng) * (m.model.parameters[i].angular ? 20e-6 : 0.005);
  PredictionResult reused;
  for (const int length : {1000, 77, 1500}) {
    const std::vector<ClPoint> path = hemisphere(length);
    predictToolPath(m.model, m.params, path, reused);
    const PredictionResult fresh = predictToolPath(m.model, m.params, path);
    ASSERT_EQ(reused.points.size(), path.size());
    for (size_t i = 0; i < path.size(); ++i) {
      const PredictedPoint a = reused.points[i], b = fresh.points[i];
      ASSERT_EQ(a.q, b.q) << length << " " << i;
      ASSERT_EQ(a.p_pred_w, b.p_pred_w) << length << " " << i;
      ASSERT_EQ(a.deviation_w, b.deviation_w) << length << " " << i;
    }
    EXPECT_EQ(reused.summary.max_deviation, fresh.summary.max_deviation);
    EXPECT_EQ(reused.summary.rms_deviation, fresh.summary.rms_deviation);
  }
}

TEST(ToolPathPrediction, AgreesWithTheComposedForwardModel) {
  Machine m = readMachineFile(test::sourcePath(test::shippedMachines()[0]));
  m.model.setup.gauge_length = 100;
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < m.model.parameterCount(); ++i)
    m.params[i] = n(rng) * (m.model.parameters[i].angular ? 30e-6 : 0.01);
  const auto path = hemisphere(2000);
  const PredictionResult r = predictToolPath(m.model, m.params, path);
  ASSERT_TRUE(r.ok());
  const ForwardKinematics fk(m.model, m.params);
  double max_dev = 0;
  for (size_t i = 0; i < path.size(); ++i) {
    const PredictedPoint& p = r.points[i];
    const Eigen::Isometry3d T = fk.w_T_t(p.q);
    EXPECT_LT((p.p_pred_w - T.translation()).norm(), 1e-11);
    EXPECT_LT((p.u_pred_w - T.linear().col(2)).norm(), 1e-14);
    // The angle by its definition, from the same predicted axis (the two forward paths agree
    // to the 1e-14 above, which would swamp a relative check of a micro-radian angle).
    const Eigen::Vector3d u = path[i].u_w, v = p.u_pred_w;
    const double angle = std::atan2(u.cross(v).norm(), u.dot(v));
    EXPECT_NEAR(p.axis_angle, angle, 1e-12 * angle);
    EXPECT_NEAR(p.along_axis, p.deviation_w.dot(u), 1e-15);
    EXPECT_NEAR(std::hypot(p.along_axis, p.across_axis), p.deviation_w.norm(), 1e-15);
    max_dev = std::max(max_dev, p.deviation_w.norm());
  }
  EXPECT_NEAR(r.summary.max_deviation, max_dev, 0.0);
  EXPECT_GT(max_dev, 0.0);
}

TEST(ToolPathPrediction, ZeroErrorsGiveZeroDeviationAndFailuresAreNaN) {
  Machine m = readMachineFile(test::sourcePath(test::shippedMachines()[0]));
  auto path = hemisphere(200);
  path[50].p_w = Eigen::Vector3d(900, 0, 0);  // beyond X travel
  const PredictionResult r = predictToolPath(m.model, m.params, path);
  ASSERT_EQ(r.failures.size(), 1u);
  EXPECT_EQ(r.failures[0].line, 51);
  EXPECT_TRUE(std::isnan(r.points[50].p_pred_w.x()));
  for (size_t i = 0; i < path.size(); ++i) {
    if (i == 50) continue;
    EXPECT_LT(r.points[i].deviation_w.norm(), 1e-12);
    EXPECT_LT(r.points[i].axis_angle, 1e-15);
  }
}

// The predicted CL reads back with the same set-up on every shipped machine: a path through the
// singular pole (tool axis along a rotary axis) and to the travel limits of the prismatic axes,
// on the machine with errors of a machine in service, predicted, written as APT to six
// decimals, read and predicted again.
class EveryShippedMachine : public ::testing::TestWithParam<const char*> {};

TEST_P(EveryShippedMachine, PredictedClReadsBackWithTheSameSetup) {
  Machine m = readMachineFile(test::sourcePath(GetParam()));
  m.model.setup.gauge_length = 80;
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < m.model.parameterCount(); ++i)
    m.params[i] = n(rng) * (m.model.parameters[i].angular ? 20e-6 : 0.005);
  const ForwardKinematics nominal(m.model, Eigen::VectorXd::Zero(m.model.parameterCount()));
  // Joints along a line: rotaries from -15 to +15 deg of tilt (through zero: the pole of
  // table-on-tilt machines), prismatic axes from 30 % to 99.9 % of their range.
  std::vector<ClPoint> path;
  const int N = 400;
  for (int k = 0; k <= N; ++k) {
    const double t = static_cast<double>(k) / N;
    JointVector q(m.model.axes.size());
    for (size_t a = 0; a < m.model.axes.size(); ++a) {
      const Axis& ax = m.model.axes[a];
      if (ax.isRotary()) {
        const double lim = std::min({15.0 * M_PI / 180.0, ax.travel_max, -ax.travel_min});
        q[a] = lim * (2.0 * t - 1.0);
      } else {
        q[a] = ax.travel_min + (0.3 + 0.699 * t) * (ax.travel_max - ax.travel_min);
      }
    }
    Eigen::Vector3d p, u;
    nominal.tipAndAxis(q, &p, &u);
    ClPoint c;
    c.p_w = p;
    c.u_w = u;
    c.line = k + 1;
    path.push_back(c);
  }
  const PredictionResult r = predictToolPath(m.model, m.params, path);
  ASSERT_TRUE(r.ok()) << GetParam() << ": " << r.failures.front().message;
  std::string apt = "UNITS/MM\nMULTAX/ON\n";
  for (size_t i = 0; i < path.size(); ++i) apt += "GOTO/0,0,0,0,0,1\n";
  ClProgram program = parseApt(apt, "nominal.apt");
  program.path = path;
  std::vector<ClPoint> predicted = path;
  for (size_t i = 0; i < path.size(); ++i) {
    predicted[i].p_w = r.points[i].p_pred_w;
    predicted[i].u_w = r.points[i].u_pred_w;
  }
  const ClProgram back =
      parseApt(formatPredictedApt(program, predicted, {"round trip"}), "back.apt");
  ASSERT_EQ(back.path.size(), path.size());
  const PredictionResult again = predictToolPath(m.model, m.params, back.path);
  EXPECT_TRUE(again.ok()) << GetParam() << ": "
                          << (again.ok() ? "" : again.failures.front().message);
}

INSTANTIATE_TEST_SUITE_P(Shipped, EveryShippedMachine,
                         ::testing::ValuesIn(test::shippedMachines()));

// A posted program's rotary solution is the one predicted: when the commanded solution puts a
// prismatic axis out of travel while the other would not, the point fails naming that axis (the
// control would not run it), never silently predicted on the other solution (issue 32: an
// impeller program's 105 points).
TEST(ToolPathPrediction, ThePostsRotarySolutionIsKeptOrThePointFails) {
  Machine m = readMachineFile(test::sourcePath("resources/machines/linuxcnc_xyzac_trt.xml"));
  const MachineModel& model = m.model;
  const InverseKinematics ik(model);
  const Eigen::Vector3d u = Eigen::Vector3d(0.3, -0.4, 0.8).normalized();
  InverseKinematics::RotaryCandidate rc[2];
  bool singular = false;
  ASSERT_EQ(ik.rotaryCandidates(u, rc, &singular), 2);
  // A tip where one candidate reaches and the other does not.
  for (double y = -150; y <= 150; y += 2.5) {
    for (double z = -100; z <= 100; z += 2.5) {
      const Eigen::Vector3d p(10, y, z);
      JointVector q[2];
      bool in[2];
      for (int c = 0; c < 2; ++c) {
        q[c] = JointVector::Zero(static_cast<int>(model.axes.size()));
        for (size_t r = 0; r < ik.rotaryAxes().size(); ++r)
          q[c][ik.rotaryAxes()[r]] = rc[c].angleOf(static_cast<int>(r));
        int violated = -1;
        in[c] = ik.placeToolPoint(Eigen::Vector3d::Zero(), p, q[c], &violated);
      }
      if (in[0] == in[1]) continue;
      const int good = in[0] ? 0 : 1, bad = 1 - good;
      ClPoint cl;
      cl.p_w = p;
      cl.u_w = u;
      const std::vector<ClPoint> path = {cl};
      const std::vector<JointVector> commanded_bad = {q[bad]}, commanded_good = {q[good]};
      const PredictionResult rb = predictToolPath(model, m.params, path, 20, &commanded_bad);
      ASSERT_FALSE(rb.ok()) << "the other solution was taken";
      EXPECT_GE(rb.failures.front().axis, 0);
      const PredictionResult rg = predictToolPath(model, m.params, path, 20, &commanded_good);
      ASSERT_TRUE(rg.ok());
      for (int r : ik.rotaryAxes()) EXPECT_NEAR(rg.points[0].q[r], q[good][r], 1e-9);
      return;
    }
  }
  FAIL() << "no tip found where only one solution reaches";
}

}  // namespace
}  // namespace tolver
