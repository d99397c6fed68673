#pragma once
// Forward kinematics of the machine with its errors ([AM01] eq. 27, 45-53, 82-89):
//   w_T_t = (F_T_w)^-1 * F_T_t,
//   F_T_w = D_1 ... D_n * table_T_w * E_w,   F_T_t = D_1 ... D_m * spindle_T_t * E_t,
// each joint D_S = D1_S * L_S * D2_S(s) * E_S(s), all exact HTMs (no small-angle shortcut).
#include <Eigen/Core>
#include <vector>

#include "core/model/machine_model.h"

namespace tolver {

// A workspace bound to one model and one parameter vector: the position-independent parts
// (nominal link times link errors, set-up frames) are composed once at construction, so each
// evaluation costs one motion and one motion-error HTM per axis.
class ForwardKinematics {
 public:
  // params: parameterCount() values (mm, rad), laid out as model.blocks say.
  ForwardKinematics(const MachineModel& model, const Eigen::VectorXd& params);

  // Pose of the tool frame t seen from the workpiece frame w at joint values q.
  // ctx: the configuration's approach directions and time, for blocks that depend on them.
  Eigen::Isometry3d w_T_t(const JointVector& q, const MotionContext* ctx = nullptr) const;
  // The tool tip (origin of t, mm) and the unit tool axis (z of t) in w: the same as
  // w_T_t(q).translation() and .linear().col(2), computed by carrying the two vectors through
  // the chains (matrix-vector products only): the hot path of prediction.
  // cos_q, sin_q: optional cos and sin of the rotary joint values (by axis index), when the
  // caller has them already (inverse kinematics does).
  void tipAndAxis(const JointVector& q, Eigen::Vector3d* p_w, Eigen::Vector3d* u_w,
                  const double* cos_q = nullptr, const double* sin_q = nullptr,
                  const MotionContext* ctx = nullptr) const;
  // tipAndAxis for n configurations at once (the batch path of prediction), four side by side
  // (eight on an AVX-512 processor: core/numerics/lanes.h), bit for bit the same as tipAndAxis
  // point by point.
  // q[a], cq[a], sq[a]: n joint values of axis a (mm, rad), and the cos and sin of the rotary
  // ones; p_w[k], u_w[k]: n values of coordinate k (x, y, z) of the tip (mm) and the unit axis.
  // Needs batchable(); configurations with motion-error angles beyond 1 mrad are computed one by
  // one (exactly, as tipAndAxis does).
  void tipAndAxisBatch(int n, const double* const q[], const double* const cq[],
                       const double* const sq[], double* const p_w[3], double* const u_w[3]) const;
  // The batch path applies: no effect blocks (they need the motion context) and every rotary
  // axis along +x, +y or +z.
  bool batchable() const { return batchable_; }
  // Pose of the workpiece (tool) frame seen from the foundation.
  Eigen::Isometry3d F_T_w(const JointVector& q) const;
  Eigen::Isometry3d F_T_t(const JointVector& q) const;
  // D_S of axis a at joint value s (parent joint frame -> this joint frame).
  Eigen::Isometry3d jointTransform(int a, double s) const;
  // The six motion-error values [ex ey ez gx gy gz] of axis a at joint value s (mm, rad).
  Vector6d motionErrors(int a, double s, const MotionContext* ctx = nullptr) const;

  // The instrument's own length error (the bar_length effect), mm: added to ball-bar readings.
  double barLengthError() const { return bar_length_error_; }

  const MachineModel& model() const { return *model_; }

  // A point (column 0) and a direction (column 1) carried through the chains by tipAndAxis.
  using Carry = Eigen::Matrix<double, 3, 2>;
  const Eigen::VectorXd& params() const { return params_; }

  // Frames along the chains at q, all seen from F: for each axis a, after_link[a] is the frame
  // after D1 L (where link errors act) and after_joint[a] the joint frame after E(s) (where
  // motion errors act); F_T_w and F_T_t close the chains.
  struct ChainFrames {
    std::vector<Eigen::Isometry3d> after_link, after_joint;
    Eigen::Isometry3d F_T_w, F_T_t;
  };
  void chainFrames(const JointVector& q, ChainFrames* out,
                   const MotionContext* ctx = nullptr) const;

 private:
  // A rigid pose as rotation and translation: cheaper to compose than Isometry3d in the hot loop.
  struct Pose {
    Eigen::Matrix3d R;
    Eigen::Vector3d p;
  };
  // this = this * D_S(s), composed in place.
  void composeJoint(int a, double s, Pose& T, const MotionContext* ctx) const;
  Pose chain(const std::vector<int>& axes, const JointVector& q, const MotionContext* ctx) const;
  friend struct FkLaneKernels;  // tipAndAxisBatch's kernels (forward_kinematics.cpp)

  struct AxisTerms {
    Eigen::Isometry3d fixed;            // D1 * L (nominal link with link errors)
    Eigen::Matrix3d fixed_R, fixed_Rt;  // its rotation and transpose, contiguous for the hot path
    Eigen::Vector3d fixed_p;
    bool fixed_identity = false;    // no nominal offset and no link errors: D1 L = I
    bool fixed_R_identity = false;  // D1 L a pure translation
    std::array<int, 6> offset;      // motion-error coefficient offsets, -1 if none
    std::array<int, 6> degree;
    int max_degree = -1;      // -1: no Chebyshev motion errors on this axis
    bool has_errors = false;  // Chebyshev motion errors or effects on this axis
    struct Effect {
      const EffectSpec* spec;
      int component;
      int size;
      std::array<double, 8> coef;
    };
    std::vector<Effect> effects;  // effect blocks acting on this axis (core/model/effects.h)
    int principal = -1;           // 0/1/2 when the joint direction is +x/+y/+z
    double mid = 0.0;             // travel midpoint and 2 / travel range, for eq. 58
    double inv_half_range = 1.0;
    Eigen::Matrix<double, 6, Eigen::Dynamic> coef;  // column k: c_k of the six components
  };
  // motionErrors of an axis with effect blocks (x: s normalised by eq. 58).
  Vector6d motionErrorsWithEffects(const AxisTerms& t, double s, double x,
                                   const MotionContext* ctx) const;
  // The carry of tipAndAxis over L = double or lanes::Lane4: M = [p u] (3 x 2 of L) from t_end
  // through the tool chain to F (p <- D_S(s) p, u <- R_S(s) u), then through the workpiece
  // chain inverted to w. q, c, sn: joint values and the cos and sin of rotary ones, by axis.
  // Returns the lanes whose motion-error angles need more than the small-angle series (never
  // for double, which computes those itself).
  template <typename L>
  auto carry(const L* q, const L* c, const L* sn, L M[3][2], const MotionContext* ctx) const;
  template <typename L>
  void motionErrorsL(const AxisTerms& t, L s, L e[6]) const;

  const MachineModel* model_;
  Eigen::VectorXd params_;
  std::vector<AxisTerms> axis_;
  Eigen::Isometry3d table_T_w_err_;    // nominal set-up times workpiece set-up errors
  Eigen::Isometry3d spindle_T_t_err_;  // nominal tool frame times tool set-up errors
  Eigen::Isometry3d w_end_;            // last workpiece joint -> w (table, set-up, errors)
  Eigen::Matrix3d w_end_Rt_;           // the transpose of its rotation
  Eigen::Isometry3d t_end_;            // last tool joint -> t
  double bar_length_error_ = 0.0;
  bool batchable_ = false;
};

}  // namespace tolver
