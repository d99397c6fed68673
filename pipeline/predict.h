#pragma once
// tolver predict as a library function: CL_predicted of a part program on a machine with errors
// ([AM01] 5.5.1-5.5.3): inverse kinematics on the nominal machine, forward kinematics with the
// errors; on a calibrated machine after the set-up a shop measures, with each point's
// uncertainty. Writes the predicted CL and the per-point table as a set.
#include <string>
#include <vector>

#include "core/path/tool_path_prediction.h"
#include "pipeline/command.h"
#include "pipeline/inputs.h"

namespace tolver {

struct PredictInputs {
  MachineOptions machine;
  ProgramOptions program;
  std::string output;                 // predicted CL to write (APT)
  std::string point_table;            // per-point table (CSV); empty: output with .csv
  double max_rotary_step_deg = 10.0;  // rotary steps above it between cutting moves are named
  bool absolute = false;              // calibrated machine: no measured set-up
  std::string probed;                 // probed points (CSV), or empty
};

struct PredictionRun {
  Machine machine;  // after the measured set-up (calibrated machine)
  ClProgram program;
  PredictionResult prediction;
  CalibratedPrediction calibration;
  std::string probe_line;             // the probed set-up fit, in words (with --probed)
  std::vector<RotaryJump> jumps;      // rotary steps above max_rotary_step_deg
  std::vector<std::string> warnings;  // set-up defaults, units, probed set-up
  std::vector<std::string> notes;     // what the program reader assumed or skipped
  int nonzero_parameters = 0;
  std::string errors_statement;     // what the machine file says of its errors
  std::string output, point_table;  // the files written
  Verdict verdict = Verdict::Ok;
};

// Reads, predicts, writes both files (or neither). Throws InputError (FieldError for the
// inputs: "output", "point_table").
PredictionRun predict(const PredictInputs& in);

}  // namespace tolver
