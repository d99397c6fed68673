// verifyPart end to end on the Matsuura model: machine errors with analytic consequences.
#include "geometry/verification.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/kinematics/forward_kinematics.h"
#include "core/model/effects.h"
#include "core/numerics/units.h"
#include "core/path/tool_motion.h"
#include "core/path/tool_path_prediction.h"
#include "io/machine/machine_file.h"
#include "test_support.h"

namespace tolver {
namespace {

Machine matsuura() { return readMachineFile(test::sourcePath(test::shippedMachines()[0])); }

// A flat plane z = 0 over [-90, 90] x [-15, 15] mm, as a grid of 1 mm squares.
TriangleMesh plane() {
  TriangleMesh m;
  m.group_names = {"face"};
  const int nx = 180, ny = 30;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) m.vertices.emplace_back(-90.0 + i, -15.0 + j, 0.0);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int a = j * (nx + 1) + i;
      m.faces.emplace_back(a, a + 1, a + nx + 2);
      m.faces.emplace_back(a, a + nx + 2, a + nx + 1);
      m.face_group.push_back(0);
      m.face_group.push_back(0);
    }
  return m;
}

// Facing passes of a D10 flat end, tool axis vertical, along x at y = -20..20 every 5 mm.
std::vector<ClPoint> facing() {
  std::vector<ClPoint> path;
  int line = 1;
  for (int j = 0; j <= 8; ++j) {
    const double y = -20.0 + 5.0 * j;
    for (double x : {-100.0, 100.0}) {
      ClPoint p;
      p.p_w = Eigen::Vector3d(j % 2 ? -x : x, y, 0.0);
      p.line = line++;
      path.push_back(p);
    }
  }
  return path;
}

// The joints of `path` on machine m (inverse kinematics).
std::vector<JointVector> jointsOf(const Machine& m, const std::vector<ClPoint>& path) {
  const PredictionResult pred = predictToolPath(m.model, m.params, path);
  EXPECT_TRUE(pred.ok());
  std::vector<JointVector> q;
  for (const auto& p : pred.points) q.push_back(p.q);
  return q;
}

struct FacingRun {
  SurfaceSamples samples;
  VerifyResult result;
};

FacingRun verifyFacing(const Machine& m) {
  Cutter c;
  c.diameter = 10;
  c.length = 30;
  const auto path = facing();
  const std::vector<JointVector> q = jointsOf(m, path);
  const ForwardKinematics nominal(m.model, Eigen::VectorXd::Zero(m.model.parameterCount()));
  const ForwardKinematics actual(m.model, m.params);
  MotionSampling sampling;
  sampling.step = 0.25;
  sampling.reach = c.length;
  std::vector<ToolPlacement> a, b;
  samplePlacements(nominal, actual, path, q, sampling, &a, &b);
  FacingRun r;
  r.samples = sampleSurface(plane(), 1.0);
  r.result = verifyPart(r.samples, c, a, b, {bilateralZone(0.02)}, SweepOptions());
  return r;
}

