// Set-up search: from a set-up that reaches nothing it finds one that reaches everything; its
// margin is the one the joint ranges of the proposal give, and no point of a grid around it
// does better.
#include "core/path/setup_search.h"

#include <gtest/gtest.h>

#include "io/machine/machine_file.h"
#include "io/program/apt_reader.h"
#include "test_support.h"

namespace tolver {
namespace {

double marginOf(const MachineModel& m, const std::vector<ClPoint>& path) {
  int failed = 0, first = -1;
  const auto r = jointRanges(m, path, nullptr, &failed, &first);
  if (failed) return -1e9;
  double t = 1e9;
  for (size_t a = 0; a < m.axes.size(); ++a)
    if (!m.axes[a].isRotary())
      t = std::min({t, r[a].min - m.axes[a].travel_min, m.axes[a].travel_max - r[a].max});
  return t;
}

TEST(SetupSearch, FindsASetupThatReachesFromOneThatDoesNot) {
  Machine m = readMachineFile(test::sourcePath("resources/machines/matsuura_mc760vx.xml"));
  m.model.setup.gauge_length = 100;
  m.model.setup.part_zero_table = Eigen::Vector3d(500, 400, -300);
  const ClProgram p = readAptFile(test::sourcePath("samples/nas979_cone.apt"));
  EXPECT_LT(marginOf(m.model, p.path), 0.0);
  const SetupSearchResult r = findSetup(m.model, p.path, nullptr);
  ASSERT_TRUE(r.found);
  EXPECT_TRUE(r.outside.empty());
  EXPECT_GT(r.margin, 0.0);
  MachineModel best = m.model;
  best.setup = r.setup;
  // The printed margin is the one the proposal's joint ranges give.
  EXPECT_NEAR(marginOf(best, p.path), r.margin, 1e-6);
  const PredictionResult pred = predictToolPath(best, m.params, p.path);
  EXPECT_TRUE(pred.ok());
  // No point of a grid around the proposal (same rotation) has a larger margin.
  for (int i = -2; i <= 2; ++i)
    for (int j = -2; j <= 2; ++j)
      for (int k = -2; k <= 2; ++k) {
        MachineModel g = best;
        g.setup.part_zero_table += Eigen::Vector3d(i, j, k) * 20.0;
        EXPECT_LE(marginOf(g, p.path), r.margin + 1e-6) << i << " " << j << " " << k;
      }
}

}  // namespace
}  // namespace tolver

