#pragma once
// Inverse kinematics on the nominal model (no errors): from a CL point (tool tip p_w and tool
// axis u_w, both in the workpiece frame w; u_w points from the tip towards the spindle) to joint
// values, for any serial topology with up to two rotary axes and three prismatic axes.
//
// Method: the tool-axis direction depends only on the rotary joints. Writing the orientation
// chain from w to t as  w_R_t = C0 Rot(a1, s1 q1) C1 Rot(a2, s2 q2) C2  (s = -1 for joints on the
// workpiece branch, which enter inverted), u_w = w_R_t k is the Paden-Kahan sub-problem 2
//   Rot(a1, phi1) Rot(C1 a2, phi2) (C1 C2 k) = C0^T u_w,
// solved in closed form (two solutions); one rotary axis is sub-problem 1. With the rotary
// angles fixed, the tool tip is affine in the prismatic joints, so one nominal pass along the
// chains gives the exact 3x3 linear system for them.
//
// Singular orientations (the tool axis along a rotary axis, which leaves that angle free) keep
// the previous value of the free angle (0 at the start of a path) and are flagged. "Along" means
// within the control's singular band (MachineModel::control.singular_band, 1e-4 rad by
// default): inside it the free angle is kept and the other solved for the tool axis, so a
// micro-radian tilt near the pole cannot swing the free axis by tens of degrees; the tool axis
// is then reached to within the band, the tool tip exactly.
#include <Eigen/Core>
#include <array>
#include <vector>

#include "core/kinematics/forward_kinematics.h"
#include "core/model/machine_model.h"

namespace tolver {

enum class IkStatus {
  Ok,
  UnreachableOrientation,  // no rotary angles give this tool axis
  OutOfTravel,             // solutions exist but none inside every axis's travel
  UnsupportedTopology,     // > 2 rotary axes, parallel rotary axes, or not 3 prismatic axes
};

struct IkSolution {
  IkStatus status = IkStatus::Ok;
  JointVector q;              // joint values (mm, rad), model axis order
  bool singular = false;      // a rotary angle was free and kept from the previous point
  int violated_axis = -1;     // with OutOfTravel: the first axis outside its travel on the
                              // preferred solution; -1 when the prismatic system is singular
  double violated_value = 0;  // and the value it would need
  // cos and sin of each rotary joint value (for reuse by the forward model), by axis index;
  // entries of prismatic axes are left unset (not zero-filled: this runs per CL point).
  std::array<double, kMaxAxes> cos_q, sin_q;
};

class InverseKinematics {
 public:
  explicit InverseKinematics(const MachineModel& model);

  // Solves for (p_w, u_w). previous: the joint values of the previous point on the path, or
  // nullptr at the start. Among the candidate solutions inside travel it returns the one closest
  // to previous in the rotary angles (continuity: the sum over rotary axes of |value - previous|,
  // each angle unwrapped by 2 pi to the nearest representative inside travel), or closest to zero
  // at the start; when the nearest one puts a prismatic axis out of travel, the other.
  // previous_cos, previous_sin (optional, by axis index): cos and sin of previous's rotary
  // values, when the caller has them (IkSolution::cos_q and sin_q of the previous point).
  // exact_angles: each rotary value from atan2, unwrapped by 2 pi to the representative nearest
  // the previous one, never as the previous value plus a step (the usual case along a path,
  // whose last bits then carry the rounding of every step before): the solution then depends on
  // previous only through the choice of candidate and representative.
  IkSolution solve(const Eigen::Vector3d& p_w, const Eigen::Vector3d& u_w,
                   const JointVector* previous, const double* previous_cos = nullptr,
                   const double* previous_sin = nullptr, bool exact_angles = false) const;

