#include "core/calibration/identifiability.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "io/machine/machine_file.h"
#include "test_support.h"

namespace tolver {
namespace {

Machine load(int i) { return readMachineFile(test::sourcePath(test::shippedMachines()[i])); }

std::vector<std::string> codes(const MachineModel& m, const std::vector<int>& idx) {
  std::vector<std::string> out;
  for (int i : idx) out.push_back(m.parameters[i].iso_code);
  return out;
}

int countKinds(const MachineModel& m, JointType t) {
  return static_cast<int>(
      std::count_if(m.axes.begin(), m.axes.end(), [&](const Axis& a) { return a.type == t; }));
}

// Thesis 3.6.2: 42 link-error parameters, rank 20 over 30 random poses.
TEST(Identifiability, MatsuuraLinkModelHasRank20Of42) {
  const Machine m = load(0);
  const auto cols = modelColumns(m.model, "link");
  ASSERT_EQ(cols.size(), 42u);
  const ForwardKinematics fk(m.model, Eigen::VectorXd::Zero(m.model.parameterCount()));
  const SvdSummary s = analyseColumns(stackedJacobian(fk, randomPoses(m.model, 30, 1), cols));
  EXPECT_EQ(s.rows, 180);
  EXPECT_EQ(s.rank, 20);
}

// Thesis Table 3.4: the minimal set is the 8 machine parameters plus the 12 part and tool ones,
// with a reduced condition number of order 10^2 ([AM01]: 87, unscaled; here about 8e2 unscaled
// in mm and rad, about 5 with columns scaled).
TEST(Identifiability, MatsuuraLinkMinimalSetIsTable34) {
  const Machine m = load(0);
  const std::vector<int> preferred = m.model.preferred.at("link");
  ASSERT_EQ(preferred.size(), 8u);
  const MinimalSet ms = minimalSetForModel(m.model, randomPoses(m.model, 30, 1),
                                           modelColumns(m.model, "link"), preferred);
  EXPECT_EQ(ms.kept.size(), 20u);
  EXPECT_EQ(ms.reduced.rank, 20);
  auto kept = codes(m.model, ms.kept);
  for (const char* c : {"COX",    "AOA",    "BOA",    "COA",    "YOC",    "BOC",    "AOZ",
                        "BOZ",    "part.X", "part.Y", "part.Z", "part.A", "part.B", "part.C",
                        "tool.X", "tool.Y", "tool.Z", "tool.A", "tool.B", "tool.C"})
    EXPECT_NE(std::find(kept.begin(), kept.end(), c), kept.end()) << c;
  EXPECT_GT(ms.reduced.condition, 1.0);
  EXPECT_LT(ms.reduced.condition, 10.0);
  EXPECT_GT(ms.reduced.condition_unscaled, 50.0);
  EXPECT_LT(ms.reduced.condition_unscaled, 2e3);
  EXPECT_TRUE(std::isinf(ms.initial.condition));
  // Without the preferred list (strategy III alone) the set is still complete: rank 20.
  const MinimalSet alone =
      minimalSetForModel(m.model, randomPoses(m.model, 30, 1), modelColumns(m.model, "link"), {});
  EXPECT_EQ(alone.kept.size(), 20u);
  EXPECT_EQ(alone.reduced.rank, 20);
}

// Thesis 4.7.2: the cubic (motion) model has 132 columns and rank 104 at 600 poses, and
// eq. 78, N = 4R + 6n(R+P) + 6, holds for other degrees.
TEST(Identifiability, MatsuuraCubicModelHasRank104Of132) {
  const Machine m = load(0);
  const auto cols = modelColumns(m.model, "motion");
  ASSERT_EQ(cols.size(), 132u);
  const ForwardKinematics fk(m.model, Eigen::VectorXd::Zero(m.model.parameterCount()));
  const SvdSummary s = analyseColumns(stackedJacobian(fk, randomPoses(m.model, 600, 2), cols));
  EXPECT_EQ(s.rank, 104);
}

// Thesis 4.7.2 and Table 4.1: the cubic model reduces to 104 variables, keeping the
// coefficients of Table 4.2 and the 12 set-up parameters.
TEST(Identifiability, MatsuuraCubicMinimalSetKeepsTable42) {
  const Machine m = load(0);
  const auto cols = modelColumns(m.model, "motion");
  const MinimalSet ms = minimalSetForModel(m.model, randomPoses(m.model, 600, 2), cols,
                                           m.model.preferred.at("motion"));
  EXPECT_EQ(ms.kept.size(), 104u);
  EXPECT_EQ(ms.reduced.rank, 104);
  EXPECT_EQ(ms.removed.size(), 28u);
  EXPECT_LT(ms.reduced.condition, 1e3);
  const auto kept = codes(m.model, ms.kept);
  for (int p : m.model.preferred.at("motion"))
    EXPECT_NE(std::find(kept.begin(), kept.end(), m.model.parameters[p].iso_code), kept.end())
        << m.model.parameters[p].iso_code;
  for (const char* c : {"part.X", "part.C", "tool.X", "tool.C"})
    EXPECT_NE(std::find(kept.begin(), kept.end(), c), kept.end()) << c;
}

class EveryMachine : public ::testing::TestWithParam<const char*> {};

TEST_P(EveryMachine, RankFollowsEquation78ForEveryDegree) {
  const Machine base = readMachineFile(test::sourcePath(GetParam()));
  const int R = countKinds(base.model, JointType::Rotary);
  const int P = countKinds(base.model, JointType::Prismatic);
  for (int n = 1; n <= 4; ++n) {
    const MachineModel m = withMotionDegree(base.model, n);
    const ForwardKinematics fk(m, Eigen::VectorXd::Zero(m.parameterCount()));
    const auto cols = modelColumns(m, "motion");
    const SvdSummary s = analyseColumns(stackedJacobian(fk, randomPoses(m, 400, 3), cols));
    EXPECT_EQ(s.rank, 4 * R + 6 * n * (R + P) + 6) << GetParam() << " degree " << n;
  }
}

INSTANTIATE_TEST_SUITE_P(Shipped, EveryMachine, ::testing::ValuesIn(test::shippedMachines()));

}  // namespace
}  // namespace tolver
