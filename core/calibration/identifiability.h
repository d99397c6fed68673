#pragma once
// Identifiability of error parameters from a stacked Jacobian ([AM01] 3.6, 4.7): rank,
// condition number and SVD of the column-scaled matrix, groups of confounded parameters from
// the right singular vectors of the (near-)zero singular values, and the selection of a
// minimal-complete parameter set by [AM01]'s strategies:
//   I   keep part and tool set-up parameters;
//   II  keep the parameters that stand for recognised link errors (a per-machine list,
//       [AM01] Tables 3.4 and 4.2);
//   III otherwise remove the parameter whose removal leaves the smallest condition number.
// Column scaling, rank and condition: core/numerics/scaled_svd.h.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/kinematics/forward_kinematics.h"
#include "core/numerics/scaled_svd.h"

namespace tolver {

// Stacked sensitivity Jacobian: 6 rows per pose (twist in t), the given parameter columns.
Eigen::MatrixXd stackedJacobian(const ForwardKinematics& fk, const std::vector<JointVector>& poses,
                                const std::vector<int>& columns);

// Parameter columns of [AM01]'s two models: "link" = link errors and set-up errors
// (chapter 3), "motion" = motion-error coefficients and set-up errors (chapter 4);
// "all" = every parameter.
std::vector<int> modelColumns(const MachineModel& m, const std::string& model);

// A copy of the model with every motion component at Chebyshev degree `degree`.
MachineModel withMotionDegree(const MachineModel& m, int degree);

struct ReductionStep {
  std::vector<int> group;  // confounded parameters (parameter indices), largest weight first
  int removed = -1;        // parameter index
  std::string strategy;    // what decided: "no effect", "I", "II", "III" or a chain "I+III"
  int size_after = 0;
  int rank_after = 0;
  double condition_after = 0.0;
};

struct MinimalSet {
  std::vector<int> kept;  // parameter indices, in the order given
  std::vector<int> removed;
  std::vector<ReductionStep> steps;
  SvdSummary initial, reduced;
};

// Reduces `columns` of J (J has one column per entry of `columns`) to a full-rank set.
// setup[i]: parameter `columns[i]` is a set-up parameter (strategy I); preferred: parameter
// indices kept by strategy II. unscaled_condition: also fill condition_unscaled of initial and
// reduced (a report's figure; 0 when false: calibration does not need it).
MinimalSet selectMinimalSet(const Eigen::MatrixXd& J, const std::vector<int>& columns,
                            const std::vector<bool>& setup, const std::vector<int>& preferred,
                            bool unscaled_condition = true);

// Convenience: the whole analysis on a machine model at the given poses.
MinimalSet minimalSetForModel(const MachineModel& m, const std::vector<JointVector>& poses,
                              const std::vector<int>& columns, const std::vector<int>& preferred);

// What an identified parameter stands for. A minimal-complete set keeps one parameter of each
// confounded group; the data then show the kept one with the removed ones folded in:
//   value(kept k) = own value + sum_j a_kj value(removed j),
// with a_kj from the least-squares fit of each removed column on the kept columns (and the
// set-up columns, which the ball positions replace), in parameter units (mm/mm, rad/rad, or
// mm/rad for a lever arm). Only terms whose share of the removed column exceeds min_share
// (|a_kj| |J_k| / |J_j|) are listed, largest first.
struct AbsorbedTerm {
  int parameter = -1;      // the removed parameter
  double coefficient = 0;  // a_kj
  double share = 0;
};
std::vector<std::vector<AbsorbedTerm>> absorbedParameters(const MachineModel& m,
                                                          const std::vector<JointVector>& poses,
                                                          const std::vector<int>& kept,
                                                          const std::vector<int>& removed,
                                                          double min_share = 0.05);

// Joint configurations drawn uniformly inside travel (deterministic for a seed).
std::vector<JointVector> randomPoses(const MachineModel& m, int count, unsigned seed);

}  // namespace tolver
