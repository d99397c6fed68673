#include "app/ballbar_support.h"

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/numerics/units.h"

namespace tolver::app {

void printTimeLine(const MachineModel& model, const TestDesign& design) {
  const TimeJointCorrelation& c = design.time;
  if (c.worst_axis < 0)
    std::printf("  time       the readings have no time_s: drift and warm-up cannot be checked\n");
  else
    std::printf(
        "  time       largest correlation of time with a joint within the set-ups: "
        "|r| = %.2f (%s)\n",
        c.worst, model.axes[c.worst_axis].name.c_str());
}

void printGross(const std::string& readings_file, const BallbarTest& test,
                const std::vector<GrossReading>& gross, bool kept,
                const CalibrationResult& with_all, const CalibrationResult& fit,
                bool limit_reached) {
  if (gross.empty()) {
    std::printf("  gross      none: every reading is consistent with the rest\n");
    return;
  }
  std::string lines;
  char buf[96];
  for (size_t k = 0; k < gross.size() && k < 12; ++k) {
    std::snprintf(buf, sizeof buf, "%sline %d (%+.2f um, t = %.1f)", k ? ", " : "",
                  test.readings[gross[k].index].line, mmToUm(gross[k].residual),
                  gross[k].studentized);
    lines += buf;
  }
  if (gross.size() > 12) lines += ", ...";
  std::printf("  gross      %zu reading(s) of %s inconsistent with the rest: %s\n", gross.size(),
              readings_file.c_str(), lines.c_str());
  if (kept) {
    std::printf("             kept in the fit (--keep-outliers)\n");
    return;
  }
  std::printf(
      "             removed and refitted: residual RMS %.3f um with them, %.3f um without\n",
      mmToUm(with_all.rms_residual), mmToUm(fit.rms_residual));
  if (limit_reached)
    std::fprintf(
        stderr,
        "tolver: warning: %s: more readings look gross than 5 %% of the test: the model or "
        "the set-up is more likely wrong than the readings; the rest were kept\n",
        readings_file.c_str());
}

}  // namespace tolver::app
