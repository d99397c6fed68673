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

// Read as a stream without the text of its GOTO and FROM statements (what predict keeps), a
// program gives the same points, statements and written file as read whole from its text; the
// text left out is that of the motion statements only.
TEST_P(RoundTrip, StreamedWithoutMotionTextWritesTheSameFile) {
  const std::string path = test::sourcePath(std::string("tests/fixtures/cl/") + GetParam());
  const ClProgram whole = parseApt(test::readText(path), path);
  AptReadOptions lean;
  lean.keep_motion_text = false;
  const ClProgram streamed = readAptFile(path, lean);
  ASSERT_EQ(streamed.path.size(), whole.path.size());
  for (size_t i = 0; i < whole.path.size(); ++i) {
    EXPECT_EQ(streamed.path[i].p_w, whole.path[i].p_w) << i;
    EXPECT_EQ(streamed.path[i].u_w, whole.path[i].u_w) << i;
    EXPECT_EQ(streamed.path[i].line, whole.path[i].line) << i;
  }
  ASSERT_EQ(streamed.statements.size(), whole.statements.size());
  ASSERT_EQ(streamed.lines.size(), whole.lines.size());
  size_t dropped = 0;
  for (const AptStatement& st : whole.statements)
    for (int l = st.first_line; l <= st.last_line; ++l) {
      const bool motion = st.major == "GOTO" || st.major == "FROM";
      EXPECT_EQ(streamed.lines.kept(l - 1), !motion) << l;
      EXPECT_TRUE(whole.lines.kept(l - 1)) << l;
      if (!motion) EXPECT_EQ(streamed.lines[l - 1], whole.lines[l - 1]) << l;
      dropped += motion;
    }
  EXPECT_GT(dropped, 0u);
  const std::vector<std::string> header = {"streamed"};
  EXPECT_EQ(formatPredictedApt(streamed, streamed.path, header),
            formatPredictedApt(whole, whole.path, header));
}

INSTANTIATE_TEST_SUITE_P(Dialects, RoundTrip,
                         ::testing::Values("nx_ust_a.cls", "nx_cutcom.clsf",
                                           "nx_TORETC_250_BOK.cls", "swcam_Teste-Metrologia.apt",
                                           "swcam_RotateThick.apt", "creo_profile_milling.ncl",
                                           "creo_drilling.ncl"));

TEST(AptWriter, KeepsNonMotionStatementsVerbatimAndUnits) {
  const ClProgram p =
      parseApt("PARTNO/P1\nUNITS/INCHES\nFEDRAT/IPM,20\nGOTO/1,2,3\nFINI\n", "in.apt");
  std::vector<ClPoint> q = p.path;
  q[0].p_w += Eigen::Vector3d(0.0254, 0, 0);
  const std::string text = formatPredictedApt(p, q, {"hdr"});
  EXPECT_NE(text.find("$$ hdr\n"), std::string::npos);
  EXPECT_NE(text.find("PARTNO/P1\nUNITS/INCHES\nFEDRAT/IPM,20\n"), std::string::npos);
  EXPECT_NE(text.find("GOTO/1.00100000,2.00000000,3.00000000,0.000000000,0.000000000,1.000000000"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("FINI"), std::string::npos);
}

}  // namespace
}  // namespace tolver
