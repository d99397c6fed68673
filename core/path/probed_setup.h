#pragma once
// The part's set-up from probed points: what a shop measures before it cuts, and what a ball-bar
// calibration cannot see (where the part sits on the table). A touch probe in the spindle
// (its tip a length L below the gauge point) touches the part at known points; at each touch the
// control records the joint values q_i. The part frame's error (the WorkpieceSetup block: its
// offset and rotation in the table frame) is fitted so that the machine, errors included, puts
// the probe tip where the part's nominal point is:
//   min over v of  sum_i | n_i^T (tip_w(q_i; v) - p_i_w) |^2   (probing along a direction n_i),
//   or            sum_i |        tip_w(q_i; v) - p_i_w  |^2   (a point probed in full),
// by Gauss-Newton on the set-up columns of the sensitivity Jacobian (in w). With the part's six
// values, the spindle's constant offset (the ToolSetup translations, shared by the probe and the
// cutter: what calibrating the probe on the machine measures; the cutter's length relative to
// the probe's is preset): a ball-bar cannot see it either, and touches at several table
// orientations separate it from the part's offset. Directions the touches do not constrain (the
// spindle offset when every touch is at one orientation, the rotation about z when every touch
// is along z) keep the machine file's values (minimum-norm step, the part preferred over the
// spindle) and are named.
//
// A spindle tram (a test indicator in the spindle swept over the table: ISO 230-1's squareness
// of the spindle axis to the table) adds the spindle's constant tilt (the ToolSetup rotations
// about x and y), which neither a ball-bar (its balls' positions are free, and the tool side of
// this machine only translates) nor touches at one probe length can see, and which sets the
// tool axis against the part: its rows are the measured tilt minus the model's, times
// kTramLever so that a radian counts as a touch over that length.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/model/machine_model.h"

namespace tolver {

struct ProbedPoint {
  int line = 0;                                   // source line, for messages
  JointVector q;                                  // joint values at the touch (mm, rad)
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();  // the probe tip's nominal point in w, mm
  Eigen::Vector3d n_w = Eigen::Vector3d::Zero();  // unit probing direction; zero: full point
  double probe_length = 0.0;                      // probe tip below the gauge point, mm
  // A spindle tram instead of a touch (tram = true): the tool axis measured against the table
  // at q, as the x and y components of the unit tool axis in the table frame (rad: the tilt
  // about -x is tilt[1], about y tilt[0]); p_w, n_w and probe_length are unused.
  bool tram = false;
  Eigen::Vector2d tilt = Eigen::Vector2d::Zero();
};

constexpr double kTramLever = 100.0;  // mm per rad of a tram row

// The tool axis's x and y components in the table frame (the part set-up taken out) at q: what
// a tram measures, on this machine.
Eigen::Vector2d tramTilt(const Machine& machine, const JointVector& q);
// The tram row this machine would give at q (a simulation's measurement).
ProbedPoint simulatedTram(const Machine& machine, const JointVector& q, int line = 0);

struct ProbedSetupFit {
  Vector6d change = Vector6d::Zero();  // added to the WorkpieceSetup block: x y z mm, rx ry rz rad
  Eigen::Vector3d spindle_change = Eigen::Vector3d::Zero();  // added to the ToolSetup x y z, mm
  Eigen::Vector2d spindle_tilt_change = Eigen::Vector2d::Zero();  // ToolSetup rx ry, rad (trams)
  int trams = 0;                                                  // tram rows among the points
  int observed = 0;                     // set-up directions the touches constrain
  int columns = 0;                      // of these many (6; 9 with the spindle offset; 11 with
                                        // its tilt, when a tram is given)
  std::vector<std::string> unobserved;  // names of those they do not ("rotation about z", ...)
  std::vector<double> residual;         // per touch, mm (along n_i, or the distance); per tram,
                                        // the tilt's disagreement, rad
  double rms = 0.0, max = 0.0;          // of the touches' residuals after the fit, mm
  double rms_before = 0.0;              // with the machine file's set-up, mm
  double tram_max = 0.0, tram_before = 0.0;  // largest tram disagreement after / before, rad
  int iterations = 0;
};

// Fits and applies (machine.params of the WorkpieceSetup block += change). Throws
// std::invalid_argument when the machine has no WorkpieceSetup block or no point is given.
ProbedSetupFit fitProbedSetup(Machine& machine, const std::vector<ProbedPoint>& points);

// The parameters the fit moves (part 6, then spindle 3 when the model has a ToolSetup block, then
// the spindle's tilt 2 with trams) and the column scale it solves in (mm for translations,
// rotations times 100 mm, the spindle's translations times 1000 so that the minimum-norm step
// puts what the touches cannot tell apart on the part).
std::vector<int> probedSetupColumns(const MachineModel& model, Eigen::VectorXd* scale,
                                    bool with_tram = false);
bool hasTram(const std::vector<ProbedPoint>& points);
// Rows of the touches (one per probed direction, three for a full point; two per tram) for the
// given parameter columns: what the uncertainty of a prediction modulo a probed set-up is built
// from.
void probedRows(const Machine& machine, const std::vector<ProbedPoint>& points,
                const std::vector<int>& columns, Eigen::MatrixXd* rows);

}  // namespace tolver
