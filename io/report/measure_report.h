#pragma once
// tolver measure's outputs: the per-point table (residuals.csv), report.json and the process
// corrections file (process.txt), from what the measure pipeline computed.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/diagnosis/part_trace.h"

namespace tolver {

// One measured point as reported (mm; NAN where it has no value).
struct MeasureRow {
  int line = 0;  // in the points file
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero(), foot_w = Eigen::Vector3d::Zero();
  Eigen::Vector3d n_w = Eigen::Vector3d::Zero();
  double measured = NAN, predicted = NAN, program = NAN, machine = NAN;
  double residual = NAN, residual_after = NAN;
  double instrument = NAN;  // the file's own deviation, when given
  int cl_line = 0, tool = 0;
  std::string region;     // the part's region (mesh group, CAD face) of the foot
  std::string operation;  // the CAM operation that cut it (as the program names it), or empty
  bool held_out = false;
  std::string status;  // "used", or why not: "beyond search range", "not machined", ...
};

struct MeasureReport {
  std::string name, machine_file, program_file, part_file, points_file;
  std::vector<MeasureRow> rows;
  int used = 0;
  int beyond_range = 0, unmachined = 0, off_face = 0;
  double search_mm = 0;
  int heldout_every = 0;
  // Summaries of the used points (mm).
  double measured_rms = 0, predicted_rms = 0, residual_rms = 0, residual_max = 0;
  int worst_row = -1;  // the used row of the largest residual after the trace
  PartTrace trace;
  // process.txt's lines: key, value (mm or rad), its standard deviation (NAN: carried over
  // from the process file the run started from).
  struct Correction {
    std::string key;
    double value = 0, sd = NAN;
  };
  std::vector<Correction> corrections;
  std::string process_from;         // the process file the prediction already held, or ""
  std::vector<std::string> images;  // the PNG files written beside report.json
  std::string machine_written;      // "machine.xml" when the part refined the machine, else
  std::vector<std::string> notes;
};
// process.txt's key of a traced value: the group's name and the value's, spaces as '_'.
std::string processKey(const std::string& group, const std::string& value_name);

// A traced group's values in words: "x +9.87 +- 0.41 um; about z +28.6 +- 91 urad;" (um,
// urad, um/h).
std::string describeTracedValues(const TraceGroup& g);

std::string formatMeasureCsv(const MeasureReport& r);
// report.html: self-contained (the images in `dir`, listed in r.images, embedded): the verdict,
// the inputs, the deviations, before and after, every candidate effect, the largest residual,
// the corrections written and the notes.
std::string formatMeasureHtml(const MeasureReport& r, const std::string& dir);
std::string formatMeasureJson(const MeasureReport& r);
// The corrections learned, as `key value` lines with units (docs/formats.md: process file).
std::string formatProcessFile(const MeasureReport& r);

}  // namespace tolver
