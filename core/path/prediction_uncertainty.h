#pragma once
// The uncertainty of a predicted tool pose: the covariance of the identified parameters
// (IdentificationUncertainty, from a calibration) carried to the tool tip and tool axis by the
// sensitivity Jacobian at the pose (first order):
//   Sigma_twist = J_id Sigma_params J_id^T   (6 x 6, twist in t),
//   Sigma_tip_w = R_wt Sigma_d R_wt^T        (3 x 3, the tip in w, mm^2),
// and the tool axis's angular uncertainty from the rotations about the two axes across it.
// Where the joints leave the ranges the readings covered, the fitted polynomials extrapolate:
// the covariance says how much that costs, and the point is flagged.
#include <Eigen/Core>
#include <vector>

#include "core/kinematics/forward_kinematics.h"
#include "core/path/probed_setup.h"

namespace tolver {

struct PoseUncertainty {
  Eigen::Matrix3d tip_covariance_w = Eigen::Matrix3d::Zero();  // mm^2
  double tip = 0.0;   // mm, 1 sigma along the worst direction (sqrt of the largest eigenvalue)
  double axis = 0.0;  // rad, 1 sigma of the tool axis's direction (worst direction)
  // The covariance of the tool axis's direction across it (rad^2): its components along t's x and
  // y, e = (w_y, -w_x) for a small rotation w of t; the spindle-tilt prior included.
  Eigen::Matrix2d axis_covariance_t = Eigen::Matrix2d::Zero();
  // The tool frame's rotation (a small rotation w of t, seen in w; rad^2) and its covariance with
  // the tip (mm rad), the spindle-tilt prior included across the axis: a point of the cutter at
  // r_w from the tip moves by d_tip + w x r_w (alongContact). axis_w: the tool axis.
  Eigen::Matrix3d rotation_covariance_w = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d tip_rotation_covariance_w = Eigen::Matrix3d::Zero();
  Eigen::Vector3d axis_w = Eigen::Vector3d::UnitZ();
  // The shares of the calibration's covariance alone (mm, rad): tip and axis above add the
  // identification's lack of fit (tip) and spindle-tilt prior (axis) in quadrature.
  double calibration_tip = 0.0, calibration_axis = 0.0;
  // How far the joints lie outside the covered ranges (mm or rad, per axis; 0 inside; empty
  // when the machine file gives no ranges). Fixed capacity: a long program keeps one per point.
  JointVector beyond;
  bool outside = false;
};

// Modulo a measured set-up. A ball-bar cannot see where the part sits on the table or where
// the tool tip is relative to the spindle: a rigid motion of the workpiece frame moves each
// table ball by a constant, a tool offset each tool ball, and the ball position errors of a
// set-up absorb both. A shop measures them: the part's position and orientation by probing
// (6 values), the tool tip's offset by presetting (length and radial offset, 3 values). Over the
// poses of a program, the set-up that best explains a tip deviation field d is
//   beta = S^+ d,  S = [R_i J_d,i(set-up columns)] stacked (least squares),
// and what is left, d_i - R_i J_d,i(set-up) beta, is the machine's share that no set-up
// removes. setupModulo() fixes S on the program's poses; after it, at() reports the
// uncertainty of that share (the covariance carried through J_id - J_set B, B = S^+ J_id).
// Measured on an independent simulation (tests/prediction_uncertainty_test.cpp): the true
// tip deviation, modulo the same set-up, lies inside 1.96 sigma for 97.5 % of coordinates;
// modulo only the part zero, rotation about the table axis and tool length, for 69 %.
class PredictionUncertainty {
 public:
  // machine.identification must not be empty.
  explicit PredictionUncertainty(const Machine& machine);
  void setupModulo(const std::vector<JointVector>& poses);
  // Modulo the part set-up fitted to probed points (fitProbedSetup): the identification's error
  // reaches a prediction both directly and through the set-up it makes the probe fit find,
  //   J_id(q) - J_part(q) P^+ J_id,probe,
  // P the probe rows of the set-up columns the fit moves (probedSetupColumns). The cutter's length
  // relative to the probe is taken as preset (exact).
  void setupModuloProbed(const std::vector<ProbedPoint>& points);
  // The part of a tip deviation field (one deviation in w per pose) that a measured set-up
  // leaves: d_i - S_i beta, beta fitted over all given poses. Returns beta (part x y z mm,
  // rotations rad, tool offset x y z mm).
  Eigen::VectorXd removeSetup(const std::vector<JointVector>& poses,
                              std::vector<Eigen::Vector3d>& deviations_w) const;
  // The set-up parameters used (indices), for reports.
  const std::vector<int>& setupParameters() const { return setup_; }
  PoseUncertainty at(const JointVector& q, const MotionContext* ctx = nullptr) const;
  // 1 sigma of the tip along a unit direction n_w (mm).
  static double along(const PoseUncertainty& u, const Eigen::Vector3d& n_w) {
    return std::sqrt(std::max(0.0, n_w.dot(u.tip_covariance_w * n_w)));
  }
  // 1 sigma along n_w of the cutter's point at r_w from the tip (mm): the tip and the tool's
  // rotation together, n.d_tip + (r x n).w, the rotation about the tool axis left out (it turns
  // the cutter in itself). A ball end's contact on a flank, or a flank cutter's at height h,
  // moves with the axis's tilt times the lever arm; along() is this with r = 0.
  static double alongContact(const PoseUncertainty& u, const Eigen::Vector3d& n_w,
                             const Eigen::Vector3d& r_w);
  // The 95 % radii: the tip's distance from its prediction (mm, 3-D) and the tool axis's angle
  // from its prediction (rad, 2-D) that hold 95 % of their Gaussian (gaussianRadiusQuantile).
  // 1.96 times the worst direction's sigma holds 95 % only when one direction dominates: for an
  // isotropic covariance it holds 85 % of the axis's angle and 72 % of the tip's distance.
  static double tipRadius95(const PoseUncertainty& u);
  static double axisRadius95(const PoseUncertainty& u);
  // The tip's error along n_w at q as a row a with error = a z, z ~ N(0, I) shared by every pose
  // (mm; the calibration's share, without the lack of fit): a_i a_j^T is the covariance of two
  // poses' errors, so a band's errors over a program are correlated, not independent.
  Eigen::RowVectorXd alongRoot(const JointVector& q, const Eigen::Vector3d& n_w) const;
  // The identified parameters' twist rows at q (6 x identified, in t: tip, then rotation),
  // modulo the measured set-up when one is fixed: what at() and alongRoot() carry the
  // covariance's root through, and what a measured part's deviations are fitted by (measure).
  Eigen::MatrixXd identifiedRows(const JointVector& q, const MotionContext* ctx) const;

