#pragma once
// The diagnose pipeline as library functions: after a ball-bar calibration, find what the model
// failed to explain, trace it to an effect the model lacks, add it (core/diagnosis), and write
// the augmented machine, its ball positions and the report directory as a set, read back.
// `tolver diagnose` parses and prints.
#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/calibration/calibration.h"
#include "core/diagnosis/diagnosis.h"
#include "io/machine/ballbar_file.h"
#include "io/report/diagnosis_report.h"
#include "pipeline/calibrate.h"
#include "pipeline/command.h"
#include "pipeline/inputs.h"

namespace tolver {

struct DiagnoseInputs {
  MachineOptions machine;          // the base model: link and motion errors, no effects
  std::string readings;            // ball-bar readings (CSV)
  std::string heldout;             // held-out readings on the same set-ups, or empty
  std::string cl, cl_setup;        // a part program (APT) to predict before and after, its set-up
  std::vector<std::string> types;  // effect types to try (empty: all)
  double alpha = 1e-3;             // family-wise significance level per round
  int max_effects = 4;
  int blocks_per_setup = 6;  // cross-validation blocks
  bool keep_outliers = false;
  double spindle_tilt_urad = 0.0;  // as CalibrateInputs::spindle_tilt_urad
  double max_seconds = 0.0;        // time budget (DiagnosisOptions::max_seconds; 0: none)
  // The outputs (diagnoseMachine): the augmented machine (XML), its ball positions (beside it
  // unless given) and the report directory.
  std::string output, balls, report_dir;
};

struct DiagnosisOutputs {
  std::string machine, balls, report_dir;
};
// The outputs' paths (balls beside the machine file unless given), checked before any work.
DiagnosisOutputs diagnosisOutputs(const std::string& machine, const std::string& balls,
                                  const std::string& report_dir);

struct DiagnosisRun {
  Machine machine;   // the base machine as read
  BallbarFile file;  // the readings as read, with the reader's warnings
  BallbarTest heldout;
  RobustCalibration robust;         // the base fit with and without the gross readings
  std::vector<GrossReading> gross;  // found (removed, or kept with keep_outliers)
  // Per reading of robust.removed as first removed: its studentised residual against the final
  // model (effects included); and those restored because the final model explains them
  // (indices into file.test, with that residual and t).
  std::vector<double> gross_t_after;
  std::vector<GrossReading> restored;
  DiagnosisResult result;
  std::unique_ptr<ProgramComparison> program;  // with a part program
  std::chrono::steady_clock::time_point started;
  TestDesign design;                  // of the readings fitted
  std::vector<std::string> warnings;  // the reader's, the design's, the held-out readings'
  const BallbarTest& used() const { return robust.test; }  // the readings fitted
  // diagnoseMachine: where the outputs went, and what they predict read back.
  DiagnosisOutputs outputs;
  WrittenCheck written;
  std::string json, html;
  Verdict verdict = Verdict::Ok;
};

// tolver diagnose: checks the outputs' places, diagnoses, writes the augmented machine, its ball
// positions and the report directory as a set. Progress: "scoring candidates". Throws InputError.
DiagnosisRun diagnoseMachine(const DiagnoseInputs& in, const Progress& progress = {});

// Reads the inputs, removes gross readings, diagnoses (progress: candidates scored of the
// round's total). A failed diagnosis or a base fit that does not converge is an InputError.
DiagnosisRun runDiagnosis(const DiagnoseInputs& in,
                          const std::function<void(int, int)>& progress = {});

struct DiagnosisWritten {
  WrittenCheck check;      // what the written machine and ball files predict, read back
  std::string json, html;  // the report's final paths
};
// Writes the augmented machine, the ball positions and the report directory (report.json,
// report.html, plots) as a set: all or none.
DiagnosisWritten writeDiagnosis(const DiagnosisRun& run, const DiagnoseInputs& in,
                                const DiagnosisOutputs& out);

}  // namespace tolver
