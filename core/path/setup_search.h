#pragma once
// Set-ups that reach: the joint ranges a program needs on a machine, and the part zero, part
// rotation (about the table z axis) and gauge length that keep the whole program inside every
// axis's travel with the largest margin.
//
// For a fixed rotation and gauge length the rotary joints of each point do not depend on the
// part zero x (table frame, mm) and its prismatic joints are affine in it, q_ij(x) = a_ij + B_ij x
// (nominal inverse kinematics, exact). The margin
//   t(x) = min over points i and prismatic axes j of min(q_ij(x) - lo_j, hi_j - q_ij(x))
// is concave and piecewise linear for one orientation solution per point. A point of CL data
// has two (the inverse kinematics falls back to the other when the first leaves travel), so the
// margin takes, per point, the better of its solutions. It is maximised by Nelder-Mead with
// restarts from the given part zero, for each candidate rotation (steps of rotation_step) and
// gauge length; the proposal is then checked on every point with the real inverse kinematics.
// Rotary travel does not depend on x; a rotation whose rotary angles leave travel is rejected.
#include <Eigen/Core>
#include <array>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "core/model/machine_model.h"
#include "core/numerics/units.h"
#include "core/path/tool_path_prediction.h"

namespace tolver {

struct AxisRange {
  double min = 0.0, max = 0.0;         // joint values the program needs (mm, rad)
  int min_index = -1, max_index = -1;  // points where they occur
  bool known = false;
};

// The joint ranges of a path on a model with its set-up, ignoring prismatic travel (so that a
// program outside travel still shows how far it needs to go). failed: points whose tool axis
// the rotary axes cannot give inside their travel.
std::vector<AxisRange> jointRanges(const MachineModel& model, const std::vector<ClPoint>& path,
                                   const std::vector<JointVector>* commanded, int* failed,
                                   int* first_failed_index);

struct SetupSearchOptions {
  double rotation_step = degToRad(15.0);  // candidate part rotations, rad (0 to keep the given one)
  std::vector<double> gauge_lengths;      // candidates, mm; empty: the model's
  int max_points = 20000;                 // points used in the search (evenly spaced subset)
  bool stop_when_found = false;           // return the first set-up that reaches every point
  // A time budget, s (0: none): once spent, the search stops with the best set-up of the
  // rotations tried (SetupSearchResult::budget_spent); one rotation is always tried.
  double max_seconds = 0.0;
  // Called with the fraction of the candidate rotations searched (0..1), from the calling thread.
  std::function<void(double)> progress;
};

struct SetupSearchResult {
  bool found = false;   // a set-up with every point inside travel (margin >= 0)
  PartSetup setup;      // the best one (largest margin), even when not found
  double margin = 0.0;  // mm: the smallest distance of a prismatic joint to its travel limit
  std::vector<AxisRange> ranges;  // with the best set-up
  std::vector<int> outside;       // with the best set-up: points outside travel
  int rotations_tried = 0, rotations_rejected = 0;
  bool budget_spent = false;  // max_seconds ran out before every rotation was tried
};

SetupSearchResult findSetup(const MachineModel& model, const std::vector<ClPoint>& path,
                            const std::vector<JointVector>* commanded,
                            const SetupSearchOptions& options = {});

// A program no single set-up reaches, cut into consecutive pieces that each one set-up
// reaches: greedily the longest reachable piece from the start, found by bisection on its end.
struct SetupPiece {
  int first = 0, last = 0;   // indices into the path, inclusive
  SetupSearchResult result;  // its set-up (found is false for a single point no set-up reaches)
};
// options.max_seconds (0: none) bounds the whole split: each search gets what is left, and once
// it is spent the split stops with the pieces finished so far (*budget_spent set); options.
// progress is called with the fraction of the path split.
std::vector<SetupPiece> splitIntoSetups(const MachineModel& model, const std::vector<ClPoint>& path,
                                        const std::vector<JointVector>* commanded,
                                        const SetupSearchOptions& options = {}, int max_pieces = 8,
                                        bool* budget_spent = nullptr);

// A posted program outside tool-centre-point mode gives joints, not tool tips: machine
// coordinate = word + work offset (+ tool length along the spindle under G43). A work offset the
// set-up does not give has its origin at the part zero (io/program/gcode_reader.h), so moving the
// part zero moves the joints of every point given in a work offset by one affine map, and leaves
// the points in machine coordinates (G53, G28, SUPA) where they are. The per-axis ranges then
// fit travel exactly when each is centred: the proposal is exact, not searched.
struct WorkOffsetSetup {
  bool found = false;                                        // every point inside travel
  double margin = -std::numeric_limits<double>::infinity();  // mm, smallest distance to a limit
  int limiting_axis = -1;                                    // the axis with that margin
  bool limited_by_machine_coordinates = false;  // by a G53/G28 move, which no offset moves
  // mm, the smallest distance of the work-offset moves alone (each axis's range centred) to a
  // limit: the margin the proposal chose; `margin` is smaller when a G53/G28 move sits nearer an
  // end (a home position at the end of travel: 0).
  double work_offset_margin = -std::numeric_limits<double>::infinity();
  Eigen::Vector3d part_zero_table = Eigen::Vector3d::Zero();  // proposed part zero, table frame
  // The work offset (G54...) the control needs for it: the machine coordinates (mm, X Y Z words
  // with the control's senses) of the program's origin.
  Eigen::Vector3d work_offset_m = Eigen::Vector3d::Zero();
  std::vector<AxisRange> ranges;  // joint ranges with the proposal
  // Per X Y Z (prismatic joint order): false when no point moves that coordinate in the work
  // offset (only G53/G28 moves set it): the program does not place the part zero along it, and
  // the proposal leaves it where the set-up had it.
  std::array<bool, 3> placed = {true, true, true};
};
// joints, kind and fixed: ClProgram::joints, ::tcp (points of kind 1, in TCP mode, are left
// out) and ::fixed_axes (bit k: X, Y, Z in machine coordinates; when empty, every coordinate of
// a kind-2 point, G53/G28, is fixed).
WorkOffsetSetup proposeWorkOffset(const MachineModel& model, const std::vector<JointVector>& joints,
                                  const std::vector<char>& kind,
                                  const std::vector<unsigned char>& fixed = {});
// The ranges of the joints a posted program commands (points in TCP mode included: their joints
// are the reader's), and the smallest distance of any to its travel (negative when outside;
// endless axes are not limits): the reach check of a work-offset proposal, on the program read
// again with it.
std::vector<AxisRange> commandedJointRanges(const MachineModel& model,
                                            const std::vector<JointVector>& joints, double* margin,
                                            int* limiting_axis);

// The work offset (machine coordinates, mm) whose origin is the model's part zero: what the
// G-code reader uses for a work offset the set-up does not give.
Eigen::Vector3d workOffsetAtPartZero(const MachineModel& model);

}  // namespace tolver