  // The batch path of prediction: solve() along consecutive CL points, bit for bit the same
  // as calling it point by point with the previous point's solution as reference (none at the
  // start and after a point that failed, as predictToolPath does). The closed-form candidates,
  // both candidates' prismatic solutions and the angle steps from each candidate of the
  // previous point are computed four points at a time (eight on an AVX-512 processor:
  // core/numerics/lanes.h); the continuity choice then runs point by point on them, and any
  // point off the common case (singular, near-singular closed form, a step of more than
  // 0.1 rad, a travel limit in play) is handed to solve().
  static constexpr int kBlock = 64;
  struct Block {
    int n = 0;                          // points in this block, <= kBlock
    double p[3][kBlock], u[3][kBlock];  // in: tip p_w (mm) and tool axis u_w, by coordinate
    bool has_before = false;            // in: a point precedes the block on the path,
    double u_before[3] = {0, 0, 1};     // with this tool axis
    bool exact_first = false;           // in: the first point solved with exact angles (solve())
    // in: the lane stage solves the prismatic axes for this candidate only (-1: both); the
    // choice solves them for the other where it takes it (a hint: the previous block's last
    // candidate, which a smooth path keeps; the results are the same either way)
    int prism_only = -1;
    // out, by axis index: joint values (mm, rad), cos and sin of the rotary ones (0, 1, 0
    // where the point failed)
    // (q and singular start on cache lines: the prediction streams them out whole)
    alignas(64) double q[kMaxAxes][kBlock];
    double c[kMaxAxes][kBlock], s[kMaxAxes][kBlock];
    IkStatus status[kBlock];
    alignas(64) bool singular[kBlock];
    int violated_axis[kBlock];
    double violated_value[kBlock];
    int from_lanes = 0;  // points solved on the lane stage's numbers (the others by solve())
    // Scratch: candidate k's cos and sin of rotary r at point i in [k][r][i + 1] (index 0: the
    // previous block's last point), the prismatic solution of each candidate, the angle steps
    // delta[k][r] from candidate k of the previous point, the chords chord2[j][k] from its
    // candidate j, and lane masks.
    double cand_c[2][2][kBlock + 1], cand_s[2][2][kBlock + 1];
    double prism[2][3][kBlock];
    double delta[2][2][kBlock], chord2[2][2][kBlock];
    long long irregular[kBlock], prism_ok[2][kBlock], delta_ok[2][2][kBlock];
    // The common case's test (blockChoice), for each candidate j the previous point was solved
    // from: the point regular, j's branch nearer by chords, both steps from it in the series,
    // its prismatic solution inside travel.
    long long common[2][kBlock];
    // The candidate each point was solved from by the choice (-1: by solve()).
    signed char taken[kBlock];
  };
  // What solveBlock carries from one block to the next.
  struct Cursor {
    bool has_previous = false;
    JointVector previous;
    std::array<double, kMaxAxes> previous_cos, previous_sin;
    int previous_candidate = -1;  // the previous point's solution is its candidate k (-1: none)
  };
  // The batch path applies: two rotary axes along +x, +y or +z, three prismatic axes.
  bool batchable() const { return batchable_; }
  void solveBlock(Block& b, Cursor& cursor) const {
    b.prism_only = cursor.previous_candidate;
    blockLanes(b);
    blockChoice(b, cursor);
  }
  // solveBlock's two stages: the lane stage depends on the block alone (blocks may run it on
  // several threads at once); the choice needs the cursor, block after block in path order.
  void blockLanes(Block& b) const;
  void blockChoice(Block& b, Cursor& cursor) const;

  // One solution of the orientation sub-problem: the rotary joint values that give a tool axis,
  // in the order of rotaryAxes(), before travel checks and unwrapping.
  struct RotaryCandidate {
    std::array<double, 2> cos{}, sin{};  // of each joint value (NaN where free)
    std::array<double, 2> angle{};       // each joint value, where known (in [-pi, pi])
    std::array<bool, 2> known{};         // angle computed (the closed form gives cos and sin)
    std::array<bool, 2> free{};          // left undetermined by a singular orientation
    // The joint value of rotary r in (-pi, pi] (NaN where free): atan2 only when asked, since
    // the continuity choice rarely needs the angles of the candidate it rejects.
    double angleOf(int r) const;
  };
  // The candidates for the tool axis u_w, at most two. Returns how many were written to out;
  // *singular tells whether an angle was left free.
  int rotaryCandidates(const Eigen::Vector3d& u_w, RotaryCandidate out[2], bool* singular) const;
  const std::vector<int>& rotaryAxes() const { return rotary_; }

