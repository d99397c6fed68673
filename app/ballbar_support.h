#pragma once
// What calibrate and diagnose share: held-out readings, the ball-positions file beside a
// machine file, warnings about the test's design, and the gross readings found.
#include <string>
#include <vector>

#include "core/calibration/ballbar.h"
#include "core/calibration/calibration.h"
#include "core/model/machine_model.h"
#include "pipeline/calibrate.h"

namespace tolver::app {

// A warning when the identified model predicts the held-out readings much worse than it fits
// its own (more than 3 times the fit's RMS and above 1 um): not the same set-ups or machine state.
void heldoutWarning(const std::string& heldout_file, const ResidualStats& after, double fit_rms);

// Too few readings for the unknowns (fewer than 3 per unknown), time correlated with a joint
// (|r| > 0.5: a drift and an error along that axis cannot be told apart). Also prints the
// correlation line.
std::vector<std::string> testDesignWarnings(const MachineModel& model, const BallbarTest& test,
                                            int unknowns);

// Prints the gross readings (by file line) and, when they were removed, the fit with and without
// them.
void printGross(const std::string& readings_file, const BallbarTest& test,
                const std::vector<GrossReading>& gross, bool kept, const CalibrationResult& with_all,
                const CalibrationResult& fit, bool limit_reached);

}  // namespace tolver::app
