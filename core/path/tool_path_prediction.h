#pragma once
// CL_predicted ([AM01] 5.5.1-5.5.3): for each CL point, joint values by inverse kinematics on
// the nominal machine, then the actual tool pose from the forward model with the machine's
// errors. Deviations are expressed in the workpiece frame w.
#include <Eigen/Core>
#include <array>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "core/kinematics/inverse_kinematics.h"
#include "core/model/machine_model.h"
#include "core/numerics/aligned_allocator.h"

namespace tolver {

// A cutter-location point: tool tip p_w (mm) and unit tool axis u_w (tip -> spindle), in w.
struct ClPoint {
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();
  Eigen::Vector3d u_w = Eigen::Vector3d::UnitZ();
  int line = 0;        // source line in the CL file (1-based), for messages
  bool rapid = false;  // a positioning move (APT RAPID), not a cutting move
  // The feed rate of the move to this point (mm/min), NAN where the program gives none the
  // reader can turn into mm/min (per revolution without a spindle speed, inverse time).
  float feed_mm_min = NAN;
};

// One predicted point, as a value: PredictedPoints assembles it from its arrays.
struct PredictedPoint {
  JointVector q;                // joint values from nominal IK (mm, rad)
  Eigen::Vector3d p_pred_w;     // predicted tool tip (mm)
  Eigen::Vector3d u_pred_w;     // predicted unit tool axis
  Eigen::Vector3d deviation_w;  // p_pred_w - p_w (mm)
  double along_axis = 0.0;      // deviation . u_w (mm)
  double across_axis = 0.0;     // |deviation - along u_w| (mm)
  double axis_angle = 0.0;      // angle between u_w and u_pred_w (rad)
  bool singular = false;
};

// The predicted points of a path, stored field by field (structure of arrays): the batch
// prediction writes each field of a block of points as whole cache lines, 137 bytes a point on
// a five-axis machine where a record of every field took 192. points[i] assembles point i;
// iteration gives the points by value.
class PredictedPoints {
 public:
  // The numbers of a point after its joint values, one array each.
  enum Field {
    kTipX,
    kTipY,
    kTipZ,
    kAxisX,
    kAxisY,
    kAxisZ,
    kDevX,
    kDevY,
    kDevZ,
    kAlong,
    kAcross,
    kAngle,
    kFields
  };
  size_t size() const { return n_; }
  bool empty() const { return n_ == 0; }
  int axes() const { return axes_; }
  PredictedPoint operator[](size_t i) const;
  PredictedPoint back() const { return (*this)[n_ - 1]; }
  void set(size_t i, const PredictedPoint& p);  // p.q holds axes() values
  void setFailed(size_t i);                     // NaN in every number, not singular
  // Points from..from+count of `other` (as many axes) into to..to+count.
  void copyFrom(const PredictedPoints& other, size_t from, size_t count, size_t to);
  // n points of axes joint values, their numbers unspecified (storage is kept when it holds
  // them: no allocation when a result is reused for a path as long).
  void resize(size_t n, int axes);
  // The arrays, each 64-byte aligned and writable up to size() rounded up to a multiple of 64
  // (whole cache lines): joint value a of every point (mm, rad), field f of every point, the
  // singular flags (0 or 1).
  double* q(int a) { return numbers_.data() + a * stride_; }
  const double* q(int a) const { return numbers_.data() + a * stride_; }
  double* field(int f) { return q(axes_ + f); }
  const double* field(int f) const { return q(axes_ + f); }
  unsigned char* singular() { return singular_.data(); }
  const unsigned char* singular() const { return singular_.data(); }

  class const_iterator {
   public:
    using iterator_category = std::input_iterator_tag;
    using value_type = PredictedPoint;
    using difference_type = std::ptrdiff_t;
    using pointer = void;
    using reference = PredictedPoint;
    const_iterator(const PredictedPoints* points, size_t i) : points_(points), i_(i) {}
    PredictedPoint operator*() const { return (*points_)[i_]; }
    const_iterator& operator++() {
      ++i_;
      return *this;
    }
    bool operator==(const const_iterator& o) const { return i_ == o.i_; }
    bool operator!=(const const_iterator& o) const { return i_ != o.i_; }

   private:
    const PredictedPoints* points_;
    size_t i_;
  };
  const_iterator begin() const { return {this, 0}; }
  const_iterator end() const { return {this, n_}; }

