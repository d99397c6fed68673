#pragma once
// Reports of a ball-bar calibration (JSON) and the NC program of a ball-bar plan (G-code).
#include <cmath>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "core/calibration/ballbar.h"
#include "core/calibration/calibration.h"
#include "core/calibration/identifiability.h"
#include "core/diagnosis/residual_analysis.h"
#include "core/model/machine_model.h"

namespace tolver {

// Held-out readings: RMS and max before (the prior machine, or the base model) and after.
struct HeldoutFigures {
  std::string file;  // empty: none given
  ResidualStats before, after;
};
// What the written files (machine file + ball positions) predict, read back from disk.
struct WrittenCheck {
  ResidualStats fit, heldout;
};
// A gross reading removed from the fit.
struct RemovedReading {
  int line = 0;
  double residual = 0.0;  // mm
  double studentized = 0.0;
  // diagnose: the studentised residual against the final model (effects included), and
  // whether that model explains the reading, which is then restored (NaN: not tested).
  double studentized_after = NAN;
  bool restored = false;
};

struct CalibrationReportInputs {
  std::string machine_file, readings_file, output_file;
  int readings = 0;
  std::string balls_file;
  HeldoutFigures heldout;
  WrittenCheck written;
  std::vector<RemovedReading> removed;
  // What each identified parameter stands for (calibrationAbsorbed), by unknown.
  std::vector<int> unknowns;
  std::vector<std::vector<AbsorbedTerm>> absorbed;
};

// "EAX.c0 + EAY.c0 - 0.5 EBX.c1 (+2 more)": an identified parameter with the ones it absorbs.
std::string standsFor(const MachineModel& model, int parameter,
                      const std::vector<AbsorbedTerm>& terms, int max_terms = 4);

// Reads the machine file and ball positions written by calibrate or diagnose and returns what
// they predict for the fitted and held-out readings (residual RMS and max).
// setup: the part set-up the fit ran with (a set-up file's gauge length moves the tool frame the
// ball positions are in), applied to the machine read back as the next command given the same
// set-up applies it; null: the machine file's own.
WrittenCheck checkWrittenFiles(const std::string& machine_file, const std::string& balls_file,
                               const BallbarTest& fit, const BallbarTest& heldout,
                               const PartSetup* setup = nullptr);

// The lack-of-fit test as JSON (um), or {"tested": false, "reason": ...}; and as one line for a
// console ("repeatability 0.58 um (33 df) against the fit's 1.32 um: F 5.20, p 1.1e-06: the
// model misses 1.19 um RMS").
nlohmann::json lackOfFitJson(const LackOfFit& l);
std::string describeLackOfFit(const LackOfFit& l, double alpha);

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