  // With the rotary joints of q fixed, sets its prismatic joints so that the tool-frame point
  // b_t lands on target_w (both mm). Returns false when no solution lies inside travel
  // (*violated_axis names the first axis outside it, or -1 when the system is singular).
  bool placeToolPoint(const Eigen::Vector3d& b_t, const Eigen::Vector3d& target_w, JointVector& q,
                      int* violated_axis) const;

 private:
  // trig_given: trig already holds cos and sin of q's rotary joints; otherwise they are computed
  // and stored there.
  bool solvePrismatic(const Eigen::Vector3d& p_w, JointVector& q, IkSolution* trig,
                      const Eigen::Vector3d& b_t = Eigen::Vector3d::Zero(),
                      bool trig_given = false) const;

  // The closed form of two rotary axes (rotaryCandidates) over L = double or lanes::Lane4:
  // for a tool axis u_w (3 of L, not necessarily unit), the cos and sin of rotary r's joint
  // value in candidate k (+g, -g) into c[k][r], s[k][r]; g; and masks: unreachable, the two
  // axes free, and g < 1e-2 (refined by Gauss-Newton).
  template <typename L, typename M>
  void candidatesL(const L u_w[3], L c[2][2], L s[2][2], L* g, M* unreachable, M* free1, M* free2,
                   M* refine) const;
  // The prismatic solution (solvePrismatic) over L: c, sn the cos and sin of the rotary joints
  // by axis index (q their values, for axes off +x/+y/+z, scalar only), m0 the tool point
  // t_end * b_t, p_w the target. Writes the three prismatic values in column order; returns
  // the mask of |det| > 1e-12.
  template <typename L>
  auto prismaticL(const L* q, const L* c, const L* sn, const double m0[3], const L p_w[3],
                  L out[3]) const;

  friend struct IkLaneKernels;  // blockLanes's kernels (inverse_kinematics.cpp)

  const MachineModel* model_;
  bool batchable_ = false;
  int column_axis_[3] = {-1, -1, -1};  // the prismatic axis of each column of the solution
  std::vector<int> rotary_;            // rotary axis indices in w->t chain order
  std::vector<int> prismatic_;         // prismatic axis indices
  Eigen::Matrix3d C0_, C1_, C2_;
  Eigen::Vector3d a_[2];     // rotary directions in the sub-problem frames
  double sign_[2] = {1, 1};  // -1 for workpiece-branch joints
  bool parallel_rotaries_ = false;
  // The constants of sub-problem 2 (two rotary axes): Rot(w1, phi1) Rot(w2, phi2) p2 = C0^T u.
  Eigen::Vector3d w1_, w2_, w12_, p2_;
  double w1w2_ = 0.0, w2p2_ = 0.0, p2_sq_ = 0.0, w12_sq_ = 1.0;
  // Its two sub-problems 1 (rotaryCandidates): u1 = w2 - (w1.w2) w1, u2 = w1 - (w1.w2) w2,
  // v1 = w1 x w12, pp2 = p2 - w2 (w2.p2), v2 = w2 x pp2, and their fixed products.
  struct {
    Eigen::Vector3d u1, u2, v1;
    double u1_sq = 0, u2_sq = 0, pp2_sq = 0, pp2_u2 = 0, pp2_w12 = 0, v2_u2 = 0, v2_w12 = 0;
  } sub1_;
  // The nominal chains, precomputed for the prismatic solve (workpiece branch, tool branch).
  struct ChainLink {
    int axis = 0;
    Eigen::Matrix3d link_R, link_Rt;
    Eigen::Vector3d link_p;
    Eigen::Vector3d direction;
    bool identity_link = false;
    bool identity_rotation = false;  // the link a pure translation
    bool rotary = false;
    int principal = -1;  // 0/1/2 when the joint direction is +x/+y/+z
    int column = 0;      // prismatic joints: its column (1..3) in the carried block
  };
  std::vector<ChainLink> chains_[2];
  Eigen::Isometry3d w_end_, t_end_;  // last joint -> w, last joint -> t (nominal)
  double band_sq_ = 1e-18;           // sin^2 of the singular band (NcControl::singular_band)
};

}  // namespace tolver
