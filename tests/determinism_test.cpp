// The same inputs and seed give byte-identical outputs, timing fields excepted: predict (its CL and
// table), calibrate, diagnose, verify, allocate and compensate (their JSON), each run twice into
// the same paths (a parallel part, TBB or pagmo's batch evaluator, must not change a digit).
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "test_support.h"

namespace tolver {
namespace {

namespace fs = std::filesystem;
std::string src(const std::string& p) { return test::sourcePath(p); }

// The JSON without its timing fields ("seconds", "timings_s", anywhere).
std::string withoutTimings(const std::string& text) {
  nlohmann::json j = nlohmann::json::parse(text);
  std::function<void(nlohmann::json&)> strip = [&](nlohmann::json& v) {
    if (v.is_object()) {
      v.erase("seconds");
      v.erase("timings_s");
      for (auto& [k, x] : v.items()) strip(x);
    } else if (v.is_array()) {
      for (auto& x : v) strip(x);
    }
  };
  strip(j);
  return j.dump(1);
}

class Determinism : public test::TempDirTest {
 protected:
  // Runs the command twice; every listed output (JSON: timings stripped) must be equal.
  void twice(const std::string& command, const std::vector<std::string>& files) {
    std::vector<std::string> first;
    for (int run = 0; run < 2; ++run) {
      const auto r = test::runTolver(command);
      ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 1) << r.output;
      for (size_t k = 0; k < files.size(); ++k) {
        ASSERT_TRUE(fs::exists(files[k])) << files[k];
        std::string text = test::readText(files[k]);
        if (files[k].size() > 5 && files[k].substr(files[k].size() - 5) == ".json")
          text = withoutTimings(text);
        if (run == 0)
          first.push_back(text);
        else
          EXPECT_EQ(first[k], text) << files[k] << " differs between two runs of: " << command;
      }
    }
  }
};

TEST_F(Determinism, EveryCommandGivesTheSameBytesTwice) {
  const std::string measured = src("samples/machines/matsuura_mc760vx_measured.xml");
  const std::string nominal = src("resources/machines/matsuura_mc760vx.xml");
  const std::string setup = " --setup " + src("samples/matsuura_setup.txt");
  twice("predict --machine " + measured + " --cl " + src("samples/nas979_cone.apt") + setup +
            " -o " + path("p.apt"),
        {path("p.apt"), path("p.csv")});
  twice("calibrate --machine " + nominal + " --readings " + src("samples/ballbar/clean.csv") +
            " -o " + path("c.xml"),
        {path("c.xml"), path("c.json"), path("c_balls.csv")});
  twice("diagnose --machine " + nominal + " --readings " + src("samples/ballbar/reversal.csv") +
            " --max-effects 1 --report-dir " + path("d") + " -o " + path("d.xml"),
        {path("d.xml"), path("d/report.json")});
  twice("verify --machine " + measured + setup + " --cl " + src("samples/sculptured_finish.apt") +
            " --part " + src("samples/sculptured_part.obj") +
            " --spacing 1.2 --tolerance 0.02 --no-images --report-dir " + path("v"),
        {path("v/report.json"), path("v/deviations.csv")});
  twice("allocate --machine " + src("resources/machines/xkh800.xml") + " --tolerances " +
            src("resources/allocation/xkh800_standard.csv") + " --report-dir " + path("a"),
        {path("a/report.json"), path("a/pareto.csv")});
  twice("compensate --machine " + measured + " --cl " + src("samples/nas979_cone.apt") + setup +
            " -o " + path("k.apt"),
        {path("k.apt"), path("k.json")});
}

}  // namespace
}  // namespace tolver
