#pragma once
// tolver plan-ballbar and simulate-ballbar as library functions: a three-set-up telescoping
// ball-bar test planned for identifiability ([AM01] 3.7, 4.8), written as a plan (CSV) and an NC
// program; and the readings a machine with given (true) errors would give for a plan.
#include <string>
#include <vector>

#include "core/calibration/ballbar_plan.h"
#include "pipeline/command.h"
#include "pipeline/inputs.h"

namespace tolver {

struct PlanBallbarInputs {
  MachineOptions machine;
  BallbarPlanOptions plan;         // set-ups, poses, seed, reference_every (default 8), ...
  std::vector<double> lengths_mm;  // bar lengths, one per set-up in turn; empty: plan.bar_length
  std::string output;              // plan to write (CSV)
  std::string gcode;               // NC program to write; empty: output with .nc
  double feed = 2000.0;            // mm/min of the NC program
  int heldout = 0;                 // held-out poses of the same set-ups, planned apart
  ProgramOptions program;          // program.cl: plan where this program cuts (or empty)
  bool volume = false;             // plan for predictions over the whole travel
  double noise_um = 0.5;           // reading noise for the expected prediction uncertainty
  PlanBallbarInputs() { plan.reference_every = 8; }
};

// The expected tip uncertainty (1 sigma, um) at the target poses, after the measured set-up.
struct ExpectedUncertainty {
  double median_um = 0, max_um = 0;
};

struct PlanRun {
  Machine machine;
  std::vector<int> unknowns;  // the machine parameters the plan identifies
  BallbarPlan plan, held;     // held: when heldout > 0
  std::string lengths_text;   // "150.000 mm"
  // With a target (program or volume): the poses the expectation is taken at, the plan's and
  // the default (D-optimal, whole travel) plan's expected uncertainty there, and the gain.
  std::vector<JointVector> target_q;
  std::string target_text;  // the program's path, or "the whole travel"
  size_t targets = 0;       // of target_q, the poses the design was chosen for
  ExpectedUncertainty expected, expected_default;
  double gain = 0;                                           // 1 - median / default median
  bool too_few_readings = false;                             // fewer than 3 readings per unknown
  std::string output, gcode, heldout_output, heldout_gcode;  // written
  Verdict verdict = Verdict::Ok;
};

// Plans, writes the plan, its NC program and the held-out ones as a set. Throws InputError
// (FieldError: "output", "gcode", "volume", "heldout"; a machine without three prismatic axes).
// Progress: "choosing poses" (the fraction of the plan's poses chosen).
PlanRun planBallbar(const PlanBallbarInputs& in, const Progress& progress = {});

struct SimulateBallbarInputs {
  MachineOptions machine;      // the true machine
  std::string plan;            // plan (CSV) from plan-ballbar
  std::string output;          // readings to write (CSV)
  std::string balls;           // ball positions per set-up (CSV, as calibrate writes), or empty
  std::string heldout_plan;    // held-out poses to simulate after the plan, or empty
  std::string heldout_output;  // empty: output with _heldout.csv
  double noise_um = 0.0;       // reading noise, 1 sigma
  double ball_error_um = 0.0;  // random ball position errors per set-up, 1 sigma
  double seconds_per_reading = 20.0;  // time_s step when the plan has none
  unsigned seed = 1;
};

struct SimulationRun {
  Machine machine;
  size_t readings = 0, heldout_readings = 0;
  std::string output, heldout_output;  // written (heldout_output: when a held-out plan was given)
  Verdict verdict = Verdict::Ok;
};

SimulationRun simulateBallbar(const SimulateBallbarInputs& in);

}  // namespace tolver
