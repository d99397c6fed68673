#pragma once
// Reports of a ball-bar calibration (JSON) and the NC program of a ball-bar plan (G-code).
#include <string>

#include "core/ballbar.h"
#include "core/calibration.h"
#include "core/machine_model.h"

namespace tolver {

struct CalibrationReportInputs {
  std::string machine_file, readings_file, output_file;
  int readings = 0;
};

// JSON: status, iterations, rank, condition, residual RMS/max (um), unknowns, and per parameter
// name, ISO code, value, standard uncertainty (um or urad), observability; held parameters;
// ball position errors per set-up.
std::string formatCalibrationJson(const MachineModel& model, const BallbarTest& test,
                                  const CalibrationResult& result,
                                  const CalibrationReportInputs& inputs);

// An ISO G-code program that visits the plan's poses: rotary axes first (G0), then the linear
// axes (G1), a dwell for each reading; NC values are nc_sign * joint value (mm, deg) relative
// to the machine file's zero. Set-ups are separated by M0 with the ball positions as comments.
std::string formatBallbarGcode(const MachineModel& model, const BallbarTest& plan,
                               double feed_mm_per_min, double dwell_s);

}  // namespace tolver
