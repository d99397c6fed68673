// The measurement behind docs/validation.md's table of diagnoses on independent data: every case of
// tests/independent_diagnosis.h x both set-up styles x seeds, printed as a Markdown table.
// Not a test: run by hand, `./build/tests/diagnosis_campaign [seeds] [clean_seeds] [case]`.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>

#include "independent_diagnosis.h"

int main(int argc, char** argv) {
  using namespace tolver::test;
  const int seeds = argc > 1 ? std::atoi(argv[1]) : 5;
  const int clean_seeds = argc > 2 ? std::atoi(argv[2]) : 20;
  const std::string only = argc > 3 ? argv[3] : "";  // cases whose name contains this
  const std::string dir = "/tmp/tolver_campaign_" + std::to_string(::getpid());
  std::printf(
      "| undeclared effect | set-up style | named right | held-out RMS before -> after (um, "
      "written files) | what was added when wrong |\n|---|---|---|---|---|\n");
  for (const DiagnosisCase& c : diagnosisCases()) {
    if (!only.empty() && c.name.find(only) == std::string::npos) continue;
    const int n = c.truth.empty() ? clean_seeds : seeds;
    for (bool on_axis : {false, true}) {
      int right = 0;
      double before = 0, after = 0;
      std::string wrong;
      for (int s = 0; s < n; ++s) {
        // Generator seeds 100+ (the tests use 1-3).
        const DiagnosisOutcome o = runDiagnosisCase(c, on_axis, 100 + s, dir);
        right += o.named_right;
        before += o.heldout_before_um / n;
        after += o.heldout_after_um / n;
        if (!o.named_right) {
          std::string a;
          for (const std::string& x : o.added) a += (a.empty() ? "" : ", ") + x;
          if (o.unexplained)
            a += (a.empty() ? "" : ", ") + std::string("unexplained: ") + o.unexplained_variable;
          wrong += (wrong.empty() ? "" : "; ") + (a.empty() ? std::string("nothing") : a);
        }
        std::fprintf(stderr,
                     "%s %s seed %d: %s (%s; lack of fit p %.2g; held-out %.3f -> %.3f um)\n",
                     c.name.c_str(), on_axis ? "on" : "off", s, o.named_right ? "right" : "WRONG",
                     o.message.c_str(), o.lack_of_fit_p, o.heldout_before_um, o.heldout_after_um);
      }
      std::printf("| %s | %s | %d/%d | %.3f -> %.3f | %s |\n", c.name.c_str(),
                  on_axis ? "tool balls on the axis" : "off the axis", right, n, before, after,
                  wrong.c_str());
      std::fflush(stdout);
    }
  }
  return 0;
}