// A path cut in pieces (samplePlacementsOf, the pieces in parallel in verify) gives, joined in
// order, the placements of the whole (samplePlacements), bit for bit: pieces that start with a
// rapid point, inside a move, and at point 0; a machine with a direction-dependent effect is
// sampled whole (refused in pieces).
TEST(Verification, APathSampledInPiecesIsTheWholePathsPlacements) {
  Machine m = matsuura();
  m.params[m.model.findParameter("EZX.c1")] = 0.019;
  auto path = facing();
  path[6].rapid = true;
  const std::vector<JointVector> q = jointsOf(m, path);
  ASSERT_EQ(q.size(), path.size());
  const ForwardKinematics nominal(m.model, Eigen::VectorXd::Zero(m.model.parameterCount()));
  const ForwardKinematics actual(m.model, m.params);
  MotionSampling sampling;
  sampling.step = 0.5;
  std::vector<ToolPlacement> a, b, pa, pb;
  samplePlacements(nominal, actual, path, q, sampling, &a, &b);
  for (const size_t cut : {size_t{6}, size_t{3}}) {
    pa.clear();
    pb.clear();
    samplePlacementsOf(nominal, actual, path, q, q, sampling, 0, cut, &pa, &pb);
    samplePlacementsOf(nominal, actual, path, q, q, sampling, cut, 11, &pa, &pb);
    samplePlacementsOf(nominal, actual, path, q, q, sampling, 11, path.size() + 5, &pa, &pb);
    ASSERT_EQ(pa.size(), a.size());
    ASSERT_EQ(pb.size(), b.size());
    ASSERT_GT(a.size(), path.size() * 10);
    for (size_t k = 0; k < a.size(); ++k) {
      EXPECT_EQ(pa[k].tip_w, a[k].tip_w) << k;
      EXPECT_EQ(pa[k].axis_w, a[k].axis_w) << k;
      EXPECT_EQ(pb[k].tip_w, b[k].tip_w) << k;
      EXPECT_EQ(pb[k].cl_index, b[k].cl_index) << k;
    }
  }
  Machine with_effect = m;
  EffectSpec rev;
  rev.type = EffectType::Reversal;
  rev.axis = 0;
  rev.component = 0;
  with_effect.model.addEffect(rev);
  with_effect.params.conservativeResize(with_effect.model.parameterCount());
  with_effect.params[with_effect.model.parameterCount() - 1] = 4e-3;
  const ForwardKinematics actual_effect(with_effect.model, with_effect.params);
  EXPECT_THROW(samplePlacementsOf(nominal, actual_effect, path, q, q, sampling, 0, 3, &pa, &pb),
               std::invalid_argument);
}

// An out-of-squareness of X to Z (ISO 230-1: the slope of X's vertical straightness, the linear
// Chebyshev term of e_z(X)) tilts the table's path: e_z(X) = c1 X / 380. To put the tool at part
// coordinate x the table moves X = -x (the machine file's convention), so the table sits e_z(-x)
// = -c1 x / 380 high and the tool +c1 x / 380 above its nominal height. Facing with the flat
// bottom, the surface left at (x, y) is the lowest bottom over the tool positions that cover it,
// x_t in [x - w, x + w] with w = sqrt(R^2 - dy^2) for the nearest pass dy away: c1 (x - w) / 380
// for c1 > 0, to within one placement step of slope. The nominal program leaves the plane
// exactly.
TEST(Verification, FlatEndFacingOnASquarenessErrorGivesTheAnalyticTilt) {
  Machine m = matsuura();
  const double c1 = 0.019;  // 50 urad over X's half travel
  m.params[m.model.findParameter("EZX.c1")] = c1;
  const FacingRun r = verifyFacing(m);
  int checked = 0;
  double sxx = 0, sxy = 0, sx = 0, sy = 0;
  for (size_t i = 0; i < r.samples.size(); ++i) {
    if (r.samples.on_edge[i]) continue;
    ASSERT_TRUE(r.result.machined[i]) << i;
    const double x = r.samples.p_w[i].x(), y = r.samples.p_w[i].y();
    const double dy = std::abs(y - (-20.0 + 5.0 * std::round((y + 20.0) / 5.0)));
    const double w = std::sqrt(25.0 - dy * dy);
    EXPECT_NEAR(r.result.program[i], 0.0, 1e-12);
    EXPECT_NEAR(r.result.total[i], c1 * (x - w) / 380.0, 0.25 * c1 / 380.0 + 1e-12) << "x = " << x;
    EXPECT_DOUBLE_EQ(r.result.machine[i], r.result.total[i] - r.result.program[i]);
    sx += x;
    sy += r.result.total[i];
    sxx += x * x;
    sxy += x * r.result.total[i];
    ++checked;
  }
  ASSERT_GT(checked, 1000);
  const double slope = (checked * sxy - sx * sy) / (checked * sxx - sx * sx);
  EXPECT_NEAR(slope, c1 / 380.0, 1e-3 * c1 / 380.0);  // the tilt, 50 urad
  // +-10 um zone: the ends of the 180 mm plane are 4.5 um out of level, all in tolerance.
  EXPECT_TRUE(r.result.pass);
}

