// The part set-up from probed points (core/probed_setup, io/program/probe_file): a set-up error and a
// spindle offset built into a machine are recovered exactly from touches at several table
// orientations, also when only the coordinate along each probing direction is measured; what
// the touches cannot see is named and left where the file put it; the CSV reads back what
// formatProbeCsv wrote and names the line and column of bad input.
#include "core/path/probed_setup.h"

#include <gtest/gtest.h>

#include <random>

#include "core/kinematics/forward_kinematics.h"
#include "io/common/io_error.h"
#include "io/machine/machine_file.h"
#include "io/program/probe_file.h"
#include "test_support.h"

namespace tolver {
namespace {

int blockOffset(const MachineModel& m, BlockKind kind) {
  for (const ParameterBlock& b : m.blocks)
    if (b.kind == kind) return b.offset;
  return -1;
}

struct Case {
  Machine nominal, truth;
  Vector6d part;
  Eigen::Vector3d spindle;
};

Case makeCase() {
  Case c;
  c.nominal = readMachineFile(test::sourcePath("resources/machines/matsuura_mc760vx.xml"));
  c.nominal.model.setup.gauge_length = 120;
  c.truth = c.nominal;
  c.part << 0.03, -0.02, 0.015, 40e-6, -25e-6, 300e-6;
  c.spindle << 0.008, -0.005, 0.012;
  const int wp = blockOffset(c.truth.model, BlockKind::WorkpieceSetup);
  const int tl = blockOffset(c.truth.model, BlockKind::ToolSetup);
  for (int k = 0; k < 6; ++k) c.truth.params[wp + k] = c.part[k];
  for (int k = 0; k < 3; ++k) c.truth.params[tl + k] = c.spindle[k];
  return c;
}

// Touches at three table orientations (the probe 80 mm long), where the truth puts the tip.
std::vector<ProbedPoint> touches(const Machine& truth, bool one_orientation) {
  Machine probe = truth;
  probe.model.setup.gauge_length = 80;
  const ForwardKinematics fk(probe.model, probe.params);
  std::vector<ProbedPoint> out;
  for (int k = 0; k < 12; ++k) {
    ProbedPoint p;
    p.q = JointVector::Zero(5);
    p.q[0] = k % 2 ? -60 : 70;
    p.q[1] = (k / 2) % 2 ? -40 : 50;
    p.q[2] = k % 3 == 0 ? 0 : 80;
    if (!one_orientation) {
      p.q[3] = k < 4 ? 0.0 : k < 8 ? -0.5 : 0.0;
      p.q[4] = k < 8 ? 0.0 : 1.6;
    }
    p.p_w = fk.w_T_t(p.q).translation();
    p.probe_length = 80;
    p.line = k + 2;
    out.push_back(p);
  }
  return out;
}

TEST(ProbedSetup, RecoversThePartSetUpAndTheSpindleOffset) {
  Case c = makeCase();
  const std::vector<ProbedPoint> pts = touches(c.truth, false);
  Machine m = c.nominal;
  const ProbedSetupFit fit = fitProbedSetup(m, pts);
  EXPECT_EQ(fit.columns, 9);
  EXPECT_EQ(fit.observed, 9);
  EXPECT_TRUE(fit.unobserved.empty());
  EXPECT_LT((fit.change - c.part).head<3>().norm(), 1e-9);
  EXPECT_LT((fit.change - c.part).tail<3>().norm(), 1e-11);
  EXPECT_LT((fit.spindle_change - c.spindle).norm(), 1e-9);
  EXPECT_LT(fit.rms, 1e-9);
  EXPECT_GT(fit.rms_before, 0.01);
  // The fitted machine predicts the cutter (another length) where the truth puts it.
  m.model.setup.gauge_length = c.truth.model.setup.gauge_length = 150;
  const ForwardKinematics a(m.model, m.params), b(c.truth.model, c.truth.params);
  JointVector q(5);
  q << 100, -80, 40, -0.8, 2.0;
  EXPECT_LT((a.w_T_t(q).translation() - b.w_T_t(q).translation()).norm(), 1e-9);
}

TEST(ProbedSetup, OnlyTheCoordinateAlongEachProbingDirectionCounts) {
  Case c = makeCase();
  std::vector<ProbedPoint> pts = touches(c.truth, false);
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  // Each touch along its own direction; the nominal point moved 5 mm across that direction
  // (the touch says nothing there). Three directions per table position keep all nine seen.
  std::vector<ProbedPoint> along;
  for (const ProbedPoint& p : pts)
    for (int k = 0; k < 3; ++k) {
      ProbedPoint q = p;
      q.n_w = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
      const Eigen::Vector3d across = q.n_w.unitOrthogonal();
      q.p_w += 5.0 * across;
      along.push_back(q);
    }
  Machine m = c.nominal;
  const ProbedSetupFit fit = fitProbedSetup(m, along);
  EXPECT_EQ(fit.observed, 9);
  EXPECT_LT((fit.change - c.part).head<3>().norm(), 1e-8);
  EXPECT_LT((fit.spindle_change - c.spindle).norm(), 1e-8);
  EXPECT_LT(fit.max, 1e-9);
}

TEST(ProbedSetup, WhatTheTouchesCannotSeeIsNamedAndKept) {
  Case c = makeCase();
  // One table orientation: the spindle offset cannot be told from the part's; it stays at the
  // file's value and the part takes the whole translation.
  {
    Machine m = c.nominal;
    const ProbedSetupFit fit = fitProbedSetup(m, touches(c.truth, true));
    EXPECT_EQ(fit.observed, 6);
    ASSERT_EQ(fit.unobserved.size(), 3u);
    EXPECT_NE(fit.unobserved[0].find("spindle offset x"), std::string::npos);
    EXPECT_LT(fit.spindle_change.norm(), 1e-7);  // nanometres: the minimum-norm step prefers the part
    EXPECT_LT(fit.rms, 1e-9);
  }
  // Every touch along z: x, y and the rotation about z are not seen (and the spindle offsets).
  {
    std::vector<ProbedPoint> pts = touches(c.truth, true);
    for (ProbedPoint& p : pts) p.n_w = Eigen::Vector3d::UnitZ();
    Machine m = c.nominal;
    const ProbedSetupFit fit = fitProbedSetup(m, pts);
    EXPECT_EQ(fit.observed, 3);
    std::string names;
    for (const std::string& s : fit.unobserved) names += s + ";";
    EXPECT_NE(names.find("x;y;"), std::string::npos) << names;
    EXPECT_NE(names.find("rotation about z;"), std::string::npos) << names;
    EXPECT_NEAR(fit.change[0], 0.0, 1e-9);
    EXPECT_NEAR(fit.change[5], 0.0, 1e-12);
    EXPECT_LT(fit.max, 1e-9);  // z (part and spindle together) and the tilts explain the touches
  }
}

TEST(ProbeFile, ReadsBackWhatItWrites) {
  Case c = makeCase();
  std::vector<ProbedPoint> pts = touches(c.truth, false);
  pts[3].n_w = Eigen::Vector3d(0, 0.6, 0.8);
  const std::string text = formatProbeCsv(c.nominal.model, pts);
  const std::vector<ProbedPoint> back = parseProbeCsv(text, "p.csv", c.nominal.model);
  ASSERT_EQ(back.size(), pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    EXPECT_LT((back[i].q - pts[i].q).norm(), 1e-12);
    EXPECT_LT((back[i].p_w - pts[i].p_w).norm(), 1e-12);
    EXPECT_LT((back[i].n_w - pts[i].n_w).norm(), 1e-12);
    EXPECT_EQ(back[i].probe_length, 80);
    EXPECT_EQ(back[i].line, static_cast<int>(i) + 2);
  }
}

TEST(ProbeFile, BadInputNamesTheLineAndColumn) {
  const Machine m = readMachineFile(test::sourcePath("resources/machines/matsuura_mc760vx.xml"));
  auto message = [&](const std::string& text) {
    try {
      parseProbeCsv(text, "p.csv", m.model);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string h = "part_x_mm,part_y_mm,part_z_mm,x_mm,y_mm,z_mm,a_deg,c_deg";
  EXPECT_NE(message("x_mm,y_mm\n1,2\n").find("part_x_mm"), std::string::npos);
  EXPECT_NE(message("part_x_mm,part_y_mm,part_z_mm,x_mm\n1,2,3,4\n").find("y_mm: missing column"), std::string::npos)
      << message("part_x_mm,part_y_mm,part_z_mm,x_mm\n1,2,3,4\n");
  EXPECT_NE(message(h + "\n1,2,3,4,5,6,7,abc\n").find("p.csv:2"), std::string::npos);
  EXPECT_NE(message(h + ",part_nx,part_ny,part_nz\n1,2,3,4,5,6,7,8,1,,\n").find("none"), std::string::npos);
  EXPECT_NE(message(h + ",part_nx,part_ny,part_nz\n1,2,3,4,5,6,7,8,0,0,0\n").find("zero"), std::string::npos);
  EXPECT_NE(message(h + "\n1e300,2,3,4,5,6,7,8\n").find("out of range"), std::string::npos);
  EXPECT_NE(message(h + "\n").find("no probed point"), std::string::npos);
}

}  // namespace
}  // namespace tolver
