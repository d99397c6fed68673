#include "io/program/apt_writer.h"

#include <gtest/gtest.h>

#include <random>

#include "io/program/apt_reader.h"
#include "test_support.h"

namespace tolver {
namespace {

// Writing shifted points and reading the result back gives the shifted points, in every
// dialect's units and coordinate systems: a round trip through the writer and the reader.
class RoundTrip : public ::testing::TestWithParam<const char*> {};

TEST_P(RoundTrip, PredictedPointsReadBackUnchanged) {
  const ClProgram p = readAptFile(test::sourcePath(std::string("tests/fixtures/cl/") + GetParam()));
  std::mt19937 rng(9);
  std::normal_distribution<double> n(0.0, 0.01);
  std::vector<ClPoint> shifted = p.path;
  for (ClPoint& c : shifted) {
    c.p_w += Eigen::Vector3d(n(rng), n(rng), n(rng));
    c.u_w = (c.u_w + Eigen::Vector3d(n(rng), n(rng), n(rng)) * 1e-3).normalized();
  }
  const std::string text = formatPredictedApt(p, shifted, {"round trip"});
  const ClProgram back = parseApt(text, "back.apt");
  ASSERT_EQ(back.path.size(), shifted.size());
  for (size_t i = 0; i < shifted.size(); ++i) {
    EXPECT_LT((back.path[i].p_w - shifted[i].p_w).norm(), 2e-6) << i;
    EXPECT_LT((back.path[i].u_w - shifted[i].u_w).norm(), 2e-9) << i;
  }
  EXPECT_EQ(back.arcs_expanded, 0);  // arcs were written as their points
  EXPECT_EQ(back.cutters.size(), p.cutters.size());
  EXPECT_EQ(back.unknown_count, p.unknown_count);
}

INSTANTIATE_TEST_SUITE_P(Dialects, RoundTrip,
                         ::testing::Values("nx_ust_a.cls", "nx_cutcom.clsf",
                                           "nx_TORETC_250_BOK.cls", "swcam_Teste-Metrologia.apt",
                                           "swcam_RotateThick.apt", "creo_profile_milling.ncl",
                                           "creo_drilling.ncl"));

TEST(AptWriter, KeepsNonMotionStatementsVerbatimAndUnits) {
  const ClProgram p = parseApt("PARTNO/P1\nUNITS/INCHES\nFEDRAT/IPM,20\nGOTO/1,2,3\nFINI\n", "in.apt");
  std::vector<ClPoint> q = p.path;
  q[0].p_w += Eigen::Vector3d(0.0254, 0, 0);
  const std::string text = formatPredictedApt(p, q, {"hdr"});
  EXPECT_NE(text.find("$$ hdr\n"), std::string::npos);
  EXPECT_NE(text.find("PARTNO/P1\nUNITS/INCHES\nFEDRAT/IPM,20\n"), std::string::npos);
  EXPECT_NE(text.find("GOTO/1.00100000,2.00000000,3.00000000,0.000000000,0.000000000,1.000000000"),
            std::string::npos) << text;
  EXPECT_NE(text.find("FINI"), std::string::npos);
}

}  // namespace
}  // namespace tolver
