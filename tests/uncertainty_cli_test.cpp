// predict and verify on a calibrated machine: the covariance of the calibration travels in the
// machine file; predict writes each point's uncertainty and applies the set-up a shop measures
// (--absolute keeps the raw prediction); verify turns a decision inside the 95 % band into
// UNDECIDED (exit 4), one clear of it into PASS (0) or FAIL (1).
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>

#include "io/machine_file.h"
#include "test_support.h"

namespace tolver {
namespace {

class UncertaintyCli : public test::TempDirTest {
 protected:
  std::string identified() {
    const std::string nominal = test::sourcePath("resources/machines/matsuura_mc760vx.xml");
    const std::string truth = test::sourcePath("samples/machines/matsuura_mc760vx_measured.xml");
    auto r = test::runTolver("plan-ballbar --machine " + nominal + " --poses 360 --seed 5 -o " + path("plan.csv"));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    r = test::runTolver("simulate-ballbar --machine " + truth + " --plan " + path("plan.csv") +
                        " --noise-um 0.5 --ball-error-um 10 --seed 5 -o " + path("r.csv"));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    r = test::runTolver("calibrate --machine " + nominal + " --readings " + path("r.csv") + " -o " + path("id.xml"));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return path("id.xml");
  }
};

TEST_F(UncertaintyCli, PredictWritesTheUncertaintyAndAppliesTheMeasuredSetup) {
  const std::string id = identified();
  const Machine m = readMachineFile(id);
  ASSERT_EQ(m.identification.parameters.size(), 92u);
  ASSERT_EQ(m.identification.covered_min.size(), 5u);
  const std::string base = "predict --machine " + id + " --cl " + test::sourcePath("samples/nas979_cone.apt") +
                           " --setup " + test::sourcePath("samples/matsuura_setup.txt");
  auto r = test::runTolver(base + " -o " + path("p.apt"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("predicted after the set-up a shop measures"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("uncertainty (1 sigma) of the prediction"), std::string::npos) << r.output;
  std::ifstream in(path("p.csv"));
  std::string header;
  std::getline(in, header);
  EXPECT_NE(header.find(",u_tip_um,u_along_axis_um,u_axis_urad,outside_calibrated"), std::string::npos);
  auto a = test::runTolver(base + " --absolute -o " + path("a.apt"));
  ASSERT_EQ(a.exit_code, 0) << a.output;
  EXPECT_NE(a.output.find("absolute prediction"), std::string::npos) << a.output;
  // The raw prediction carries what the set-up takes up: a larger RMS deviation.
  const std::regex rms("deviation  max [0-9.]+ um at point [0-9]+ \\(line [0-9]+\\), RMS ([0-9.]+) um");
  std::smatch s1, s2;
  ASSERT_TRUE(std::regex_search(r.output, s1, rms)) << r.output;
  ASSERT_TRUE(std::regex_search(a.output, s2, rms)) << a.output;
  EXPECT_LT(std::stod(s1[1]), std::stod(s2[1]));
}

TEST_F(UncertaintyCli, VerifySaysUndecidedWhenTheLimitIsInsideTheBand) {
  const std::string id = identified();
  const std::string base = "verify --machine " + id + " --cl " + test::sourcePath("samples/nas979_cone.apt") +
                           " --setup " + test::sourcePath("samples/matsuura_setup.txt") + " --no-images";
  auto r = test::runTolver(base + " --tolerance 0.05 --report-dir " + path("v0"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex("total +([-+0-9.]+) \\.\\. ([-+0-9.]+) um"))) << r.output;
  const double worst = std::max(std::abs(std::stod(m[1])), std::abs(std::stod(m[2])));  // um
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex("known to \\+- ([0-9.]+) um"))) << r.output;
  const double band = std::stod(m[1]);
  ASSERT_GT(band, 0.0);
  auto run = [&](double t_um, const std::string& dir) {
    char t[32];
    std::snprintf(t, sizeof t, "%.6f", t_um * 1e-3);
    return test::runTolver(base + " --tolerance " + t + " --report-dir " + path(dir));
  };
  // The worst sample exactly at the limit: inside its band.
  r = run(2 * worst, "u");
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("tolver verify: UNDECIDED"), std::string::npos) << r.output;
  std::ifstream in(path("u") + "/report.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["verdict"], "undecided");
  EXPECT_EQ(j["exit_code"], 4);
  // Clear of the band on both sides.
  EXPECT_EQ(run(2 * (worst + 2 * band), "p").exit_code, 0);
  EXPECT_EQ(run(2 * (worst - 3 * band), "f").exit_code, 1);
}

// plan-ballbar --for: poses chosen by the prediction variance where the program cuts give a
// smaller expected tip uncertainty there than the D-optimal plan of the same size (the
// comparison plan-ballbar prints, recomputed here from its output).
TEST_F(UncertaintyCli, APlanForAProgramPredictsItBetter) {
  auto r = test::runTolver("plan-ballbar --machine " + test::sourcePath("resources/machines/matsuura_mc760vx.xml") +
                           " --setup " + test::sourcePath("samples/matsuura_setup.txt") + " --for " +
                           test::sourcePath("samples/nas979_cone.apt") + " --poses 360 -o " + path("p.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m,
                                std::regex("median ([0-9.]+) um, max ([0-9.]+) um; the D-optimal plan of "
                                           "the same size: median ([0-9.]+) um, max ([0-9.]+) um")))
      << r.output;
  EXPECT_LT(std::stod(m[1]), 0.9 * std::stod(m[3]));
  EXPECT_LT(std::stod(m[2]), std::stod(m[4]));
}

}  // namespace
}  // namespace tolver
