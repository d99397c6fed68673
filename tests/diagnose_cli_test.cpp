// tolver diagnose end to end: report.json fields, report.html with plots, the augmented machine
// file used as it is by predict and simulate-ballbar, --cl, and bad input.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "test_support.h"

namespace tolver {
namespace {

class DiagnoseCli : public test::TempDirTest {
 protected:
  const std::string nominal = test::sourcePath("resources/machines/matsuura_mc760vx.xml");
  std::string readings(const std::string& name) {
    return test::sourcePath("samples/ballbar/" + name + ".csv");
  }
};

TEST_F(DiagnoseCli, ReversalDatasetEndToEnd) {
  const auto r =
      test::runTolver("diagnose --machine " + nominal + " --readings " + readings("reversal") +
                      " -o " + path("augmented.xml") + " --report-dir " + path("out") + " --cl " +
                      test::sourcePath("samples/nas979_cone.apt") + " --cl-setup " +
                      test::sourcePath("samples/matsuura_setup.txt") + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("added      reversal Y ey"), std::string::npos) << r.output;
  std::ifstream in(path("out/report.json"));
  const nlohmann::json j = nlohmann::json::parse(in);
  ASSERT_EQ(j["effects_added"].size(), 1u);
  const auto& e = j["effects_added"][0];
  EXPECT_EQ(e["type"], "reversal");
  EXPECT_EQ(e["axis"], "Y");
  EXPECT_NEAR(e["parameters"]["EYY.rev"].get<double>(), 4.0,
              3 * e["uncertainty"]["EYY.rev"].get<double>());
  EXPECT_LT(j["rms_after_um"].get<double>(), j["rms_before_um"].get<double>());
  EXPECT_LT(j["cv_rms_after_um"].get<double>(), j["cv_rms_before_um"].get<double>());
  EXPECT_LE(j["cv_rms_after_um"].get<double>(), 0.75);
  EXPECT_GT(j["candidates"].size(), 50u);
  for (const auto& c : j["candidates"]) {
    EXPECT_TRUE(c.contains("delta_ic") && c.contains("p_value") && c.contains("cv_rms_after_um") &&
                c.contains("verdict"));
  }
  // The program's predicted error before and after: the reversal changes it.
  EXPECT_GT(j["program"]["change_max_um"].get<double>(), 1.0);
  EXPECT_GT(j["program"]["after"]["points"].get<int>(), 0);
  // Report with the residual plots embedded, and the PNGs beside it.
  const std::string html = test::readText(path("out/report.html"));
  EXPECT_NE(html.find("data:image/png;base64,"), std::string::npos);
  // A periodogram's period is a harmonic order on a rotary axis and a length on a linear one,
  // printed as such whatever its size (a 4 mm period is not "order 4").
  int periodograms = 0;
  for (const auto& f : j["residual_analysis"]["before"]["findings"]) {
    if (f["test"] != "periodogram") continue;
    ++periodograms;
    const double period = f["period"].get<double>();
    const bool order = f["period_unit"] == "harmonic order";
    EXPECT_EQ(order, f["variable"] == "A" || f["variable"] == "B" || f["variable"] == "C")
        << f.dump();
    char text[64];
    if (order)
      std::snprintf(text, sizeof text, "(harmonic order %.0f)", period);
    else
      std::snprintf(text, sizeof text, "(period %.2f +- %.2f mm)", period,
                    f["period_uncertainty_mm"].get<double>());
    EXPECT_NE(html.find(text), std::string::npos) << text;
  }
  EXPECT_GT(periodograms, 0);
  EXPECT_TRUE(std::filesystem::exists(path("out/residual_reversal_Y_ey_before.png")));
  EXPECT_TRUE(std::filesystem::exists(path("out/residual_reversal_Y_ey_after.png")));
  // The augmented machine file works as it is.
  EXPECT_NE(test::readText(path("augmented.xml")).find("<effect type=\"reversal\" axis=\"Y\""),
            std::string::npos);
  auto p =
      test::runTolver("predict --machine " + path("augmented.xml") + " --cl " +
                      test::sourcePath("samples/nas979_cone.apt") + " --setup " +
                      test::sourcePath("samples/matsuura_setup.txt") + " -o " + path("cone.apt"));
  EXPECT_EQ(p.exit_code, 0) << p.output;
  auto s =
      test::runTolver("simulate-ballbar --machine " + path("augmented.xml") + " --plan " +
                      test::sourcePath("samples/ballbar/plan.csv") + " -o " + path("again.csv"));
  EXPECT_EQ(s.exit_code, 0) << s.output;
  // Diagnosing the data again on the augmented model's readings (no noise) finds the reversal
  // again.
  auto d = test::runTolver("diagnose --machine " + nominal + " --readings " + path("again.csv") +
                           " -o " + path("again.xml") + " --report-dir " + path("again") +
                           " --types reversal --quiet");
  EXPECT_EQ(d.exit_code, 0) << d.output;
  EXPECT_NE(d.output.find("added      reversal Y ey"), std::string::npos) << d.output;
}

TEST_F(DiagnoseCli, CleanDatasetAddsNothing) {
  const auto r =
      test::runTolver("diagnose --machine " + nominal + " --readings " + readings("clean") +
                      " -o " + path("augmented.xml") + " --report-dir " + path("out") + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("nothing missing"), std::string::npos) << r.output;
  std::ifstream in(path("out/report.json"));
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_TRUE(j["effects_added"].empty());
  EXPECT_EQ(j["verdict"], "nothing missing");
  EXPECT_EQ(test::readText(path("augmented.xml")).find("<effect"), std::string::npos);
}

// Progress when stderr is not a terminal (a log, a script): no bar, one line per phase that took
// TOLVER_PROGRESS_SECONDS or more (0 here: every phase), and none with --quiet.
TEST_F(DiagnoseCli, ProgressInALogIsOneLinePerPhase) {
  const std::string cmd = "diagnose --machine " + nominal + " --readings " + readings("clean") +
                          " -o " + path("augmented.xml") + " --report-dir " + path("out");
  setenv("TOLVER_PROGRESS_SECONDS", "0", 1);
  const auto r = test::runTolver(cmd);
  const auto q = test::runTolver(cmd + " --quiet");
  unsetenv("TOLVER_PROGRESS_SECONDS");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const size_t at = r.output.find("tolver: scoring candidates: ");
  ASSERT_NE(at, std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("tolver: scoring candidates: ", at + 1), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("[#"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find('\r'), std::string::npos);
  ASSERT_EQ(q.exit_code, 0) << q.output;
  EXPECT_EQ(q.output.find("tolver: scoring candidates"), std::string::npos) << q.output;
}

// A time budget stops the selection after the rounds done and says so (console and JSON); the
// two-effect readings then get the first effect only, where without a budget they get both.
TEST_F(DiagnoseCli, ATimeBudgetStopsTheSelectionAndSaysSo) {
  const std::string cmd = "diagnose --machine " + nominal + " --readings " +
                          readings("two_effects") + " -o " + path("augmented.xml") +
                          " --quiet --report-dir ";
  const auto all = test::runTolver(cmd + path("all"));
  ASSERT_EQ(all.exit_code, 0) << all.output;
  EXPECT_EQ(all.output.find("  budget "), std::string::npos) << all.output;
  const auto cut = test::runTolver(cmd + path("cut") + " --max-seconds 0.000001");
  ASSERT_EQ(cut.exit_code, 0) << cut.output;
  EXPECT_NE(cut.output.find("--max-seconds 1e-06 ran out after 1 selection round"),
            std::string::npos)
      << cut.output;
  auto report = [&](const char* dir) {
    std::ifstream in(path(dir) + "/report.json");
    return nlohmann::json::parse(in);
  };
  const nlohmann::json a = report("all"), c = report("cut");
  EXPECT_FALSE(a["budget_spent"].get<bool>());
  EXPECT_TRUE(c["budget_spent"].get<bool>());
  EXPECT_EQ(c["rounds_done"].get<int>(), 1);
  EXPECT_EQ(a["effects_added"].size(), 2u);
  EXPECT_EQ(c["effects_added"].size(), 1u);
}

// The lack-of-fit test on the plan's repeated poses: the reversal data fail it with the base
// model and pass it with the reversal added; the clean data pass it. One verdict line.
TEST_F(DiagnoseCli, LackOfFitBeforeAndAfterAndOneVerdict) {
  const auto r = test::runTolver("diagnose --machine " + nominal + " --readings " +
                                 readings("reversal") + " -o " + path("aug.xml") +
                                 " --report-dir " + path("rev") + " --types reversal --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(path("rev/report.json"));
  const nlohmann::json j = nlohmann::json::parse(in);
  ASSERT_TRUE(j["lack_of_fit"]["before"]["tested"].get<bool>());
  EXPECT_LT(j["lack_of_fit"]["before"]["p_value"].get<double>(), 1e-3);
  EXPECT_GT(j["lack_of_fit"]["after"]["p_value"].get<double>(), 1e-3);
  EXPECT_GT(j["lack_of_fit"]["before"]["repeated_poses"].get<int>(), 2);
  EXPECT_EQ(j["verdict"], "effects added");
  size_t verdicts = 0;
  for (size_t at = r.output.find("  verdict "); at != std::string::npos;
       at = r.output.find("  verdict ", at + 1))
    ++verdicts;
  EXPECT_EQ(verdicts, 1u) << r.output;
  EXPECT_NE(r.output.find("lack of fit repeatability"), std::string::npos) << r.output;
}

// A reading the base model calls gross but the final model explains (the warm-up's first) is
// restored, the diagnosis run again with it, and listed with t before and after.
TEST_F(DiagnoseCli, GrossReadingsTheFinalModelExplainsAreRestored) {
  const auto r =
      test::runTolver("diagnose --machine " + nominal + " --readings " + readings("warmup") +
                      " -o " + path("aug.xml") + " --report-dir " + path("w") + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("restored (the diagnosis was run again"), std::string::npos) << r.output;
  std::ifstream in(path("w/report.json"));
  const nlohmann::json j = nlohmann::json::parse(in);
  ASSERT_EQ(j["gross_readings_restored"].size(), 1u) << j.dump(1);
  EXPECT_GT(std::abs(j["gross_readings_restored"][0]["studentized"].get<double>()), 5.0);
  EXPECT_LT(
      std::abs(j["gross_readings_restored"][0]["studentized_against_final_model"].get<double>()),
      4.0);
  EXPECT_NE(j["effects_added"].dump().find("warmup"), std::string::npos);
}

TEST_F(DiagnoseCli, BadInputExitsTwoWithoutWriting) {
  const std::string out = " -o " + path("aug.xml") + " --report-dir " + path("out") + " --quiet";
  auto r =
      test::runTolver("diagnose --machine " + nominal + " --readings " + path("missing.csv") + out);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  const std::string bad = write("bad.csv", test::readText(readings("clean")).substr(0, 600) +
                                               "1,80,0,20,12.5,21.6,0,x,1,2,3,4,5,150\n");
  r = test::runTolver("diagnose --machine " + nominal + " --readings " + bad + out);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("bad.csv:"), std::string::npos) << r.output;
  r = test::runTolver("diagnose --machine " +
                      test::sourcePath("samples/ballbar/truth_reversal.xml") + " --readings " +
                      readings("clean") + out);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("already has effects"), std::string::npos) << r.output;
  r = test::runTolver("diagnose --machine " + nominal + " --readings " + readings("clean") + out +
                      " --types backlash");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  // Readings that the machine and set-up cannot explain: refused, not diagnosed.
  r = test::runTolver("diagnose --machine " + nominal + " --gauge-length 200 --readings " +
                      readings("clean") + out);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("did not converge"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(path("aug.xml")));
}

}  // namespace
}  // namespace tolver
