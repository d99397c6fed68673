#pragma once
// The inputs every command reads: the machine with its set-up, the part program, probed points,
// and the prediction of the program on the machine (with the set-up a shop measures and the
// prediction's uncertainty on a calibrated machine). No printing, no command-line parsing: the
// options are plain values, in the units their names give (mm, deg).
#include <cmath>
#include <string>
#include <vector>

#include "core/model/machine_model.h"
#include "core/path/prediction_uncertainty.h"
#include "core/path/probed_setup.h"
#include "core/path/tool_path_prediction.h"
#include "io/program/apt_reader.h"
#include "pipeline/command.h"

namespace tolver {

// Machine file plus the set-up options every command accepts.
struct MachineOptions {
  std::string machine;
  std::string setup;
  std::vector<double> part_zero;
  double part_rotation_deg = NAN;
  double gauge_length = NAN;
};

// Reads the machine file and applies the set-up file and options. Throws InputError.
Machine loadMachine(const MachineOptions& o);
// Warnings naming the set-up defaults used (values no file or option gave).
std::vector<std::string> setupWarnings(const MachineModel& model);
// What the machine file says of its errors; *none: it carries none (the machine's share is zero
// by construction).
std::string machineErrorsStatement(const Machine& machine, bool* none);

// The program options every command that reads a part program accepts.
struct ProgramOptions {
  std::string cl, nc;
  std::string units;  // "", "mm" or "inch"
  double chordal_tolerance = 0.001;
  std::string lines;  // "first-last": only the points of these source lines (a piece of a split)
  // Keep the text of APT GOTO statements, for the in-place compensated writer that edits it
  // (compensate sets it); without it a long program costs its points, not its text
  // (AptReadOptions::keep_motion_text).
  bool keep_motion_text = false;
  // NX MSYS in the CAD's absolute frame instead of relative to the first (AptReadOptions).
  bool absolute_msys = false;
  // "wear": G-code's G41/G42 read as wear compensation, the path as written is the tool centre
  // (GcodeReadOptions::cutter_comp_wear); "": refused.
  std::string cutter_comp;
  // LinuxCNC's tool table (io/program/tool_table.h), in the control's default units: the
  // diameters G41/G42 compensate by on a LinuxCNC control; "": none.
  std::string tool_table;
};
// Whether the program reads as G-code (--nc, a G-code extension, or content that reads as
// G-code); FieldError "cl" when neither or both of --cl and --nc are given.
bool readsAsGcode(const ProgramOptions& o);
// Reads the CL or G-code program (G-code: --nc, a G-code extension, or content that reads as
// G-code), as a stream of lines. Throws InputError.
ClProgram loadProgram(const ProgramOptions& o, const MachineModel& model);
// The same in blocks (io/program/apt_reader.h, ProgramBlocks), --lines applied to each: a long
// program's memory independent of its length. Returns the program's state after the last block
// (no points; pointsRead() counts them). An InputError may come after blocks were passed on.
// read_from: another file to read, named as the program in messages (a written program's
// temporary, read back).
ClProgram streamProgram(const ProgramOptions& o, const MachineModel& model,
                        const ProgramBlocks& blocks,
                        const std::function<void(double)>& fraction_read = {},
                        const std::string& read_from = {});
// The same on text already read (path names it and chooses the dialect as above).
ClProgram parseProgram(const std::string& text, const std::string& path, const ProgramOptions& o,
                       const MachineModel& model);
// When the program declares no units: what was assumed, and whether inches fit better.
std::vector<std::string> unitWarnings(const ClProgram& program, const MachineModel& model,
                                      const std::string& units_option);
// The same for a program read in blocks: its points' bounding box (min, max corners, mm).
std::vector<std::string> unitWarnings(const ClProgram& program, const MachineModel& model,
                                      const std::string& units_option, const Eigen::Vector3d& lo,
                                      const Eigen::Vector3d& hi);

// The message for a prediction that failed: the first failing point, how many fail, and per
// axis how many break it first.
std::string describeUnreachable(const MachineModel& model, const PredictionResult& r);
// The program predicted on the machine (its own commanded joints for G-code); a point the
// machine cannot reach is an InputError naming its line (describeUnreachable).
PredictionResult predictProgram(const Machine& machine, const ClProgram& program);
// What the reader assumed or skipped, one line each.
std::vector<std::string> programNotes(const ClProgram& program);
// The same over a program read in blocks: add() each block in order, then notes() with the
// program's state after the last.
class ProgramNotes {
 public:
  void add(const ClProgram& block);
  std::vector<std::string> notes(const ClProgram& program) const;

 private:
  std::vector<AptStatement> pending_;  // coordinate system statements before any point after them
  std::string frame_note_;             // the first that moved the points
};

// Evenly spaced poses of a program, taken point by point in bounded memory: every step-th point,
// the step a power of two doubled whenever more than 2 * kFew are held, so that kFew to 2 kFew
// remain (all of a shorter program). The set-up a shop measures is fitted over them.
class EvenPoses {
 public:
  static constexpr size_t kFew = 2000;
  bool wants(size_t index) const { return index % step_ == 0; }
  void add(size_t index, const JointVector& q, const Eigen::Vector3d& deviation_w);
  std::vector<JointVector> q;
  std::vector<Eigen::Vector3d> deviation_w;

 private:
  size_t step_ = 1;
  std::vector<size_t> index_;
};

// Throws FieldError(field) when the directory of `path` does not exist.
void checkOutputDir(const std::string& path, const char* field);
// A prediction on a calibrated machine (one whose file carries its calibration's covariance):
// unless `absolute`, the set-up a shop measures (part probed, tool preset), which the calibration
// cannot see, is fitted to the prediction and applied to the machine, and `pred` redone with it;
// then the uncertainty of each point's prediction (modulo that set-up). Nothing for a machine
// that was not calibrated.
// With probed points (the set-up the shop measured, --probed), the part set-up is fitted to them
// instead (fitProbedSetup, on any machine, calibrated or not), the tool taken as preset, and the
// uncertainty is modulo that fit.
struct CalibratedPrediction {
  Eigen::VectorXd measured_setup;            // part x y z (mm), rotations (rad), tool x y z (mm)
  std::vector<PoseUncertainty> uncertainty;  // per program point
  bool probed = false;
  ProbedSetupFit probe;  // when probed
};
CalibratedPrediction applyCalibration(Machine& machine, const ClProgram& program,
                                      PredictionResult& pred, bool absolute,
                                      const std::vector<ProbedPoint>& probed = {});
// The probed points of --probed FILE (none for an empty path).
std::vector<ProbedPoint> loadProbed(const std::string& path, const MachineModel& model);
// The console line for a probed set-up fit, and its warnings (unobserved directions, points the
// fitted set-up does not explain).
std::string describeProbedSetup(const std::string& path, const ProbedSetupFit& fit,
                                const std::vector<ProbedPoint>& points,
                                std::vector<std::string>* warnings);

// Creates a report directory (and its parents); an unwritable place, a path below a regular
// file or naming one is FieldError(field) (exit 2), never an internal error.
void makeReportDir(const std::string& dir, const char* field = "report_dir");

// `path` with its extension replaced (or `suffix` appended when it has none).
std::string replaceExtension(const std::string& path, const std::string& ext);

}  // namespace tolver
