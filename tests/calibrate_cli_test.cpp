// calibrate as a metrologist runs it: held-out readings of the same set-ups, the ball positions
// written beside the identified machine (simulate-ballbar --balls reproduces the readings from
// the two files), gross readings named by their line and removed, and bad held-out files.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "io/common/text_util.h"
#include "io/machine/machine_file.h"
#include "test_support.h"

namespace tolver {
namespace {

namespace fs = std::filesystem;

class CalibrateCli : public test::TempDirTest {
 protected:
  const std::string nominal = test::sourcePath("resources/machines/matsuura_mc760vx.xml");
  const std::string truth = test::sourcePath("samples/machines/matsuura_mc760vx_measured.xml");
  // A fit plan and its held-out poses (plan-ballbar --heldout), simulated with noise.
  void simulate() {
    auto r = test::runTolver("plan-ballbar --machine " + nominal +
                             " --poses 360 --heldout 60 --seed 3 -o " + path("fit_plan.csv"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    ASSERT_NE(r.output.find("60 held-out poses"), std::string::npos) << r.output;
    // The measurement order does not follow a joint (a drift cannot pass for an axis error).
    const size_t at = r.output.find("|r| = ");
    ASSERT_NE(at, std::string::npos) << r.output;
    EXPECT_LT(std::stod(r.output.substr(at + 6)), 0.3) << r.output;
    fs::rename(path("fit_plan_heldout.csv"), path("held_plan.csv"));
    // The held-out poses on the same set-ups (same ball errors), measured after the plan.
    r = test::runTolver("simulate-ballbar --machine " + truth + " --plan " + path("fit_plan.csv") +
                        " --heldout-plan " + path("held_plan.csv") + " --heldout-output " +
                        path("held.csv") + " --noise-um 0.5 --ball-error-um 10 --seed 13 -o " +
                        path("fit.csv"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  // The length column of one file, in order.
  static std::vector<double> lengths(const std::string& file) {
    std::vector<double> out;
    std::ifstream in(file);
    std::string line;
    int col = -1;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#') continue;
      const auto cells = splitCsvLine(line);
      if (col < 0) {
        for (size_t k = 0; k < cells.size(); ++k)
          if (cells[k] == "length_mm") col = static_cast<int>(k);
        continue;
      }
      out.push_back(std::stod(cells[col]));
    }
    return out;
  }
};

TEST_F(CalibrateCli, HeldOutReadingsAndTheWrittenFilesReproduceTheReport) {
  simulate();
  auto r = test::runTolver("calibrate --machine " + nominal + " --readings " + path("fit.csv") +
                           " --heldout " + path("held.csv") + " -o " + path("id.xml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("held-out   60 readings"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("gross      none"), std::string::npos) << r.output;
  // What the test cannot see is named, with what a shop measures instead.
  EXPECT_NE(r.output.find("its three rotations"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the spindle's tilt against the machine's axes"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("a tram row"), std::string::npos) << r.output;
  ASSERT_TRUE(fs::exists(path("id_balls.csv")));
  std::ifstream in(path("id.json"));
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["ball_positions_file"], path("id_balls.csv"));
  // A parameter that stands for a combination says so (console and JSON).
  bool named = false;
  for (const auto& p : j["parameters"])
    if (p["iso_code"] == "EAX.c0") {
      ASSERT_TRUE(p.contains("stands_for"));
      EXPECT_NE(p["stands_for"].get<std::string>().find("EAY.c0"), std::string::npos);
      EXPECT_NE(p["stands_for"].get<std::string>().find("EAA.c0"), std::string::npos);
      named = true;
    }
  EXPECT_TRUE(named);
  const double held_after = j["heldout"]["after"]["rms_um"].get<double>();
  EXPECT_LT(held_after, j["heldout"]["before"]["rms_um"].get<double>() / 5);
  EXPECT_LT(held_after, 1.5);  // 0.5 um noise
  // The report's written-files figures are the fit's.
  EXPECT_NEAR(j["written_files_check"]["fit"]["rms_um"].get<double>(),
              j["residual_rms_um"].get<double>(), 1e-3);
  EXPECT_NEAR(j["written_files_check"]["heldout"]["rms_um"].get<double>(), held_after, 1e-3);
  // simulate-ballbar with the two written files reproduces every fitted reading to the fit's
  // residual, and the held-out ones to the reported held-out RMS.
  for (const char* name : {"fit", "held"}) {
    r = test::runTolver("simulate-ballbar --machine " + path("id.xml") + " --balls " +
                        path("id_balls.csv") + " --plan " + path(std::string(name) + "_plan.csv") +
                        " -o " + path(std::string(name) + "_re.csv"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::vector<double> a = lengths(path(std::string(name) + ".csv")),
                              b = lengths(path(std::string(name) + "_re.csv"));
    ASSERT_EQ(a.size(), b.size());
    double sum = 0;
    for (size_t i = 0; i < a.size(); ++i) sum += (a[i] - b[i]) * (a[i] - b[i]);
    const double rms_um = std::sqrt(sum / a.size()) * 1e3;
    EXPECT_NEAR(rms_um,
                std::string(name) == "fit" ? j["residual_rms_um"].get<double>() : held_after, 2e-3)
        << name;
  }
}

TEST_F(CalibrateCli, GrossReadingsAreNamedByLineAndRemoved) {
  simulate();
  // +20 um on three readings (file lines 30, 150 and 300).
  std::ifstream in(path("fit.csv"));
  std::ostringstream out;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (n == 30 || n == 150 || n == 300) {
      const size_t c = line.rfind(',');
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.7f", std::stod(line.substr(c + 1)) + 0.020);
      line = line.substr(0, c + 1) + buf;
    }
    out << line << "\n";
  }
  write("gross.csv", out.str());
  auto r = test::runTolver("calibrate --machine " + nominal + " --readings " + path("gross.csv") +
                           " --heldout " + path("held.csv") + " -o " + path("g.xml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("3 reading(s) of " + path("gross.csv")), std::string::npos) << r.output;
  for (const char* l : {"line 30 (+", "line 150 (+", "line 300 (+"})
    EXPECT_NE(r.output.find(l), std::string::npos) << l << "\n" << r.output;
  std::ifstream jin(path("g.json"));
  const nlohmann::json j = nlohmann::json::parse(jin);
  ASSERT_EQ(j["gross_readings_removed"].size(), 3u);
  for (const auto& g : j["gross_readings_removed"])
    EXPECT_NEAR(g["residual_um"].get<double>(), 20.0, 2.0);
  const double clean = j["heldout"]["after"]["rms_um"].get<double>();
  // Kept, they spoil the held-out prediction.
  r = test::runTolver("calibrate --machine " + nominal + " --readings " + path("gross.csv") +
                      " --heldout " + path("held.csv") + " --keep-outliers -o " + path("k.xml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("kept in the fit (--keep-outliers)"), std::string::npos) << r.output;
  std::ifstream kin(path("k.json"));
  const nlohmann::json k = nlohmann::json::parse(kin);
  EXPECT_GT(k["heldout"]["after"]["rms_um"].get<double>(), 1.3 * clean);
  EXPECT_EQ(k["gross_readings_removed"].size(), 0u);
}

// The lack-of-fit test: the reversal sample (a backlash the base model lacks) fails it and says
// to diagnose; the clean sample passes it. Console and JSON.
TEST_F(CalibrateCli, LackOfFitOnTheRepeatedPoses) {
  const std::string samples = test::sourcePath("samples/ballbar/");
  auto r = test::runTolver("calibrate --machine " + nominal + " --readings " + samples +
                           "reversal.csv -o " + path("r.xml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("the model misses"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("tolver diagnose looks for what"), std::string::npos) << r.output;
  std::ifstream in(path("r.json"));
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_LT(j["lack_of_fit"]["p_value"].get<double>(), 1e-3);
  EXPECT_GT(j["lack_of_fit"]["missing_rms_um"].get<double>(), 0.5);
  // What the covariance does not hold goes into the machine file and into every band: the lack
  // of fit on the tip, the stated spindle-tilt prior on the axis.
  auto t = test::runTolver("calibrate --machine " + nominal + " --readings " + samples +
                           "reversal.csv -o " + path("t.xml") + " --spindle-tilt-urad 10");
  ASSERT_EQ(t.exit_code, 0) << t.output;
  const Machine id = readMachineFile(path("t.xml"));
  EXPECT_NEAR(id.identification.lack_of_fit_mm * 1e3,
              j["lack_of_fit"]["missing_rms_um"].get<double>(), 1e-9);
  EXPECT_NEAR(id.identification.spindle_tilt_rad, 10e-6, 1e-15);
  auto p = test::runTolver("predict --machine " + path("t.xml") + " --cl " +
                           test::sourcePath("samples/nas979_cone.apt") + " --setup " +
                           test::sourcePath("samples/matsuura_setup.txt") + " -o " + path("p.apt"));
  ASSERT_EQ(p.exit_code, 0) << p.output;
  EXPECT_NE(p.output.find("the calibration's lack of fit"), std::string::npos) << p.output;
  EXPECT_NE(p.output.find("the spindle tilt's prior, 10.0 urad"), std::string::npos) << p.output;
  std::ifstream csv(path("p.csv"));
  std::string header, row;
  std::getline(csv, header);
  std::getline(csv, row);
  std::vector<std::string> names, v;
  std::stringstream hs(header), rs(row);
  for (std::string c; std::getline(hs, c, ',');) names.push_back(c);
  for (std::string c; std::getline(rs, c, ',');) v.push_back(c);
  auto col = [&](const char* n) {
    return std::stod(v[std::find(names.begin(), names.end(), n) - names.begin()]);
  };
  EXPECT_GE(col("u_tip_um"), id.identification.lack_of_fit_mm * 1e3 - 1e-4);
  EXPECT_GE(col("u_axis_urad"), 10.0 - 1e-4);
  auto c = test::runTolver("calibrate --machine " + nominal + " --readings " + samples +
                           "clean.csv -o " + path("c.xml"));
  ASSERT_EQ(c.exit_code, 0) << c.output;
  EXPECT_NE(c.output.find("no significant lack of fit"), std::string::npos) << c.output;
}

TEST_F(CalibrateCli, BadHeldOutFilesExitTwoNamingTheLine) {
  simulate();
  const std::string base =
      "calibrate --machine " + nominal + " --readings " + path("fit.csv") + " -o " + path("x.xml");
  // An empty held-out file.
  write("empty.csv", "");
  auto r = test::runTolver(base + " --heldout " + path("empty.csv"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find(path("empty.csv")), std::string::npos) << r.output;
  // A set-up the fit lacks (set-up 7 on line 3).
  std::ifstream in(path("held.csv"));
  std::string text((std::istreambuf_iterator<char>(in)), {});
  std::vector<std::string> lines;
  std::istringstream ls(text);
  for (std::string l; std::getline(ls, l);) lines.push_back(l);
  std::string other;
  for (size_t i = 0; i < lines.size(); ++i)
    other += (i == 2 ? "7" + lines[i].substr(1) : lines[i]) + "\n";
  write("other.csv", other);
  r = test::runTolver(base + " --heldout " + path("other.csv"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find(path("other.csv") + ":3"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("set-up 7 is not in the fit readings"), std::string::npos) << r.output;
  // A pose the fit measured (the fit's first reading copied in as line 3).
  std::ifstream fin(path("fit.csv"));
  std::string fit_line;
  for (int k = 0; k < 3 && std::getline(fin, fit_line);)
    if (!fit_line.empty() && fit_line[0] != '#') ++k, (void)0;
  std::string dup;
  for (size_t i = 0; i < lines.size(); ++i) dup += (i == 2 ? fit_line : lines[i]) + "\n";
  write("dup.csv", dup);
  r = test::runTolver(base + " --heldout " + path("dup.csv"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find(path("dup.csv") + ":3"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the fit readings measured this pose"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("x.xml")));
}

// Held-out readings of other set-ups (other ball errors) than the fit's: the identified model
// predicts them far worse than it fits, and calibrate says what to check.
TEST_F(CalibrateCli, HeldOutReadingsOfOtherSetupsAreFlagged) {
  simulate();
  auto r =
      test::runTolver("simulate-ballbar --machine " + truth + " --plan " + path("held_plan.csv") +
                      " --noise-um 0.5 --ball-error-um 10 --seed 99 -o " + path("other.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = test::runTolver("calibrate --machine " + nominal + " --readings " + path("fit.csv") +
                      " --heldout " + path("other.csv") + " -o " + path("o.xml"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("were they measured on the same set-ups"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace tolver