TEST(Verification, ZeroErrorMachineContributesNothing) {
  const Machine m = matsuura();
  ASSERT_EQ(m.params.norm(), 0.0);
  const FacingRun r = verifyFacing(m);
  for (size_t i = 0; i < r.samples.size(); ++i) {
    EXPECT_EQ(r.result.machine[i], 0.0);
    EXPECT_EQ(r.result.total[i], r.result.program[i]);
  }
  EXPECT_EQ(r.result.machine_stats.rms, 0.0);
}

// A sample far beyond the tolerance makes one region, found where it is.
TEST(Verification, OutOfTolerancePlaneIsOneRegionWithItsArea) {
  Machine m = matsuura();
  m.params[m.model.findParameter("EZX.c1")] = 0.2;  // 526 urad: -25 .. +24 um
  const FacingRun r = verifyFacing(m);
  EXPECT_FALSE(r.result.pass);
  ASSERT_GE(r.result.regions.size(), 1u);
  const auto& worst = r.result.regions.front();
  EXPECT_EQ(worst.kind, Conformance::Gouge);  // x < 0: the tool sits lower
  EXPECT_LT(worst.where_w.x(), -80.0);
  EXPECT_NEAR(worst.worst_deviation, -0.2 * (90.0 - 1.0 + 5.0) / 380.0, 0.2 * 1.5 / 380);
}

// A cut's boundary on a pocket floor: a D10 flat end faces the floor z = 0 along x at y = 0 (its
// disc reaches y = 5), a second pass 0.1 mm higher covers y from 5 to 15. A sample at y = 4.995
// is cut by the first pass's disc; shifted 10 um in y by the machine, the disc's edge leaves it
// and the upper pass cuts it: a 100 um step for a 10 um shift. Such samples are a cut boundary
// (no program/machine split), never a 100 um machine share; everywhere else total = program +
// machine exactly and the machine's share stays within the tool's displacement.
TEST(Verification, ACutBoundaryIsNotAMachineShare) {
  Cutter c;
  c.diameter = 10;
  c.length = 30;
  std::vector<ToolPlacement> nominal, actual;
  const Eigen::Vector3d shift(0.0, -0.010, 0.0);
  for (int k = 0; k <= 200; ++k) {
    for (int pass = 0; pass < 2; ++pass) {
      ToolPlacement t;
      t.tip_w = Eigen::Vector3d(-20.0 + 0.2 * k, pass ? 10.0 : 0.0, pass ? 0.1 : 0.0);
      t.cl_index = pass;
      nominal.push_back(t);
      t.tip_w += shift;
      actual.push_back(t);
    }
  }
  // Samples on the floor across the boundary at y = 5.
  SurfaceSamples samples;
  samples.group_names = {"floor"};
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 41; ++j) {
      samples.p_w.emplace_back(-5.0 + 0.5 * i, 4.9013 + 0.005 * j, 0.0);
      samples.n_w.emplace_back(0, 0, 1);
      samples.area.push_back(0.01);
      samples.group.push_back(0);
      samples.on_edge.push_back(0);
    }
  const VerifyResult r =
      verifyPart(samples, c, nominal, actual, {bilateralZone(0.5)}, SweepOptions());
  int boundary = 0, split = 0;
  for (size_t i = 0; i < samples.size(); ++i) {
    ASSERT_TRUE(r.machined[i]) << samples.p_w[i].transpose();
    if (r.split[i] == Split::CutBoundary) {
      ++boundary;
      EXPECT_NEAR(samples.p_w[i].y(), 4.995, 0.0051) << i;  // between the two edges of the disc
      continue;
    }
    ASSERT_EQ(r.split[i], Split::Attributable);
    ++split;
    EXPECT_DOUBLE_EQ(r.total[i], r.program[i] + r.machine[i]);
    EXPECT_LE(std::abs(r.machine[i]), shift.norm() + 1e-12) << samples.p_w[i].transpose();
  }
  EXPECT_GT(boundary, 0);
  EXPECT_GT(split, boundary);
  EXPECT_EQ(r.split_boundary, boundary);
  EXPECT_LE(std::max(std::abs(r.machine_stats.min), std::abs(r.machine_stats.max)),
            shift.norm() + 1e-12);
}

