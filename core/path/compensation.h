#pragma once
// Compensation: the joint values at which the machine, errors included, puts the tool tip and the
// tool axis where the program asked, and the program that commands them.
//
// For each program point (p_w, u_w), starting from the nominal inverse kinematics q0 (or the
// program's commanded joints), Newton on
//   r(q) = [ tip_w(q) - p_w ;  L e1 . u(q) ;  L e2 . u(q) ]      (e1, e2 across u_w, L = 100 mm)
// with tip_w and u the forward kinematics with the errors (the exact model, no small-angle
// shortcut) and the Jacobian dr/dq by forward differences, solved by SVD. Stops when the tip is
// within `tolerance` and the axis within `angle_tolerance`. Near a singular pose (the tool axis
// on a rotary axis: the condition of the Jacobian, orientation rows times L, beyond
// max_condition) correcting the tool axis would swing a rotary axis half a turn: the axis is
// left as programmed and the tip compensated by the prismatic joints (IllConditioned, reported).
// A 3-axis program (orientation=false) moves the prismatic joints only.
//
// The corrected program is then the nominal machine's pose at the compensating joints (what a
// post-processor for a perfect machine turns into exactly those joints): for CL data,
// nominal_p_w and nominal_u_w; for G-code, the joint changes q - q0.
#include <Eigen/Core>
#include <memory>
#include <vector>

#include "core/model/machine_model.h"
#include "core/path/tool_path_prediction.h"

namespace tolver {

struct CompensationOptions {
  double tolerance = 1e-7;        // mm
  double angle_tolerance = 1e-9;  // rad
  int max_iterations = 20;
  // The Jacobian (orientation rows times L) is ill-conditioned beyond this condition number: the
  // point's tool axis is left as programmed, its tip compensated, and it is reported.
  double max_condition = 1e6;
  // Per point (optional): 1 where the tool axis is not the program's to change (a swivel cycle
  // such as Sinumerik CYCLE800 set the rotaries): the tip compensated by the prismatic joints,
  // the axis left as programmed.
  const std::vector<char>* tip_only = nullptr;
};

enum class CompensationStatus {
  Compensated,     // within the tolerances
  IllConditioned,  // near a singular pose: the tip compensated, the axis left as programmed
  OutOfTravel,     // the compensating joints leave travel: left uncompensated, reported
  NotConverged,    // no convergence in max_iterations: left uncompensated, reported
};

struct CompensatedPoint {
  CompensationStatus status = CompensationStatus::Compensated;
  JointVector q0;  // the program's joints (nominal inverse kinematics)
  JointVector q;   // the compensating joints (q0 when left uncompensated)
  Eigen::Vector3d nominal_p_w =
      Eigen::Vector3d::Zero();  // nominal machine's tip at q: the corrected CL
  Eigen::Vector3d nominal_u_w = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d before_w =
      Eigen::Vector3d::Zero();                        // tip deviation at q0 (machine - program), mm
  Eigen::Vector3d after_w = Eigen::Vector3d::Zero();  // at q
  double before_axis = 0, after_axis = 0;             // tool-axis angle to the program's, rad
  double condition = 1;                               // of the final Jacobian
  int iterations = 0;
  int axis_out = -1;  // OutOfTravel: the first axis beyond travel
};

struct CompensationResult {
  std::vector<CompensatedPoint> points;
  int ill_conditioned = 0, out_of_travel = 0, not_converged = 0;
};

// path and q0 (one joint vector per point, e.g. PredictionResult::points[i].q) on the machine
// with the given error parameters.
// predicted (optional): the machine's pose at q0 per point (predictToolPath's p_pred_w, u_pred_w),
// which saves evaluating it again.
CompensationResult compensateToolPath(const MachineModel& model, const Eigen::VectorXd& params,
                                      const std::vector<ClPoint>& path,
                                      const std::vector<JointVector>& q0, bool orientation = true,
                                      const CompensationOptions& options = {},
                                      const PredictedPoints* predicted = nullptr);

// The same over a path given in consecutive stretches (a program read in blocks): what is carried
// from point to point (the kept Jacobian, the warm start, the basis across the tool axis) is
// carried across stretches too, so that the points are compensateToolPath's on the whole path,
// bit for bit. tip_only (optional): per point of the stretch, as CompensationOptions::tip_only
// (which this ignores).
class StreamCompensator {
 public:
  StreamCompensator(const MachineModel& model, const Eigen::VectorXd& params,
                    const CompensationOptions& options = {});
  ~StreamCompensator();
  StreamCompensator(const StreamCompensator&) = delete;
  StreamCompensator& operator=(const StreamCompensator&) = delete;
  CompensationResult compensate(const std::vector<ClPoint>& path,
                                const std::vector<JointVector>& q0, bool orientation,
                                const PredictedPoints* predicted = nullptr,
                                const std::vector<char>* tip_only = nullptr);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// Compensation tables for a control's linear axes (pitch and straightness): for each prismatic
// axis, on a grid over its travel with the other joints at q_ref, the changes of the prismatic
// joints that put the tool tip back where the nominal machine puts it (compensateToolPath,
// position only), relative to the grid point at q_ref's position (zero there: the constant goes
// into the work offset). A control adds the tables of all axes at their positions; what depends
// on more than one axis (angular errors seen through the tool length and the other axes'
// offsets), and every error of a rotary axis, a linear table cannot carry.
struct AxisTable {
  int axis = 0;
  double start = 0, step = 0;               // mm
  std::vector<double> position;             // mm
  std::vector<Eigen::Vector3d> correction;  // per position: the changes of the prismatic
                                            // joints (in prismatic-axis order), mm
  std::vector<int> prismatic;               // the prismatic axes' indices
};
std::vector<AxisTable> linearAxisTables(const MachineModel& model, const Eigen::VectorXd& params,
                                        const JointVector& q_ref, double step);
// The tables' correction at joints q (linear interpolation, clamped at the ends), added over
// the axes: the prismatic joint changes a control applies (mm).
Eigen::Vector3d tableCorrection(const std::vector<AxisTable>& tables, const JointVector& q);
// What the tables leave: the tool-tip deviation (RMS, mm) over `samples` poses drawn evenly over
// the travel (the rotary joints at q_ref's values, or over their travel too), before and with
// the tables applied; both relative to the deviation at q_ref (a constant the work offset takes).
struct TableEffect {
  double before_rms = 0, after_rms = 0;
};
TableEffect tableEffect(const MachineModel& model, const Eigen::VectorXd& params,
                        const std::vector<AxisTable>& tables, const JointVector& q_ref,
                        bool rotaries_move, int samples = 500, unsigned seed = 1);

}  // namespace tolver
