#pragma once
// Reports of `tolver diagnose`: report.json, report.html with residual plots (PNG) before and
// after, against the variable each added effect follows.
#include <string>
#include <vector>

#include "core/diagnosis/diagnosis.h"
#include "core/path/tool_path_prediction.h"
#include "io/report/calibration_report.h"

namespace tolver {

// The predicted error of a part program on the machine before and after the diagnosis.
struct ProgramComparison {
  std::string cl_file;
  PredictionSummary before, after;
  double change_max = 0.0, change_rms = 0.0;  // |p_after - p_before| over the points, mm
  int change_max_line = 0;                    // CL line of change_max
};

struct DiagnosisReportInputs {
  std::string machine_file, readings_file, output_file;
  const ProgramComparison* program = nullptr;
  double seconds = 0.0;
  std::string balls_file, heldout_file;
  WrittenCheck written;                 // what the written files predict (readings 0: not run)
  std::vector<RemovedReading> removed;  // gross readings left out of the fit
};

std::string formatDiagnosisJson(const MachineModel& base, const BallbarTest& test,
                                const DiagnosisResult& result, const DiagnosisReportInputs& in);

// Writes the PNG plots into dir and returns the self-contained HTML (images embedded).
// Throws InputError when a plot cannot be written.
std::string writeDiagnosisHtml(const std::string& dir, const MachineModel& base,
                               const BallbarTest& test, const DiagnosisResult& result,
                               const DiagnosisReportInputs& in);

// Units of an effect coefficient in reports ("um", "urad", "um/h") and the factor from the
// model's units (mm, rad, mm per hour).
const char* effectUnit(const EffectSpec& spec, double* scale);

}  // namespace tolver
