#pragma once
// What calibrate and diagnose print alike: the test's design and the gross readings found.
#include <string>
#include <vector>

#include "pipeline/calibrate.h"

namespace tolver::app {

// The line on time against the joints (the test's design; its warnings are the run's).
void printTimeLine(const MachineModel& model, const TestDesign& design);

// Prints the gross readings (by file line) and, when they were removed, the fit with and without
// them.
void printGross(const std::string& readings_file, const BallbarTest& test,
                const std::vector<GrossReading>& gross, bool kept,
                const CalibrationResult& with_all, const CalibrationResult& fit,
                bool limit_reached);

}  // namespace tolver::app
