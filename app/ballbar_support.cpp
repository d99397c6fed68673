#include "app/ballbar_support.h"

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/calibration/ballbar_plan.h"
#include "io/machine/ballbar_file.h"
#include "io/common/io_error.h"
#include "core/numerics/units.h"

namespace tolver::app {

void heldoutWarning(const std::string& file, const ResidualStats& after, double fit_rms) {
  if (after.readings > 0 && after.rms > 3.0 * fit_rms && after.rms > 1e-3)
    std::fprintf(stderr,
                 "tolver: warning: %s: the identified machine predicts the held-out readings at "
                 "RMS %.3f um, %.0f times its fit (%.3f um): were they measured on the same "
                 "set-ups (ball positions untouched), in the same machine state?\n",
                 file.c_str(), mmToUm(after.rms), after.rms / fit_rms, mmToUm(fit_rms));
}

std::vector<std::string> testDesignWarnings(const MachineModel& model, const BallbarTest& test,
                                            int unknowns) {
  std::vector<std::string> w;
  const int m = static_cast<int>(test.readings.size());
  char buf[400];
  if (m < 3 * unknowns) {
    std::snprintf(buf, sizeof buf,
                  "%d readings for %d unknowns (fewer than 3 per unknown): the fit follows the "
                  "noise and predicts other poses worse than its residual says; plan at least %d "
                  "readings",
                  m, unknowns, 3 * unknowns);
    w.push_back(buf);
  }
  const TimeJointCorrelation c = timeJointCorrelation(model, test);
  if (c.worst_axis < 0) {
    std::printf("  time       the readings have no time_s: drift and warm-up cannot be checked\n");
  } else {
    std::printf("  time       largest correlation of time with a joint within the set-ups: "
                "|r| = %.2f (%s)\n",
                c.worst, model.axes[c.worst_axis].name.c_str());
    if (c.worst > 0.5) {
      std::snprintf(buf, sizeof buf,
                    "time and %s move together in these readings (|r| = %.2f): a thermal drift "
                    "and an error along %s cannot be told apart; order the poses at random "
                    "(plan-ballbar does)",
                    model.axes[c.worst_axis].name.c_str(), c.worst,
                    model.axes[c.worst_axis].name.c_str());
      w.push_back(buf);
    }
  }
  return w;
}

void printGross(const std::string& readings_file, const BallbarTest& test,
                const std::vector<GrossReading>& gross, bool kept, const CalibrationResult& with_all,
                const CalibrationResult& fit, bool limit_reached) {
  if (gross.empty()) {
    std::printf("  gross      none: every reading is consistent with the rest\n");
    return;
  }
  std::string lines;
  char buf[96];
  for (size_t k = 0; k < gross.size() && k < 12; ++k) {
    std::snprintf(buf, sizeof buf, "%sline %d (%+.2f um, t = %.1f)", k ? ", " : "",
                  test.readings[gross[k].index].line, mmToUm(gross[k].residual), gross[k].studentized);
    lines += buf;
  }
  if (gross.size() > 12) lines += ", ...";
  std::printf("  gross      %zu reading(s) of %s inconsistent with the rest: %s\n", gross.size(),
              readings_file.c_str(), lines.c_str());
  if (kept) {
    std::printf("             kept in the fit (--keep-outliers)\n");
    return;
  }
  std::printf("             removed and refitted: residual RMS %.3f um with them, %.3f um without\n",
              mmToUm(with_all.rms_residual), mmToUm(fit.rms_residual));
  if (limit_reached)
    std::fprintf(stderr,
                 "tolver: warning: %s: more readings look gross than 5 %% of the test: the model or "
                 "the set-up is more likely wrong than the readings; the rest were kept\n",
                 readings_file.c_str());
}

}  // namespace tolver::app