 private:
  size_t n_ = 0, stride_ = 0;
  int axes_ = 0;
  std::vector<double, AlignedAllocator<double>> numbers_;  // (axes + kFields) arrays of stride
  std::vector<unsigned char, AlignedAllocator<unsigned char>> singular_;
};

struct PredictionFailure {
  int index = 0;  // CL point index
  int line = 0;   // CL file line
  IkStatus status = IkStatus::Ok;
  int axis = -1;  // with OutOfTravel: the axis that breaks its travel first
  std::string message;
};

// The headline figures are over the cutting points (ClPoint::rapid false) that were predicted:
// rapids (positioning, home and machine-coordinate moves) are counted apart, with their own
// largest deviation.
struct PredictionSummary {
  int points = 0;
  int singular_points = 0;
  int first_singular_line = 0;
  double max_deviation = 0.0;        // mm, |deviation_w|, over cutting points
  double rms_deviation = 0.0;        // mm, over cutting points
  int max_index = -1;                // cutting point with the largest deviation
  int max_line = 0;                  // its source line
  double max_axis_angle = 0.0;       // rad, over cutting points
  double rms_axis_angle = 0.0;       // rad
  int rapid_points = 0;              // rapids predicted, not in the figures above
  double rapid_max_deviation = 0.0;  // mm
  int rapid_max_index = -1;
  int rapid_max_line = 0;
};

struct PredictionResult {
  PredictedPoints points;                   // one per CL point; NaN where IK failed
  std::vector<PredictionFailure> failures;  // the first max_failures
  int failed_points = 0;                    // all of them
  // Failing points per axis that breaks first (index as model.axes; the last entry counts the
  // points with no axis to blame: unreachable orientation, singular prismatic system).
  std::vector<int> failures_per_axis;
  PredictionSummary summary;
  bool ok() const { return failures.empty(); }
};

// A path predicted in consecutive stretches (a program read and written block by block, its
// memory independent of its length): what each stretch hands the next (the inverse kinematics'
// choice, the last point's tool axis, the approach directions of direction-dependent effects),
// and the failures and summary of the whole path so far. The stretches' points are those of the
// whole path predicted at once, bit for bit, when every stretch but the last holds a multiple of
// BlockPrediction::kExactEvery points (tested). Given to a prediction (`carry`), the result's
// points are the stretch's and its failures, failures_per_axis and summary the whole path's so
// far, with indices in the whole path.
class PredictionCarry {
 public:
  PredictionCarry();
  ~PredictionCarry();
  PredictionCarry(PredictionCarry&&) noexcept;
  PredictionCarry& operator=(PredictionCarry&&) noexcept;
  PredictionCarry(const PredictionCarry& other);  // a copy, to predict ahead with
  size_t points() const;                          // predicted so far
  struct State;                                   // (complete in core)
  State& state() { return *s_; }

 private:
  std::unique_ptr<State> s_;
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
                     int max_failures = 20, const std::vector<JointVector>* commanded = nullptr);

// batch: false takes the reference path, one point at a time, that the batch path (four
// or eight points side by side, when the model allows: InverseKinematics and ForwardKinematics
// batchable()) reproduces bit for bit (tests); without commanded joints only.
void predictToolPath(const MachineModel& model, const Eigen::VectorXd& params,
                     const std::vector<ClPoint>& path, PredictionResult& result, int max_failures,
                     const std::vector<JointVector>* commanded, bool batch,
                     PredictionCarry* carry = nullptr);

// The batch path block by block, for a driver that runs blocks on several threads
// (pipeline/parallel_prediction.h): blocks of InverseKinematics::kBlock points. predict()
// solves a block's inverse kinematics, chooses among the solutions with a cursor it carries
// from the block before (continuity), runs the forward model and the deviations, writes the
// block's points and its tally (failures and sums); finish() merges the tallies in path order.
// With the prediction's own cursor, blocks go through predict() in path order; blocks with
// other cursors may run at the same time. predictToolPath runs every block with cursor() on
// one thread.
//
// A driver may also run a stretch of blocks speculatively with a cursor of its own (from an
// empty Cursor{}) from a point solved with exact angles (kExactEvery), then, once the true
// cursor at the stretch's start is known, run its blocks again with it until the two cursors
// agree (sameCursor): from there on the speculative blocks are the true ones.
class BlockPrediction {
 public:
  struct Work;  // one block's numbers (about 40 kB)
  using Cursor = InverseKinematics::Cursor;
  // Every kExactEvery-th point of a path (0 included) is solved with exact angles
  // (InverseKinematics::solve's exact_angles), on every path through the prediction: after it
  // the joint values no longer carry the rounding of the steps before, so a speculative stretch
  // that starts there agrees with the true one as soon as both take the same candidate.
  static constexpr size_t kExactEvery = 64 * InverseKinematics::kBlock;
  // Prepares result for path (its points resized, its failures and summary cleared).
  // With a carry, path is the next stretch of a longer one (PredictionCarry): the cursor starts
  // as the stretch before left it, and finish() hands it on.
  BlockPrediction(const MachineModel& model, const Eigen::VectorXd& params,
                  const std::vector<ClPoint>& path, PredictionResult& result, int max_failures,
                  PredictionCarry* carry = nullptr);
  ~BlockPrediction();
  // The stages apply (InverseKinematics and ForwardKinematics batchable()).
  bool batchable() const;
  size_t blocks() const;
  std::shared_ptr<Work> newWork() const;  // (shared: Work is complete only in core)
  // The block's points and tally, in w's scratch, from cursor, which is left as the block's
  // last point leaves it.
  void predict(size_t block, Work& w, Cursor& cursor) const;
  void finish();     // after the last block: failures and summary
  Cursor& cursor();  // the prediction's own
  // The two cursors lead the choice of the blocks after them to the same bits.
  bool sameCursor(const Cursor& a, const Cursor& b) const;

 private:
  // predict's stages. lanes: the IK lane stage; hint: the cursor's candidate (-1 for none),
  // which a smooth path keeps: the stage then solves the prismatic axes for it alone (the
  // result is the same with any hint). forward: forward carry, deviations, the block's points.
  // account: the block's failures and tally.
  void lanes(size_t block, Work& w, int hint) const;
  void forward(Work& w) const;
  void account(Work& w) const;
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
// The same over a path given in consecutive stretches (a program read in blocks).
class RotaryJumpFinder {
 public:
  RotaryJumpFinder(const MachineModel& model, double threshold);
  // The stretch's points, the first at index first_index of the whole path.
  void add(const std::vector<ClPoint>& path, const PredictedPoints& points, size_t first_index);
  std::vector<RotaryJump> jumps;

 private:
  const MachineModel& model_;
  double threshold_;
  bool has_previous_ = false, previous_rapid_ = false;
  std::array<double, kMaxAxes> previous_q_{};
};

// One-line description of an IK failure (axis names and values in mm or deg).
std::string describeIkFailure(const MachineModel& model, const IkSolution& sol);

}  // namespace tolver
