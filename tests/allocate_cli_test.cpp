// End-to-end: tolver allocate on the XKH800 and bad input.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "test_support.h"

namespace tolver {
namespace {

class AllocateCli : public test::TempDirTest {};

TEST_F(AllocateCli, Xkh800ReportsAndExitCodes) {
  const std::string base = "allocate --machine " +
                           test::sourcePath("resources/machines/xkh800.xml") +
                           " --gauge-length 150 --tolerances " +
                           test::sourcePath("resources/allocation/xkh800_standard.csv") +
                           " --limits 0.015,0.015,0.010 --generations 60 ";
  // The standard tolerances break the limits and the default bounds allow no tightening.
  auto r = test::runTolver(base + "--report-dir " + path("a"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("(breaks the limits)"), std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(path("a/report.json")));
  // Allowing tighter tolerances finds the cheapest allocation that meets the limits.
  r = test::runTolver(base + "--lower-factor 0.25 --report-dir " + path("b"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f : {"report.html", "report.json", "allocation.csv", "pareto.csv", "pareto.png"})
    EXPECT_TRUE(std::filesystem::exists(path(std::string("b/") + f))) << f;
  std::ifstream in(path("b/report.json"));
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["terms"].size(), 37u);
  EXPECT_EQ(j["correlation_groups"].size(), 4u);
  for (int d = 0; d < 3; ++d)
    EXPECT_LE(j["chosen"]["worst_mm"][d].get<double>(),
              j["limits_mm"][d].get<double>() * (1 + 1e-9));
  std::ifstream html(path("b/report.html"));
  const std::string page((std::istreambuf_iterator<char>(html)), std::istreambuf_iterator<char>());
  EXPECT_NE(page.find("data:image/png;base64,iVBORw0KGgo"), std::string::npos);  // embedded PNG
  // Stacked root-sum-square, the cheapest feasible allocation costs less than the standard.
  r = test::runTolver(base + "--combination rss --lower-factor 0.25 --report-dir " + path("c"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in_c(path("c/report.json"));
  const auto jc = nlohmann::json::parse(in_c);
  EXPECT_GT(jc["chosen"]["cost_saving_percent"].get<double>(), 0.0);
  EXPECT_LT(jc["chosen"]["cost"].get<double>(), jc["standard"]["cost"].get<double>());
}

TEST_F(AllocateCli, BadToleranceFilesExitWithCode2) {
  const std::string machine = test::sourcePath("resources/machines/xkh800.xml");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"term,category,standard,unit\ndq_q,positional,0.005,mm\n",
       "t.csv:2: term: no parameter named 'dq_q'"},
      {"term,category,standard,unit\ndx_x,sideways,0.005,mm\n",
       "t.csv:2: category: unknown category"},
      {"term,category,standard,unit\ndx_x,linear_positioning,abc,mm\n",
       "t.csv:2: standard: expected a positive number"},
      {"term,category,standard,unit\ndx_x,linear_positioning,0.005,urad\n", "t.csv:2: unit:"},
      {"term,category,standard\ndx_x,linear_positioning,0.005\n", "t.csv:1: unit: missing column"},
  };
  for (const auto& [text, needle] : cases) {
    write("t.csv", text);
    const auto r = test::runTolver("allocate --machine " + machine + " --tolerances " +
                                   path("t.csv") + " --report-dir " + path("out"));
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(needle), std::string::npos) << r.output;
  }
}

}  // namespace
}  // namespace tolver