 private:
  // R_wt J_d for the given columns at q (3 x columns.size()).
  Eigen::MatrixXd tipColumns(const JointVector& q, const std::vector<int>& columns) const;

  const Machine& machine_;
  ForwardKinematics fk_;
  Eigen::MatrixXd root_;             // Sigma_params = root root^T
  mutable Eigen::MatrixXd J_;        // 6 x parameterCount work matrix
  std::vector<int> setup_;           // the part's pose (6), the tool tip's offset (3)
  std::vector<int> modulo_columns_;  // the set-up values B_ fits (all of setup_, or the part's)
  Eigen::MatrixXd B_;  // modulo x identified: the set-up fit of each identified column
  bool modulo_ = false;
};

// The set-up a shop measures, applied to a calibrated machine's prediction of a program: the
// set-up beta that best explains the predicted tip deviations at the poses (up to max_poses of
// them, evenly spaced) is taken off the machine's set-up parameters (params -= beta), so that
// predictions made with the result are the machine's share that probing the part and presetting
// the tool leave. Returns beta (part x y z mm, rotations about x y z rad, tool x y z mm).
Eigen::VectorXd applyMeasuredSetup(Machine& machine, const std::vector<JointVector>& q,
                                   const std::vector<Eigen::Vector3d>& deviations_w,
                                   size_t max_poses = 2000);

}  // namespace tolver
