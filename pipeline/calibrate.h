#pragma once
// The calibrate pipeline as library functions: the machine's errors identified from ball-bar
// readings ([AM01] 3.7, 4.9: Gauss-Newton with gross readings removed, a prior towards zero
// chosen by the readings' evidence), then the identified machine, its ball positions and the
// report written as a set and read back. `tolver calibrate` parses and prints.
#include <string>
#include <vector>

#include "core/calibration/ballbar.h"
#include "core/calibration/ballbar_plan.h"
#include "core/calibration/calibration.h"
#include "core/calibration/identifiability.h"
#include "io/machine/ballbar_file.h"
#include "io/report/calibration_report.h"
#include "pipeline/command.h"
#include "pipeline/inputs.h"

namespace tolver {

struct CalibrateInputs {
  MachineOptions machine;
  std::string readings;        // ball-bar readings (CSV)
  std::string heldout;         // held-out readings on the same set-ups (CSV), or empty
  std::string prior = "auto";  // "auto" (by the evidence), "none", or "um,urad"
  bool strict = false;         // refuse a fit whose rank falls short
  bool keep_outliers = false;  // fit every reading, gross ones included
  // The prior of the spindle's tilt against the machine's axes (urad, 1 sigma per direction),
  // which a ball-bar cannot see: written into the identification, added to the tool-axis band
  // of every prediction (0: not stated).
  double spindle_tilt_urad = 0.0;
  // The outputs (calibrateMachine): the identified machine (XML); its ball positions (CSV) and
  // the JSON report, beside it unless given.
  std::string output, balls, report;
};

// The test's design, judged before the fit.
struct TestDesign {
  TimeJointCorrelation time;          // worst_axis < 0: the readings have no time_s
  std::vector<std::string> warnings;  // too few readings for the unknowns; time moving with a joint
};
TestDesign testDesign(const MachineModel& model, const BallbarTest& test, int unknowns);
// A warning when the identified model predicts the held-out readings much worse than it fits its
// own (more than 3 times the fit's RMS and above 1 um); empty otherwise.
std::string heldoutWarning(const std::string& heldout_file, const ResidualStats& after,
                           double fit_rms);

// Where the outputs go: the identified machine, its ball positions and the JSON report.
struct CalibrationOutputs {
  std::string machine, balls, report;
};
// The outputs' paths (balls and report beside the machine file unless given), checked to be
// writable places before any work is done. Throws InputError.
CalibrationOutputs calibrationOutputs(const std::string& machine, const std::string& balls,
                                      const std::string& report);

struct CalibrationRun {
  Machine machine;                  // as read: the prior values
  BallbarFile file;                 // the readings as read, with the reader's warnings
  BallbarTest heldout;              // aligned to the fit's set-ups (empty: none)
  BallbarTest used;                 // the readings fitted (gross readings removed)
  RobustCalibration robust;         // the fit with and without the gross readings
  std::vector<GrossReading> gross;  // found (removed, or kept with --keep-outliers)
  CalibrationResult fit;
  std::vector<int> unknowns;                        // the machine parameters identified
  std::vector<std::vector<AbsorbedTerm>> absorbed;  // what each unknown stands for
  std::string prior_text = "none";                  // the prior used, in words
  HeldoutFigures heldout_figures;                   // the held-out readings before and after
  Machine identified;                 // the machine with the identified values and covariance
  LackOfFit lack_of_fit;              // the fit's residual against the repeated poses' scatter
  TestDesign design;                  // of the readings as read
  std::vector<std::string> warnings;  // the reader's, the design's, the held-out readings'
  // calibrateMachine: where the outputs went, and what they predict read back.
  CalibrationOutputs outputs;
  WrittenCheck written;
  Verdict verdict = Verdict::Ok;  // NotMet: the fit did not converge
};

// tolver calibrate: checks the outputs' places, identifies, writes the machine, its ball
// positions and the report as a set, and reads them back. Throws InputError.
// Progress: "fitting", then "writing and checking the files" (each 0 then 1).
CalibrationRun calibrateMachine(const CalibrateInputs& in, const Progress& progress = {});

// Reads the inputs and identifies. An unobservable test or no data is an InputError.
CalibrationRun runCalibration(const CalibrateInputs& in);

// Writes the identified machine, its ball positions and the report as a set (all three or
// none), and returns what the written files predict, read back as the next command will.
WrittenCheck writeCalibration(const CalibrationRun& run, const CalibrateInputs& in,
                              const CalibrationOutputs& out);

// The held-out readings of `file`, aligned to the fit's set-ups (an empty test when file is
// empty). Exit 2 (InputError) for an empty file, a set-up the fit lacks, a pose the fit measured.
BallbarTest loadHeldout(const std::string& file, const MachineModel& model, const BallbarTest& fit,
                        const std::string& fit_file);
// "out/m.xml" -> "out/m_balls.csv": the identified ball positions beside the machine file.
std::string ballsPathFor(const std::string& machine_output);

}  // namespace tolver
