// The part set-up from probed points (core/probed_setup, io/program/probe_file): a set-up error and
// a spindle offset built into a machine are recovered exactly from touches at several table
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

// Linear in the touches: 21 000 of them (the fit's rows, 63 000) fit as the few do. The SVD kept
// a full 63 000-square U before (32 GB: std::bad_alloc, exit 3; 10 000 touches took 61 s and
// 6.8 GB), now the thin one.
TEST(ProbedSetup, ManyTouchesFitWithoutASquareMatrixOfThem) {
  Case c = makeCase();
  const std::vector<ProbedPoint> few = touches(c.truth, false);
  std::vector<ProbedPoint> many;
  while (many.size() < 21000) many.insert(many.end(), few.begin(), few.end());
  Machine m = c.nominal;
  const ProbedSetupFit fit = fitProbedSetup(m, many);
  EXPECT_EQ(fit.observed, 9);
  EXPECT_LT((fit.change - c.part).head<3>().norm(), 1e-9);
  EXPECT_LT((fit.spindle_change - c.spindle).norm(), 1e-9);
  EXPECT_LT(fit.rms, 1e-9);
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
    EXPECT_LT(fit.spindle_change.norm(),
              1e-7);  // nanometres: the minimum-norm step prefers the part
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

// A tram reads the tool axis against the table: a spindle rotated by g about x tilts the axis
// to (0, -sin g), about y to (sin g, 0) (the rotation matrices' third columns); the part's
// set-up does not enter it.
TEST(ProbedSetup, ATramReadsTheSpindleTiltAgainstTheTable) {
  Case c = makeCase();  // the part set-up is tilted by 40 and -25 urad
  const int tl = blockOffset(c.truth.model, BlockKind::ToolSetup);
  JointVector q = JointVector::Zero(5);
  q << 30, -20, 50, 0, 0;
  Machine m = c.truth;
  EXPECT_LT(tramTilt(m, q).norm(), 1e-15);
  const double g = 70e-6;
  m.params[tl + 3] = g;
  EXPECT_LT((tramTilt(m, q) - Eigen::Vector2d(0, -std::sin(g))).norm(), 1e-15);
  m.params[tl + 3] = 0;
  m.params[tl + 4] = g;
  EXPECT_LT((tramTilt(m, q) - Eigen::Vector2d(std::sin(g), 0)).norm(), 1e-15);
}

// The spindle's tilt: touches at one probe length cannot see it (tilt times length looks like
// an offset), so the tool axis against the part keeps the file's; one tram recovers it, and the
// fitted machine then has the truth's tool axis and the cutter's tip at another length.
TEST(ProbedSetup, ATramRecoversTheSpindleTilt) {
  Case c = makeCase();
  const int tl = blockOffset(c.truth.model, BlockKind::ToolSetup);
  c.truth.params[tl + 3] = 60e-6;
  c.truth.params[tl + 4] = -35e-6;
  std::vector<ProbedPoint> pts = touches(c.truth, false);
  ProbedPoint tram;
  tram.tram = true;
  tram.line = 40;
  tram.q = JointVector::Zero(5);
  tram.q << 10, 20, 60, 0, 0;
  tram.tilt = tramTilt(c.truth, tram.q);
  JointVector q(5);
  q << 100, -80, 40, -0.8, 2.0;
  auto axisError = [&](const Machine& m) {
    const ForwardKinematics a(m.model, m.params), b(c.truth.model, c.truth.params);
    return (a.w_T_t(q).linear().col(2) - b.w_T_t(q).linear().col(2)).norm();
  };
  {
    Machine m = c.nominal;
    const ProbedSetupFit fit = fitProbedSetup(m, pts);
    EXPECT_EQ(fit.columns, 9);
    EXPECT_LT(fit.rms, 1e-9);        // the touches are explained...
    EXPECT_GT(axisError(m), 50e-6);  // ...but the tool axis is off by the tilt
  }
  pts.push_back(tram);
  Machine m = c.nominal;
  const ProbedSetupFit fit = fitProbedSetup(m, pts);
  EXPECT_EQ(fit.columns, 11);
  EXPECT_EQ(fit.observed, 11);
  EXPECT_EQ(fit.trams, 1);
  EXPECT_LT((fit.spindle_tilt_change - Eigen::Vector2d(60e-6, -35e-6)).norm(), 1e-10);
  EXPECT_LT((fit.change - c.part).tail<3>().norm(), 1e-10);
  EXPECT_LT((fit.spindle_change - c.spindle).norm(), 1e-8);
  EXPECT_LT(fit.rms, 1e-9);
  EXPECT_LT(fit.tram_max, 1e-10);
  EXPECT_GT(fit.tram_before, 60e-6);
  EXPECT_LT(axisError(m), 1e-10);
  m.model.setup.gauge_length = c.truth.model.setup.gauge_length = 150;
  const ForwardKinematics a(m.model, m.params), b(c.truth.model, c.truth.params);
  EXPECT_LT((a.w_T_t(q).translation() - b.w_T_t(q).translation()).norm(), 1e-8);
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
  // With a tram row: the tram columns are written and read back; the touches are unchanged.
  ProbedPoint tram;
  tram.tram = true;
  tram.q = pts[0].q;
  tram.tilt = Eigen::Vector2d(12.5e-6, -3e-6);
  pts.push_back(tram);
  const std::string with = formatProbeCsv(c.nominal.model, pts);
  EXPECT_NE(with.find("tram_x_urad,tram_y_urad"), std::string::npos);
  const std::vector<ProbedPoint> again = parseProbeCsv(with, "p.csv", c.nominal.model);
  ASSERT_EQ(again.size(), pts.size());
  EXPECT_TRUE(again.back().tram);
  EXPECT_LT((again.back().tilt - tram.tilt).norm(), 1e-18);
  EXPECT_LT((again.back().q - tram.q).norm(), 1e-12);
  EXPECT_FALSE(again.front().tram);
  EXPECT_LT((again.front().p_w - pts.front().p_w).norm(), 1e-12);
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
  EXPECT_NE(message("part_x_mm,part_y_mm,part_z_mm,x_mm\n1,2,3,4\n").find("y_mm: missing column"),
            std::string::npos)
      << message("part_x_mm,part_y_mm,part_z_mm,x_mm\n1,2,3,4\n");
  EXPECT_NE(message(h + "\n1,2,3,4,5,6,7,abc\n").find("p.csv:2"), std::string::npos);
  EXPECT_NE(message(h + ",part_nx,part_ny,part_nz\n1,2,3,4,5,6,7,8,1,,\n").find("none"),
            std::string::npos);
  EXPECT_NE(message(h + ",part_nx,part_ny,part_nz\n1,2,3,4,5,6,7,8,0,0,0\n").find("zero"),
            std::string::npos);
  EXPECT_NE(message(h + "\n1e300,2,3,4,5,6,7,8\n")
                .find("expected a position from -100000 to 100000 mm, found 1e+300"),
            std::string::npos);
  EXPECT_NE(message(h + "\n").find("no probed point"), std::string::npos);
  // A tram row takes joints only; its tilt is a bounded number.
  const std::string t = h + ",tram_x_urad,tram_y_urad\n";
  EXPECT_NE(message(t + "1,,,4,5,6,7,8,3,4\n").find("p.csv:2:1: part_x_mm: a tram row"),
            std::string::npos)
      << message(t + "1,,,4,5,6,7,8,3,4\n");
  EXPECT_NE(message(t + ",,,4,5,6,7,8,3,\n").find("tram_y_urad: missing value"), std::string::npos);
  EXPECT_NE(message(t + ",,,4,5,6,7,8,3,1e9\n").find("out of range"), std::string::npos);
  EXPECT_EQ(message(t + ",,,4,5,6,7,8,3,-2\n"), "no error");
}

}  // namespace
}  // namespace tolver
