#pragma once
// Telescoping ball-bar measurement model ([AM01] 4.8, eq. 79-81).
//
// A reading is the distance between the tool-ball centre b_t (a point of the tool frame t) and
// the table-ball centre b_w (a point of the workpiece frame w):
//   L = | w_T_t(q) (b_t + db_t) - (b_w + db_w) | + dL,
// where db_t (in t) and db_w (in w) are the position errors of the two balls in one set-up
// (unknowns of a calibration, three each per set-up), and dL the bar's own length error (the
// bar_length effect of core/model/effects.h, zero unless the model has it). Its gradient orients
// the error twist along the bar: with n the unit vector from the table ball to the tool ball (in
// w),
//   dL = n^T R_wt (d + theta x b_t) + n^T R_wt db_t - n^T db_w.
#include <Eigen/Core>
#include <array>
#include <cmath>
#include <vector>

#include "core/kinematics/forward_kinematics.h"

namespace tolver {

struct BallbarSetup {
  int id = 0;                                              // as numbered in the file
  Eigen::Vector3d table_ball_w = Eigen::Vector3d::Zero();  // nominal, mm
  Eigen::Vector3d tool_ball_t = Eigen::Vector3d::Zero();   // nominal, mm
};

struct BallbarReading {
  int setup = 0;          // index into BallbarTest::setups
  JointVector q;          // joint values (mm, rad), model axis order
  double length = NAN;    // measured ball-to-ball distance, mm (NaN in a plan)
  MotionContext context;  // time_s and approach directions, passed to the model
  int line = 0;           // source line, for messages
};

struct BallbarTest {
  std::vector<BallbarSetup> setups;
  std::vector<BallbarReading> readings;
};

// Ball errors of one set-up: table ball in w, tool ball in t (mm).
struct BallErrors {
  Eigen::Vector3d table_w = Eigen::Vector3d::Zero();
  Eigen::Vector3d tool_t = Eigen::Vector3d::Zero();
};

// Ball-to-ball distance at q (mm).
double ballbarLength(const ForwardKinematics& fk, const JointVector& q, const BallbarSetup& s,
                     const BallErrors& e = {}, const MotionContext* ctx = nullptr);

// J_length_params: 1 x parameterCount() (mm per parameter unit); J_length_table, J_length_tool:
// derivatives with respect to the ball errors. Returns the length, as ballbarLength.
double ballbarGradient(const ForwardKinematics& fk, const JointVector& q, const BallbarSetup& s,
                       const BallErrors& e, Eigen::Ref<Eigen::RowVectorXd> J_length_params,
                       Eigen::RowVector3d* J_length_table, Eigen::RowVector3d* J_length_tool,
                       const MotionContext* ctx = nullptr);

// Reading change per unit additive change of each motion-error component of each axis
// (1 x 6 * axes, column 6 a + c; see componentSensitivities): what an effect's coefficient
// multiplies by its basis value. scratch: a work matrix (resized).
void ballbarComponentGradient(const ForwardKinematics& fk, const JointVector& q,
                              const BallbarSetup& s, const BallErrors& e,
                              Eigen::Ref<Eigen::RowVectorXd> J_length_components,
                              Eigen::MatrixXd& scratch, const MotionContext* ctx = nullptr);

// The identification Jacobian of a test ([AM01] eq. 80): one row per reading, columns
// [unknown machine parameters..., per set-up: table-ball xyz, tool-ball xyz] (balls: one per
// set-up, the ball errors at which to linearise). residuals, when given: measured - model, mm.
Eigen::MatrixXd identificationJacobian(const ForwardKinematics& fk, const BallbarTest& test,
                                       const std::vector<BallErrors>& balls,
                                       const std::vector<int>& unknowns,
                                       Eigen::VectorXd* residuals = nullptr);

// measured - model (mm) of every reading, with the ball errors of each set-up.
Eigen::VectorXd ballbarResiduals(const ForwardKinematics& fk, const BallbarTest& test,
                                 const std::vector<BallErrors>& balls);

// Size of a set of residuals (mm): RMS and largest magnitude.
struct ResidualStats {
  int readings = 0;
  double rms = 0.0, max = 0.0;
};
ResidualStats residualStats(const Eigen::VectorXd& residuals);

// Directions of approach derived from the sequence: each axis's sign of motion from the previous
// reading (kept when it did not move; 0 for the first reading), where the file gave none.
void deriveDirections(BallbarTest& test);

}  // namespace tolver