namespace tolver {
namespace {

// Analytic truth: a vertical-tool program on the Matsuura at a fixed rotation keeps A and C at
// zero, so each prismatic joint is the point's coordinate plus a constant, and the best margin
// is half the smallest difference between an axis's travel and the program's span along it.
// A time budget stops the search with the best set-up of the rotations tried, and says so; one
// rotation is always tried, and without a budget all of them are.
TEST(SetupSearch, ATimeBudgetStopsWithTheBestSetupTriedAndSaysSo) {
  Machine m = readMachineFile(test::sourcePath("resources/machines/matsuura_mc760vx.xml"));
  m.model.setup.gauge_length = 100;
  const ClProgram p = readAptFile(test::sourcePath("samples/nas979_cone.apt"));
  SetupSearchOptions o;
  const SetupSearchResult all = findSetup(m.model, p.path, nullptr, o);
  EXPECT_FALSE(all.budget_spent);
  EXPECT_EQ(all.rotations_tried, 24);
  o.max_seconds = 1e-9;
  const SetupSearchResult cut = findSetup(m.model, p.path, nullptr, o);
  EXPECT_TRUE(cut.budget_spent);
  EXPECT_EQ(cut.rotations_tried, 1);
  EXPECT_TRUE(std::isfinite(cut.margin));
  EXPECT_LE(cut.margin, all.margin);
  EXPECT_EQ(cut.setup.part_rotation, 0.0);  // the first rotation's best
}

TEST(SetupSearch, VerticalToolMarginIsHalfTheSmallestSlack) {
  Machine m = readMachineFile(test::sourcePath("resources/machines/matsuura_mc760vx.xml"));
  m.model.setup.gauge_length = 100;
  m.model.setup.part_zero_table = Eigen::Vector3d(900, -700, 400);  // far outside
  std::vector<ClPoint> path;
  const Eigen::Vector3d span(600, 200, 90);
  for (int i = 0; i < 40; ++i) {
    ClPoint c;
    c.p_w = Eigen::Vector3d(span.x() * ((i * 7) % 40) / 39.0, span.y() * ((i * 13) % 40) / 39.0,
                            span.z() * ((i * 3) % 40) / 39.0) -
            Eigen::Vector3d(50, 20, 0);
    c.u_w = Eigen::Vector3d::UnitZ();
    c.line = i + 1;
    path.push_back(c);
  }
  SetupSearchOptions o;
  o.rotation_step = 0.0;
  const SetupSearchResult r = findSetup(m.model, path, nullptr, o);
  ASSERT_TRUE(r.found);
  double expected = 1e9;
  for (size_t a = 0; a < m.model.axes.size(); ++a) {
    const Axis& ax = m.model.axes[a];
    if (ax.isRotary()) continue;
    const int j = ax.name == "X" ? 0 : ax.name == "Y" ? 1 : 2;
    expected = std::min(expected, (ax.travel_max - ax.travel_min - span[j]) / 2.0);
  }
  EXPECT_NEAR(r.margin, expected, 1e-6);
}

// A program no single set-up reaches is cut into consecutive pieces that cover it, each with a
// set-up that reaches every point of its piece.
TEST(SetupSearch, SplitsAProgramTooLongForTheTravel) {
  Machine m = readMachineFile(test::sourcePath("resources/machines/matsuura_mc760vx.xml"));
  m.model.setup.gauge_length = 100;
  std::vector<ClPoint> path;
  for (int i = 0; i <= 120; ++i) {  // a 1200 mm straight line: longer than any travel
    ClPoint c;
    c.p_w = Eigen::Vector3d(10.0 * i, 0, 0);
    c.u_w = Eigen::Vector3d::UnitZ();
    c.line = i + 1;
    path.push_back(c);
  }
  SetupSearchOptions o;
  EXPECT_FALSE(findSetup(m.model, path, nullptr, o).found);
  const std::vector<SetupPiece> pieces = splitIntoSetups(m.model, path, nullptr, o);
  // The longest piece lies along the diagonal of the X-Y travel, hypot(760, 510) = 915.3 mm
  // (a part rotation puts it there): 91 steps of 10 mm fit, 92 do not.
  ASSERT_EQ(pieces.size(), 2u);
  EXPECT_EQ(pieces.front().first, 0);
  EXPECT_EQ(pieces.back().last, 120);
  EXPECT_EQ(pieces[1].first, pieces[0].last + 1);
  EXPECT_EQ(pieces[0].last, 91);
  for (const SetupPiece& p : pieces) {
    ASSERT_TRUE(p.result.found);
    MachineModel model = m.model;
    model.setup = p.result.setup;
    const std::vector<ClPoint> piece(path.begin() + p.first, path.begin() + p.last + 1);
    EXPECT_TRUE(predictToolPath(model, m.params, piece).ok());
  }
  // A budget bounds the whole split (each bisection step got the whole budget before: a 35 k
  // point Creo program took 3 min under --max-seconds 20): spent at once, no piece is given and
  // the split says so; ample, the same pieces as without.
  bool spent = false;
  o.max_seconds = 1e-9;
  EXPECT_TRUE(splitIntoSetups(m.model, path, nullptr, o, 8, &spent).empty());
  EXPECT_TRUE(spent);
  o.max_seconds = 600;
  const std::vector<SetupPiece> again = splitIntoSetups(m.model, path, nullptr, o, 8, &spent);
  EXPECT_FALSE(spent);
  ASSERT_EQ(again.size(), 2u);
  EXPECT_EQ(again[0].last, 91);
  EXPECT_EQ(again[1].result.setup.part_rotation, pieces[1].result.setup.part_rotation);
}

}  // namespace
}  // namespace tolver
