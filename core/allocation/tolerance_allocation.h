#pragma once
// Tolerance allocation for machine builders (Cai, Li, Cheng, Sun, Wang: "A method to optimize
// geometric errors of machine tool based on SNR quality loss function and correlation analysis"):
// how loose can each geometric error be toleranced so that the machine costs least while its
// tool-tip error stays within the accuracy limits?
//
// Terms: each toleranced error is one machine parameter with a full tolerance band T (mm or rad)
// between bounds; t = T/2 is the half band.
// Cost (eq. 8):          C = sum_i (h_i t_i)^-r,  h_i from the term's category (Table 3: positional
//                        h_p, linear positioning 1, angular positioning h_a, linear
//                        non-positioning h_d, angular non-positioning h_a h_d), t_i in cost units:
//                        mm for lengths and mm/m (mrad) for angles, as [Cai]'s Table 4 states them.
// Quality loss (eq. 9-13): eta_i = -10 log10(E[y_i^2]) (smaller-the-better SNR) with y_i the error
//                        value within its tolerance; this project's reading: y_i uniform in
//                        [-t_i, t_i] (E[y^2] = t^2/3; or normal with t = 3 sigma, E = t^2/9);
//                        lambda_i = (1/eta_i) / sum_j (1/eta_j); L = w_L sum_i lambda_i t_i^2.
// Accuracy (eq. 15, 21): the largest tool-tip error |dx|, |dy|, |dz| (machine axes, mm) over a
//                        grid of the working volume and rotary axes, worst case over the signs of
//                        the errors inside their tolerances. For each pose and axis the worst sign
//                        vertex follows from the exact model's sensitivities; the nonlinear forward
//                        model then evaluates that vertex (verifyAccuracy).
// Objectives: M1 = C + L (minimise) and M2 = sum over correlation groups g of
//                        sqrt(sum_{i in g} (t_i / t_i,standard)^2) (maximise; eq. 17 with the
//                        groups of this machine's own correlation analysis).
#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

#include "core/model/machine_model.h"

