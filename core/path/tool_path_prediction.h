#pragma once
// CL_predicted ([AM01] 5.5.1-5.5.3): for each CL point, joint values by inverse kinematics on
// the nominal machine, then the actual tool pose from the forward model with the machine's
// errors. Deviations are expressed in the workpiece frame w.
#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "core/kinematics/inverse_kinematics.h"
#include "core/model/machine_model.h"

namespace tolver {

// A cutter-location point: tool tip p_w (mm) and unit tool axis u_w (tip -> spindle), in w.
struct ClPoint {
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();
  Eigen::Vector3d u_w = Eigen::Vector3d::UnitZ();
  int line = 0;  // source line in the CL file (1-based), for messages
  bool rapid = false;  // a positioning move (APT RAPID), not a cutting move
};

// Three whole cache lines (64-byte aligned, 192 bytes): the prediction writes a block of points
// with full-line stores that need not read the lines first.
struct alignas(64) PredictedPoint {
  // Left uninitialised on purpose: predictToolPath writes every field of every point, and a
  // zero-filling pass over a long path costs a tenth of the prediction.
  PredictedPoint() {}
  JointVector q;                       // joint values from nominal IK (mm, rad)
  Eigen::Vector3d p_pred_w;            // predicted tool tip (mm)
  Eigen::Vector3d u_pred_w;            // predicted unit tool axis
  Eigen::Vector3d deviation_w;         // p_pred_w - p_w (mm)
  double along_axis;                   // deviation . u_w (mm)
  double across_axis;                  // |deviation - along u_w| (mm)
  double axis_angle;                   // angle between u_w and u_pred_w (rad)
  bool singular;
};

struct PredictionFailure {
  int index = 0;       // CL point index
  int line = 0;        // CL file line
  IkStatus status = IkStatus::Ok;
  int axis = -1;       // with OutOfTravel: the axis that breaks its travel first
  std::string message;
};

struct PredictionSummary {
  int points = 0;
  int singular_points = 0;
  int first_singular_line = 0;
  double max_deviation = 0.0;   // mm, |deviation_w|
  double rms_deviation = 0.0;   // mm
  int max_index = -1;           // point with the largest deviation
  double max_axis_angle = 0.0;  // rad
  double rms_axis_angle = 0.0;  // rad
};

struct PredictionResult {
  std::vector<PredictedPoint> points;     // one per CL point; NaN where IK failed
  std::vector<PredictionFailure> failures;  // the first max_failures
  int failed_points = 0;                  // all of them
  // Failing points per axis that breaks first (index as model.axes; the last entry counts the
  // points with no axis to blame: unreachable orientation, singular prismatic system).
  std::vector<int> failures_per_axis;
  PredictionSummary summary;
  bool ok() const { return failures.empty(); }
};

// Predicts the path; params are the machine's error parameters (model.parameterCount()).
// Stops collecting failures after max_failures.
// commanded: optional, one joint vector per point (a G-code program's joint words): the inverse
// kinematics then takes the solution nearest to the commanded rotary values, i.e. the one the
// control was told to use, instead of the one nearest to the previous point.
PredictionResult predictToolPath(const MachineModel& model, const Eigen::VectorXd& params,
                                 const std::vector<ClPoint>& path, int max_failures = 20,
                                 const std::vector<JointVector>* commanded = nullptr);
// The same into an existing result, reusing its storage (no allocation when it already holds as
// many points): for batch work over many programs.
void predictToolPath(const MachineModel& model, const Eigen::VectorXd& params,
                     const std::vector<ClPoint>& path, PredictionResult& result,
                     int max_failures = 20,
                     const std::vector<JointVector>* commanded = nullptr);

// batch: false takes the reference path, one point at a time, that the batch path (four
// or eight points side by side, when the model allows: InverseKinematics and ForwardKinematics
// batchable()) reproduces bit for bit (tests); without commanded joints only.
void predictToolPath(const MachineModel& model, const Eigen::VectorXd& params,
                     const std::vector<ClPoint>& path, PredictionResult& result, int max_failures,
                     const std::vector<JointVector>* commanded, bool batch);

// The batch path in stages, for a driver that runs them on several threads
// (pipeline/parallel_prediction.h): blocks of InverseKinematics::kBlock points. lanes() and
// forward() of different blocks may run at the same time; choice() and account() run one block
// at a time, in path order. predictToolPath runs the four in turn on one thread; any order
// that keeps those rules gives its result, bit for bit.
class BlockPrediction {
 public:
  struct Work;  // one block's numbers (about 50 kB)
  // Prepares result for path (its points resized, its failures and summary cleared).
  BlockPrediction(const MachineModel& model, const Eigen::VectorXd& params,
                  const std::vector<ClPoint>& path, PredictionResult& result, int max_failures);
  ~BlockPrediction();
  // The stages apply (InverseKinematics and ForwardKinematics batchable()).
  bool batchable() const;
  size_t blocks() const;
  std::shared_ptr<Work> newWork() const;  // (shared: Work is complete only in core)
  void lanes(size_t block, Work& w) const;  // the block's IK lane stage
  void choice(Work& w);                     // the continuity choice, after the previous block's
  void forward(Work& w) const;              // forward carry, deviations, the block's points
  void account(Work& w);                    // failures and summary, after the previous block's
  void finish();                            // after the last block

 private:
  struct State;
  std::unique_ptr<State> s_;
};

// A large rotary step between two consecutive cutting moves: the machine swings the part or
// the head while the tool is in the material (a program risk near the singular pole).
struct RotaryJump {
  int index = 0;      // the point after the step
  int line = 0;       // its source line
  int axis = 0;       // model axis index
  double step = 0.0;  // rad, signed
};
// Rotary steps above threshold (rad) between consecutive points that are both cutting moves
// (not rapid) and both predicted.
std::vector<RotaryJump> findRotaryJumps(const MachineModel& model, const std::vector<ClPoint>& path,
                                        const PredictionResult& result, double threshold);

// One-line description of an IK failure (axis names and values in mm or deg).
std::string describeIkFailure(const MachineModel& model, const IkSolution& sol);

}  // namespace tolver
