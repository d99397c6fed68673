#pragma once
// What a fit's residuals follow: against every joint coordinate (a smooth trend and,
// for uneven sampling, a Lomb-Scargle periodogram: periods of 2 to 100 mm on a prismatic axis,
// harmonic orders 1 to 8 on a rotary one), against each axis's approach direction, against
// time, per set-up, the runs test in measurement order, and the drift of repeated poses.
// Each finding gives the fraction of the residual variance it explains (strength) and a p-value.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/calibration/ballbar.h"
#include "core/model/machine_model.h"

namespace tolver {

struct ResidualFinding {
  std::string variable;  // "X", "X direction", "C", "time", "set-up", "measurement order"
  std::string test;      // "trend", "periodogram", "direction", "set-up means", "runs"
  double strength = 0.0;  // fraction of the residual variance explained, 0..1
  double p_value = 1.0;
  double period = 0.0;    // periodogram: mm (prismatic), or the harmonic order (rotary)
};

// A pose measured several times in one set-up (the plan's drift check).
struct RepeatedPose {
  int setup = 0;
  std::vector<int> readings;  // indices in measurement order
  double span_mm = 0.0;       // max - min residual
};

struct ResidualAnalysis {
  std::vector<ResidualFinding> findings;  // smallest p-value first
  std::vector<RepeatedPose> repeats;
  double runs_z = 0.0, runs_p = 1.0;
  double rms = 0.0;  // mm
  // The variable the residual follows: the first finding when its p-value is below 1e-3
  // (empty: no structure found).
  std::string follows;
  double follows_strength = 0.0;
};

// residuals: measured - model (mm), one per reading of test, in measurement order.
ResidualAnalysis analyseResiduals(const MachineModel& model, const BallbarTest& test,
                                  const Eigen::VectorXd& residuals);

}  // namespace tolver
