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
  bool no_point_table = false;        // the predicted CL alone
  double max_rotary_step_deg = 10.0;  // rotary steps above it between cutting moves are named
  bool absolute = false;              // calibrated machine: no measured set-up
  std::string probed;                 // probed points (CSV), or empty
  // The program is read, predicted and written in blocks of at least this many points (ending
  // on a statement): the memory a run takes does not grow with the program's length.
  size_t block_points = 16384;
};

// The prediction's band over a calibrated machine's program (PoseUncertainty per point, not
// kept: a long program is read in blocks). Medians within 2e-5 (StreamQuantiles).
struct BandSummary {
  double tip_median = 0.0, tip_max = 0.0;    // mm, 1 sigma worst direction
  double axis_median = 0.0, axis_max = 0.0;  // rad
  double calibration_tip_median = 0.0, calibration_axis_median = 0.0;  // the covariance's share
  int outside = 0;             // points beyond the joint ranges the calibration covered
  int first_outside_line = 0;  // the first's source line
  std::vector<double> beyond;  // per axis, the most any point lies beyond (mm or rad)
};

struct PredictionRun {
  Machine machine;                   // after the measured set-up (calibrated machine)
  ClProgram program;                 // the program's state after its last block (no points)
  PredictionResult prediction;       // failures and summary (no points: they were written)
  PredictedPoint worst;              // the point of prediction.summary.max_index
  CalibratedPrediction calibration;  // the measured set-up (no per-point uncertainty)
  BandSummary band;                  // when calibration.uncertainty would have been filled
  bool has_band = false;
  int passes = 1;                     // the program read twice: the measured set-up's fit first
  std::string probe_line;             // the probed set-up fit, in words (with --probed)
  std::vector<RotaryJump> jumps;      // rotary steps above max_rotary_step_deg
  std::vector<std::string> warnings;  // set-up defaults, units, probed set-up
  std::vector<std::string> notes;     // what the program reader assumed or skipped
  int nonzero_parameters = 0;
  std::string errors_statement;     // what the machine file says of its errors
  std::string output, point_table;  // the files written (point_table empty: none)
  Verdict verdict = Verdict::Ok;
};

// Reads, predicts and writes both files (or neither), block by block. Progress: "predicting"
// (with a calibrated machine's measured set-up, "fitting the measured set-up" first), the
// fraction of the program read. Throws InputError (FieldError for the inputs: "output",
// "point_table").
PredictionRun predict(const PredictInputs& in, const Progress& progress = {});

}  // namespace tolver