namespace tolver {

enum class ToleranceCategory {
  Positional,             // h_p
  LinearPositioning,      // 1
  AngularPositioning,     // h_a
  LinearNonPositioning,   // h_d
  AngularNonPositioning,  // h_a h_d
};

struct ToleranceTerm {
  std::string name;    // e.g. "dx_x"
  int parameter = -1;  // index into the machine's parameter vector
  ToleranceCategory category = ToleranceCategory::LinearNonPositioning;
  double standard = 0.0;  // full band T, mm or rad
  double lower = 0.0;     // bounds of T
  double upper = 0.0;
  double reference = std::numeric_limits<double>::quiet_NaN();  // e.g. a published allocation
  int reference_group = 0;  // a published correlation class (1..), 0 if none
};

struct AllocationModel {
  double h_p = 3.0, h_a = 4.0, h_d = 5.0;
  double r = 2.0;            // cost characteristic index (all terms)
  double loss_weight = 1.0;  // w_L; 0 leaves the quality loss out
  bool loss_normal = false;  // false: uniform within +-t; true: normal with t = 3 sigma
  Eigen::Vector3d limits{0.015, 0.015, 0.010};  // |dx|, |dy|, |dz| allowed, mm
  // How the terms' effects combine at a pose: worst case over the signs (sum of |effects|,
  // the default) or root-sum-square (statistical stacking of independent errors).
  bool rss = false;
};

// Cost units: mm for lengths, mm/m for angles.
double costUnitValue(const MachineModel& m, const ToleranceTerm& t, double value);
double categoryWeight(const AllocationModel& a, ToleranceCategory c);
double manufacturingCost(const MachineModel& m, const std::vector<ToleranceTerm>& terms,
                         const Eigen::VectorXd& T, const AllocationModel& a);
double qualityLoss(const MachineModel& m, const std::vector<ToleranceTerm>& terms,
                   const Eigen::VectorXd& T, const AllocationModel& a);

// Tool-tip position error sensitivities over the working volume: for every pose, three rows
// (dx, dy, dz in machine axes, mm) and one column per term (mm per mm or per rad), from the
// exact model at zero errors.
struct AccuracyModel {
  std::vector<JointVector> poses;
  Eigen::MatrixXd J;  // 3 * poses x terms
  // |J| and J^2 (element-wise), computed once: the constraint is evaluated with matrix-vector
  // products only, so the optimiser's loop allocates nothing large.
  Eigen::MatrixXd absJ, J2;
};
// A grid of the working volume: `levels` values per prismatic axis, `rotary_levels` per rotary.
std::vector<JointVector> workspaceGrid(const MachineModel& m, int levels, int rotary_levels);
AccuracyModel buildAccuracyModel(const MachineModel& m, const std::vector<ToleranceTerm>& terms,
                                 const std::vector<JointVector>& poses);
// Largest |dx|, |dy|, |dz| over the poses for half bands t = T/2, to first order: worst case
// sum_i |J_ki| t_i, or with rss sqrt(sum_i (J_ki t_i)^2). The optimiser's constraint.
Eigen::Vector3d worstCaseLinear(const AccuracyModel& acc, const Eigen::VectorXd& T,
                                bool rss = false);
// The same with the nonlinear forward model, independent of the linearisation (the check of a
// returned solution): worst case evaluates each pose's worst sign vertex (both signs); rss
// combines each term's exact effect alone.
Eigen::Vector3d verifyAccuracy(const MachineModel& m, const std::vector<ToleranceTerm>& terms,
                               const AccuracyModel& acc, const Eigen::VectorXd& T,
                               bool rss = false);

// Correlation of the terms' effects on the tool tip over the working volume (Pearson correlation
// of the columns of J) and agglomerative clustering (average linkage, distance 1 - |r|) into
// `groups` groups ([Cai] 4.1).
struct CorrelationAnalysis {
  Eigen::MatrixXd correlation;  // terms x terms
  std::vector<int> group;       // per term, 0 .. groups-1
  std::vector<std::vector<int>> members;
};
CorrelationAnalysis correlateTerms(const AccuracyModel& acc, int groups);
double spreadObjective(const std::vector<ToleranceTerm>& terms, const CorrelationAnalysis& c,
                       const Eigen::VectorXd& T);  // M2

struct AllocationOptions {
  int population = 100;  // a multiple of 4
  int generations = 250;
  unsigned seed = 1;
};

struct AllocationSolution {
  Eigen::VectorXd T;          // full bands, mm or rad
  double cost = 0, loss = 0;  // C, L
  double m1 = 0, m2 = 0;
  Eigen::Vector3d worst_linear = Eigen::Vector3d::Zero();
  Eigen::Vector3d worst_exact = Eigen::Vector3d::Zero();
};

struct AllocationResult {
  AllocationSolution standard;            // the standard tolerances
  std::vector<AllocationSolution> front;  // Pareto front, by increasing M1
  int chosen = -1;                        // index into front (rule: closest to the ideal point)
  bool standard_feasible = true;
  CorrelationAnalysis correlation;
  std::string constraint_handling;
};

// NSGA-II (pagmo) on x_i = T_i / standard_i within the bounds. Constraint handling: a repair
// step inside the fitness: an infeasible x is pulled towards the lower bounds along the straight
// line, to the largest step that meets the limits (exact for the first-order constraint, by a
// linear or quadratic root per pose and axis); returned solutions are the repaired ones and are
// re-checked with the nonlinear model. When the lower bounds themselves break the limits, the
// front is empty and standard_feasible is false.
AllocationResult allocateTolerances(const MachineModel& m, const std::vector<ToleranceTerm>& terms,
                                    const AllocationModel& a, const AccuracyModel& acc,
                                    const CorrelationAnalysis& corr, const AllocationOptions& o);

}  // namespace tolver
