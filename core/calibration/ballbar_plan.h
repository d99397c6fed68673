#pragma once
// Planning a three-set-up ball-bar test ([AM01] 4.8.1, Fig. 4.9): joint configurations inside
// travel whose nominal ball-to-ball distance is the bar length, chosen among many sampled ones
// to maximise identifiability (greedy D-optimal design on the column-scaled identification
// Jacobian: each new pose is the candidate that most increases det(J^T J)).
#include <Eigen/Core>
#include <functional>
#include <vector>

#include "core/calibration/ballbar.h"
#include "core/model/machine_model.h"

namespace tolver {

struct BallbarPlanOptions {
  // Called with the fraction of the poses chosen (0..1), from the calling thread; may be empty.
  std::function<void(double)> progress;
  double bar_length = 150.0;  // mm
  // Per set-up bar lengths (mm), cycled over the set-ups; empty: bar_length for every set-up.
  // Two or more lengths let a calibration tell the bar's own length error from machine scale.
  std::vector<double> bar_lengths;
  int setups = 3;
  int poses = 180;  // in all, shared equally between the set-ups
  unsigned seed = 1;
  int candidates_per_pose = 5;      // sampled configurations per selected one
  double min_elevation_deg = 10.0;  // bar elevation above the machine's xy plane
  // A drift check: after every `reference_every` poses of a set-up, the set-up's first pose is
  // measured again (0: never). These repeats come on top of `poses`.
  int reference_every = 0;
  // Largest correlation of time (the reading's index) with a joint within a set-up that the
  // measurement order may have (see timeJointCorrelation).
  double max_time_correlation = 0.3;
  // Joint ranges to plan in (mm, rad, per axis; empty: the travel): rotary angles are drawn
  // from them and candidates whose prismatic joints leave them by more than range_margin are
  // rejected. plan-ballbar --for sets them to the ranges a program uses.
  std::vector<double> range_min, range_max;
  double range_margin = 50.0;  // mm
  // Where the machine will be used (a program's poses): when given, poses are chosen by the
  // prediction variance of the tool tip there (greedy I-optimal design: each new pose is the
  // candidate that most reduces the summed variance of the tips at these poses) instead of
  // D-optimality.
  std::vector<JointVector> target_poses;
  // Set-up geometry; when empty, defaults: table balls 80 mm off the table's axis at three
  // heights, tool balls 25 mm off the spindle axis at 60, 180 and 300 degrees (so the spindle's
  // own errors are observable).
  std::vector<BallbarSetup> geometry;
};

struct BallbarPlan {
  BallbarTest test;  // readings without lengths
  int unknowns = 0;  // machine parameters + 6 per set-up
  int rank = 0;
  double condition = 0;  // column-scaled identification Jacobian at the nominal machine
  int sampled = 0, rejected = 0;
  double time_correlation = 0;     // |r| of the measurement order (reading index vs joint)
  int time_correlation_axis = -1;  // the axis it is largest for
};

// unknowns: the machine parameters to identify (see defaultCalibrationUnknowns).
BallbarPlan planBallbarTest(const MachineModel& model, const std::vector<int>& unknowns,
                            const BallbarPlanOptions& options);

// How well a test can tell a time effect (drift, warm-up) from a joint effect: per axis, the
// correlation of time with the joint value within the set-ups (both centred on each set-up's
// mean, then pooled). NaN for an axis when the readings have no time or the axis never moves.
struct TimeJointCorrelation {
  std::vector<double> r;  // per axis, model order
  int worst_axis = -1;    // largest |r|
  double worst = 0.0;     // |r| of that axis
};
TimeJointCorrelation timeJointCorrelation(const MachineModel& model, const BallbarTest& test);

// The expected standard uncertainty (mm) of the tool tip predicted at each of `poses` by the
// machine a plan would identify, before anyone measures: the plan's identification Jacobian at
// the nominal machine with readings of standard deviation noise_mm gives the covariance of the
// machine parameters (ball positions free), carried to the tip modulo the measured set-up (see
// core/path/prediction_uncertainty.h).
std::vector<double> expectedTipUncertainty(const MachineModel& model,
                                           const std::vector<int>& unknowns,
                                           const BallbarTest& plan, double noise_mm,
                                           const std::vector<JointVector>& poses);

// The default set-up geometry for n set-ups.
std::vector<BallbarSetup> defaultBallbarSetups(int n);

}  // namespace tolver