// Beyond the gouge search range: a tool 1 mm below the floor cuts every blade at its lower end;
// the deviation does not split, and the total is flagged as beyond the range (never a clipped
// number taken for a value).
TEST(Verification, BeyondTheSearchRangeIsFlagged) {
  Cutter c;
  c.diameter = 10;
  c.length = 30;
  std::vector<ToolPlacement> nominal, actual;
  for (int k = 0; k <= 100; ++k) {
    ToolPlacement t;
    t.tip_w = Eigen::Vector3d(-10.0 + 0.2 * k, 0.0, 0.0);
    nominal.push_back(t);
    t.tip_w.z() = -1.0;
    actual.push_back(t);
  }
  SurfaceSamples samples;
  samples.group_names = {"floor"};
  for (int i = 0; i < 10; ++i) {
    samples.p_w.emplace_back(-4.5 + i, 0.0, 0.0);
    samples.n_w.emplace_back(0, 0, 1);
    samples.area.push_back(1.0);
    samples.group.push_back(0);
    samples.on_edge.push_back(0);
  }
  const VerifyResult r =
      verifyPart(samples, c, nominal, actual, {bilateralZone(0.02)}, SweepOptions());
  for (size_t i = 0; i < samples.size(); ++i) {
    EXPECT_EQ(r.split[i], Split::BeyondRange);
    EXPECT_TRUE(r.total_beyond[i]);
  }
  EXPECT_EQ(r.split_beyond, 10);
  EXPECT_FALSE(r.pass);
}

}  // namespace
}  // namespace tolver

