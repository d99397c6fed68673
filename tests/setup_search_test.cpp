// Set-up search: from a set-up that reaches nothing it finds one that reaches everything; its
// margin is the one the joint ranges of the proposal give, and no point of a grid around it
// does better.
#include "core/setup_search.h"

#include <gtest/gtest.h>

#include "io/apt_reader.h"
#include "io/machine_file.h"
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
