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
  std::string variable;   // "X", "X direction", "C", "time", "set-up", "measurement order"
  std::string test;       // "trend", "periodogram", "direction", "set-up means", "runs"
  double strength = 0.0;  // fraction of the residual variance explained, 0..1
  double p_value = 1.0;
  double period = 0.0;  // periodogram: mm (prismatic), or the harmonic order (rotary)
  double period_uncertainty =
      0.0;             // prismatic periodogram: half the peak's width, P^2 / (2 span), mm
  bool order = false;  // period is a harmonic order (a rotary axis), not a length
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

// Lack of fit (the classical test of a regression with replicates): the residuals of readings
// that repeat a pose (same set-up, same joint values, approached the same way) scatter about their
// pose's mean only by the measurement's repeatability, the pure error, with sum of squares
//   SS_pe = sum over poses of sum (r_i - mean_pose)^2,  df_pe = sum (n_pose - 1);
// what the fit leaves beyond it is the lack of fit, SS_lof = RSS - SS_pe with
// df_lof = (m - fitted) - df_pe. F = (SS_lof / df_lof) / (SS_pe / df_pe), p its F tail. A model
// that lacks something leaves F large; an adequate one F about 1.
struct LackOfFit {
  bool tested = false;  // df_pe >= 2 and df_lof >= 1
  int poses = 0;        // poses measured more than once
  int repeats = 0;      // readings at them
  double df_pure = 0, df_lack = 0;
  double s_pure = 0;  // repeatability, mm (sqrt(SS_pe / df_pe))
  double s_fit = 0;   // the fit's residual sigma, mm (sqrt(RSS / (m - fitted)))
  double s_lack = 0;  // sqrt(SS_lof / df_lof), mm
  double f = 0, p_value = 1;
  // What the model misses beyond the repeatability, as an RMS over the readings (mm):
  // sqrt(max(0, s_fit^2 - s_pure^2)).
  double missing_rms = 0;
};
// fitted: the number of unknowns the fit identified (machine parameters and ball errors).
LackOfFit lackOfFit(const BallbarTest& test, const Eigen::VectorXd& residuals, int fitted);

// residuals: measured - model (mm), one per reading of test, in measurement order.
ResidualAnalysis analyseResiduals(const MachineModel& model, const BallbarTest& test,
                                  const Eigen::VectorXd& residuals);

}  // namespace tolver