namespace tolver {
namespace {

// CL-only surfaces ([AM01] 5.5.4): the area of the surface through the CL points against the
// area the paths sweep, analytic. Tool axis vertical; a rapid marks the move to its point.
double clOnlyArea(const std::vector<ClPoint>& path, double width = 6) {
  SurfaceSamples s;
  VerifyResult r;
  clOnlyDeviation(path, path, {}, std::vector<double>(path.size(), width), &s, &r);
  double area = 0;
  for (double a : s.area) area += a;
  return area;
}

ClPoint at(double x, double y, double z, bool rapid = false) {
  ClPoint p;
  p.p_w = Eigen::Vector3d(x, y, z);
  p.rapid = rapid;
  return p;
}

// An Archimedean spiral r = r0 + step theta / 2 pi, a point every 0.3 mm, out to r_end; with
// `lift_deg`, cut into pieces by lifts (up 5 mm, over, down) every lift_deg of turn (Fabex's
// spiral pattern). The strips between one turn and the next cover
//   integral over theta in [0, theta_end - 2 pi] of (r step + step^2 / 2).
std::vector<ClPoint> spiral(double r0, double step, double r_end, double lift_deg, double* area) {
  std::vector<ClPoint> path{at(r0, 0, 5, true), at(r0, 0, 0, true)};
  double last_lift = 0, theta = 0;
  for (;; theta += 0.3 / (r0 + step * theta / (2 * kPi))) {
    const double r = r0 + step * theta / (2 * kPi);
    if (r > r_end) break;
    const double x = r * std::cos(theta), y = r * std::sin(theta);
    if (lift_deg > 0 && theta - last_lift > degToRad(lift_deg)) {
      path.push_back(at(path.back().p_w.x(), path.back().p_w.y(), 5, true));
      path.push_back(at(x, y, 5, true));
      path.push_back(at(x, y, 0, true));
      last_lift = theta;
    } else {
      path.push_back(at(x, y, 0));
    }
  }
  const double end = theta - 2 * kPi;
  *area = r0 * step * end + step * step * end * end / (4 * kPi) + step * step * end / 2;
  return path;
}

TEST(ClOnlySurface, ASpiralInOnePassIsJoinedTurnToTurn) {
  double area = 0;
  const std::vector<ClPoint> path = spiral(1, 1, 30, 0, &area);
  EXPECT_NEAR(clOnlyArea(path), area, 0.01 * area);  // a single pass had no strip at all
}

TEST(ClOnlySurface, ASpiralCutByLiftsIsJoinedSideBySideNotEndToEnd) {
  double area = 0;
  const std::vector<ClPoint> path = spiral(1, 1, 30, 250, &area);
  // The pieces were joined end to end, each to the one before: strips across the part.
  EXPECT_NEAR(clOnlyArea(path), area, 0.04 * area);
}

// Offset contours of a 40 x 20 mm rectangle 1 mm apart, corners only (straight moves): the
// ring between the outer loop and the tenth covers 40 x 20 - 22 x 2 mm2 (less a little at the
// corners, where one side's run ends and the next one's begins: 740 mm2; 5 548 before).
TEST(ClOnlySurface, OffsetContoursOfStraightMovesAreJoinedLoopToLoop) {
  std::vector<ClPoint> path{at(0, 0, 5, true), at(0, 0, 0, true)};
  for (int k = 0; k < 10; ++k) {
    const double a = k;
    for (const auto& [x, y] : {std::pair{a, a}, {40 - a, a}, {40 - a, 20 - a}, {a, 20 - a}, {a, a}})
      path.push_back(at(x, y, 0));
  }
  EXPECT_NEAR(clOnlyArea(path), 40 * 20 - 22 * 2, 0.03 * 756);
}

// A raster of 21 straight passes 1 mm apart at two depths 10 mm apart, rapids between: two
// 40 x 20 mm faces, and nothing between the levels.
std::vector<ClPoint> rasterLevels(std::initializer_list<double> levels) {
  std::vector<ClPoint> path;
  for (double z : levels)
    for (int k = 0; k <= 20; ++k) {
      path.push_back(at(0, k, 5, true));
      path.push_back(at(0, k, z, true));
      path.push_back(at(40, k, z));
    }
  return path;
}

TEST(ClOnlySurface, RasterLevelsAreJoinedWithinALevelOnly) {
  EXPECT_NEAR(clOnlyArea(rasterLevels({0.0, -10.0})), 2 * 40 * 20, 1e-6);
}

// A raster stepping down 0.1 mm a level, its rows 1 mm apart (Fabex's parallel pattern): the
// rows of each level join each other, not the row 0.1 mm above them (which gave the second
// level a vertical sliver and no floor). The first row of the level below has only rows of the
// level above beside it, and joins the one across: a strip of 40 x 1 mm2 more.
TEST(ClOnlySurface, ALevelsRowsJoinEachOtherNotTheRowsAbove) {
  EXPECT_NEAR(clOnlyArea(rasterLevels({0.0, -0.1})), 2 * 40 * 20 + 40, 1.0);
}

// A wall cut in Z-level contours 5 mm apart (a D10 cutter), in a program that also cuts a spiral
// 0.2 mm a turn elsewhere: every level joins the one above, the first included (it was left
// out: 2.5 times the program's median gap, 0.2 mm, was the limit beside a first contour).
TEST(ClOnlySurface, AWallsContoursJoinLevelToLevel) {
  double spiral_area = 0;
  std::vector<ClPoint> path = spiral(1, 0.2, 4, 0, &spiral_area);
  for (double z : {0.0, -5.0, -10.0, -15.0}) {
    path.push_back(at(100, 0, 5, true));
    path.push_back(at(100, 0, z, true));
    for (const auto& [x, y] : {std::pair{140.0, 0.0}, {140.0, 20.0}, {100.0, 20.0}, {100.0, 0.0}})
      path.push_back(at(x, y, z));
  }
  EXPECT_NEAR(clOnlyArea(path, 10), spiral_area + 120 * 15, 0.01 * (spiral_area + 1800));
}

// What sweeps no surface between passes: a row of drilled holes (feed moves along the tool
// axis), and a single contour whose sides meet at corners. Both had strips before (a vertical
// wall between the holes; a fan across the contour's inside).
TEST(ClOnlySurface, DrilledHolesAndASingleContourHaveNoSurfaceBetweenThem) {
  std::vector<ClPoint> holes;
  for (int k = 0; k < 6; ++k) {
    holes.push_back(at(10.0 * k, 0, 5, true));
    holes.push_back(at(10.0 * k, 0, 2, true));
    holes.push_back(at(10.0 * k, 0, -20));
  }
  EXPECT_NEAR(clOnlyArea(holes), 0.0, 1e-9);
  std::vector<ClPoint> contour{at(110, 212, 25, true), at(110, 212, 0, true), at(9, 110, 0),
                               at(110, 8, 0), at(211, 110, 0)};
  EXPECT_NEAR(clOnlyArea(contour), 0.0, 1e-9);
}

}  // namespace
}  // namespace tolver
