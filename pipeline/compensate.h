#pragma once
// The compensate pipeline as library functions: the program that the machine, errors included,
// runs onto the nominal path ([AM01] ch. 5, conclusion: correcting the CL data), written back in
// the source's dialect, with the predicted error before and after, the after measured on the
// written text read back; and the linear-axis tables (--table). `tolver compensate` parses and
// prints.
#include <optional>
#include <string>
#include <vector>

#include "core/path/compensation.h"
#include "io/program/compensated_program.h"
#include "io/program/process_file.h"
#include "io/report/compensation_report.h"
#include "pipeline/command.h"
#include "pipeline/inputs.h"

namespace tolver {

struct CompensateInputs {
  MachineOptions machine;
  ProgramOptions program;
  std::string probed;  // probed points (CSV)
  // Process corrections learned from a measured part (tolver measure's process.txt): the
  // program is compensated for them too (processTargets).
  std::string process;
  bool absolute = false;       // calibrated machine: no measured set-up
  double max_condition = 1e6;  // beyond it, a point is near a singular pose
  // The outputs (compensateProgram): the compensated program (same dialect), its JSON report
  // (default: beside it, .json), an HTML report directory (or empty); and the linear-axis tables
  // (<stem>_<axis>.csv per axis, or empty) at their grid step.
  std::string output, report, report_dir;
  std::string table;
  double table_step = 10.0;  // mm
  // The program is read, compensated and written in blocks of at least this many points (ending
  // on a statement); 0: the whole program at once (compensateProgram).
  size_t block_points = 16384;
};

struct CompensationRun {
  Machine machine;  // after the measured set-up (calibrated machine)
  ClProgram program;
  PredictionResult before, after;  // after: the written text read back and predicted
  CompensationResult compensation;
  // With --process: where the machine must put the tool tip and axis so that, with the process
  // effects, the cut lands on the program's path; the before and after are measured against it.
  // Empty without.
  std::vector<ClPoint> target;
  CompensatedProgramText text;  // the corrected program, in the source's encoding
  bool orientation = false;     // the tool axis is compensated too (five-axis program)
  std::string setup_note;
  std::vector<std::string> warnings;
  CompensationReport report;
  // Per program point: source line, tip deviation (um) and axis error (urad), before and after.
  // Empty for a program compensated block by block (compensateProgram streams CL data): its
  // figures are in the report.
  std::vector<int> line;
  std::vector<double> tip_before_um, tip_after_um, axis_before_urad, axis_after_urad;
  // The read-back check (CompensateRun::worse_lines).
  std::vector<int> worse_lines;
  double worse_max_um = 0.0;
};

// Where the machine must put the tool for the process effects a measured part showed to leave
// the cut on the program's path (mm; io/program/process_file.h), per program point:
//   p' = E p + dL_k u' + g t u' - d_k (u' x f),   u' = R_E u,
// E the part's true pose on the table (R_E its rotation), dL_k tool k's extra length, g the
// spindle's growth rate and t the program's clock at the point (programTimes), d_k tool k's
// sideways deflection and f the direction of the move to the point. The measured effects read
// tip = commanded - (dL + g t) u + d (u x f) on a part at E (verify's applyTimedCorrections and
// sweepPart): p' inverts them to first order (their size is micrometres). A radius error is
// not a tip offset: it is listed in `notes` for the control's tool table (radius wear), as are
// the keys verify does not apply either, and drift without feed rates.
std::vector<ClPoint> processTargets(const ClProgram& program, const ProcessCorrections& process,
                                    std::vector<std::string>* notes);
// What processTargets compensates, in words (um, urad, um/h).
std::string describeProcessTargets(const ProcessCorrections& process);

// Reads, predicts, compensates, writes the text (named `output` in its notes) and measures it
// read back, the whole program in memory. Throws InputError.
CompensationRun runCompensation(const CompensateInputs& in, const std::string& output,
                                const Progress& progress = {});
// Where the joints of every point go: beside the JSON report, <report stem>_joints.csv.
std::string compensatedJointsPath(const std::string& report_json);
// Writes the program, the JSON report and the joints (CSV) as a set, then the report directory
// (when given).
void writeCompensation(const CompensationRun& run, const std::string& output,
                       const std::string& report_json, const std::string& report_dir);

// --table: one CSV per linear axis (pitch and straightness), and what such tables leave.
struct TableRun {
  Machine machine;
  std::vector<AxisTable> tables;
  std::string reference;     // the reference pose, in words ("X=0 mm Y=0 mm ...")
  TableEffect flat, full;    // rotary axes at the reference; whole travel, rotaries moving
  int rotary_terms = 0;      // non-zero error terms of the rotary axes (no table carries them)
  std::string rotary_names;  // the first of them
  std::vector<std::string> files;
};
// Computes the tables and writes <stem>_<axis>.csv for each (stem: `table` without extension).
TableRun runTables(const MachineOptions& machine, double step_mm, const std::string& table);

// tolver compensate: the tables (when asked) and the compensated program (when a program is
// given), written; then the read-back check.
struct CompensateRun {
  std::optional<TableRun> tables;
  std::optional<CompensationRun> compensation;
  std::string output, report, joints;  // written with the program
  // The read-back check: lines whose point is further off after than before (by more than 1 um
  // and 10 %): the written program moves where the original did not (verdict NotMet).
  std::vector<int> worse_lines;
  double worse_max_um = 0.0;
  Verdict verdict = Verdict::Ok;
};
// A program compensated whole (no --lines, no --process; CL data or G-code) is read, predicted,
// compensated and written block by block, then read back and predicted block by block: memory
// independent of the program's length (its points' records wait in a temporary file beside the
// output between the passes; a first pass finds the whole program's flags and, for G-code, the
// blocks that start an arc, one bit per line; the charts of --report-dir keep at most 4 points
// of every 1/10 000 of the program, the largest before and after). The files are those of
// runCompensation, byte for byte. --lines and --process are compensated whole (runCompensation):
// a piece is matched to its read-back by line, and the process's program clock and tools are
// the whole program's. CompensateInputs::block_points = 0 compensates whole too.
// Throws InputError (FieldError "output": neither a program's output nor tables asked for).
// Progress: streamed, "reading" (or "fitting the measured set-up" on a calibrated machine),
// "compensating", "reading back", each with the fraction of the file read; whole, "reading and
// predicting", "compensating", "writing and reading back" (each 0, then the next).
CompensateRun compensateProgram(const CompensateInputs& in, const Progress& progress = {});

}  // namespace tolver
