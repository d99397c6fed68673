#pragma once
// Identification of a machine's errors from ball-bar readings ([AM01] 3.7, 4.9, eq. 43-44 and
// 80-81): iterative Gauss-Newton with the SVD pseudo-inverse of the column-scaled
// identification Jacobian, until the scaled step falls below a tolerance.
//
// Unknowns: the chosen machine parameters (normally the minimal-complete set without the part
// and tool set-up parameters) and, per set-up, the position errors of the table ball (in w) and
// of the tool ball (in t). Parameters the data cannot see (a rank-deficient identification
// Jacobian) are named and held at their prior values; the rest are identified.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/calibration/ballbar.h"
#include "core/calibration/identifiability.h"
#include "core/model/machine_model.h"

namespace tolver {

struct CalibrationOptions {
  int max_iterations = 30;
  // Converged when the step, in column-scaled units (each unknown times its column norm, mm),
  // is below step_tolerance, or below floor_tolerance and no longer shrinking (rounding
  // level).
  double step_tolerance = 1e-12;
  double floor_tolerance = 1e-8;
  // Also converged when the step changes the readings by less than this fraction of the
  // residual no step can remove (noisy data: further steps only chase rounding).
  double relative_tolerance = 1e-6;
  bool strict = false;  // refuse (status Unobservable) instead of holding unobservable parameters
  // A prior towards zero for each machine parameter (regularisation where the data are weak):
  // the standard deviation of a linear (mm) and of an angular (rad) coefficient on a machine of
  // its accuracy class; 0: none. The fit then minimises
  //   |r - J d|^2 / s^2 + sum_k (value_k / sigma_k)^2,   s = prior_noise (mm),
  // and the covariance is s^2 (J^T J + s^2 diag(1/sigma_k^2))^-1.
  double prior_linear = 0.0, prior_angular = 0.0;
  double prior_noise = 0.5e-3;
  // Solve each Gauss-Newton step by the normal equations when the column-scaled Jacobian is well
  // conditioned (see calibrate); false: always by Householder QR (slower, for comparison).
  bool normal_equations = true;
};

enum class CalibrationStatus { Converged, NotConverged, Unobservable, NoData };

struct CalibrationResult {
  CalibrationStatus status = CalibrationStatus::NoData;
  std::string message;
  Eigen::VectorXd params;               // the full parameter vector, identified values set
  std::vector<int> identified;          // parameter indices identified
  std::vector<int> held;                // parameter indices the data cannot see, held at prior
  Eigen::VectorXd uncertainty;          // standard uncertainty per identified parameter
  Eigen::MatrixXd covariance;           // of the identified parameters: s^2 (J^T J)^-1 (mm, rad)
  Eigen::VectorXd observability;        // per identified parameter, in (0, 1]: 1 = independent
  std::vector<BallErrors> ball_errors;  // per set-up
  std::vector<BallErrors> ball_uncertainty;
  Eigen::VectorXd residuals;                      // measured - model, mm, per reading
  double rms_residual = 0.0, max_residual = 0.0;  // mm
  double residual_sigma = 0.0;                    // s = sqrt(rss / (m - n)), mm
  int rank = 0;
  double condition = 0.0;  // column-scaled
  int iterations = 0;      // Gauss-Newton steps taken
  int unknowns = 0;
};

// prior: the starting parameter vector (values of parameters not identified stay as they are).
// unknown_params: parameter indices to identify.
CalibrationResult calibrate(const MachineModel& model, const Eigen::VectorXd& prior,
                            const BallbarTest& test, const std::vector<int>& unknown_params,
                            const CalibrationOptions& options = {});

// Gross readings: readings inconsistent with the rest of a fit. A reading's studentised
// residual t_i = r_i / (s sqrt(1 - h_ii)), h_ii its leverage (the diagonal of the hat matrix of
// the column-scaled identification Jacobian at the solution, rank-truncated as in the fit), is
// gross when its two-sided normal tail, Bonferroni-multiplied by the number of readings, is
// below alpha. Sorted by |t|, largest first.
struct GrossReading {
  int index = 0;          // into the test's readings
  double residual = 0.0;  // mm
  double studentized = 0.0;
};
std::vector<GrossReading> grossReadings(const MachineModel& model, const BallbarTest& test,
                                        const CalibrationResult& fit, double alpha = 0.01);

// A calibration that removes gross readings one at a time (the largest, then a refit) until
// none is left, at most max_fraction of the readings; the fit with every reading is kept for
// the report.
struct RobustCalibration {
  CalibrationResult with_all;  // every reading
  CalibrationResult fit;       // without the removed ones (= with_all when none)
  BallbarTest test;            // the readings of `fit`
  // Index into the original test; residual: the reading's deviation from the final fit (mm),
  // studentized: that over the final fit's residual sigma.
  std::vector<GrossReading> removed;
  bool limit_reached = false;  // more readings were gross than max_fraction allows
};
RobustCalibration calibrateWithoutGross(const MachineModel& model, const Eigen::VectorXd& prior,
                                        const BallbarTest& test,
                                        const std::vector<int>& unknown_params,
                                        const CalibrationOptions& options = {}, double alpha = 0.01,
                                        double max_fraction = 0.05);

// The scale of the prior (regularisation) chosen by the readings themselves (empirical Bayes):
// with each machine parameter ~ N(0, (k sigma_unit)^2) (sigma_unit = unit_linear mm or
// unit_angular rad) and the ball positions free, the readings projected off the ball columns are
// Gaussian with covariance s^2 I + k^2 A D A^T (A the projected machine columns, D the unit
// variances, s the fit's residual sigma); the k of largest marginal likelihood over a log grid
// from 0.03 to 100 is returned. Linearised at the unregularised fit `fit`.
double choosePriorScale(const MachineModel& model, const BallbarTest& test,
                        const CalibrationResult& fit, double unit_linear, double unit_angular);
// The grid search behind it: the k of largest log N(y; 0, s2 I + k^2 A diag(d) A^T) over the
// same grid, from one thin SVD of A diag(d)^(1/2) (linear in the readings).
double evidenceScale(const Eigen::MatrixXd& A, const Eigen::VectorXd& d, const Eigen::VectorXd& y,
                     double s2);
// The evidence over the whole grid, and what not knowing k costs. The regularised fit takes the
// k of largest evidence, and its covariance is that of the parameters given k; but k is itself
// uncertain (a few readings decide it), and where the readings are weak (the cubic terms that
// carry a prediction beyond the calibrated ranges) the covariance scales with k. With a flat
// prior on log k over the grid, the posterior of the whitened parameters phi = D^(-1/2) theta is
// a mixture over k of Gaussians that share V's basis (B = A D^(1/2) = U S V^T):
//   given k:  precision S_j^2 / s^2 + 1 / k^2,  mean S_j c_j / s^2 / precision  (c = U^T y),
// so the mixture's second moment about the chosen k's mean is, in V's basis,
//   M = sum_k w_k [diag(1 / prec(k)) + (mean(k) - mean(k*)) (mean(k) - mean(k*))^T],
// w_k proportional to the evidence. inflation() returns T = D^(1/2) V L P*^(1/2) V^T D^(-1/2)
// (L L^T = M, P* = diag(prec(k*))): T Sigma T^T is the chosen k's covariance widened to the
// mixture's (much where k decides a value, not at all where the readings do).
struct PriorScaleEvidence {
  double k = 1.0;  // the grid's k of largest evidence
  std::vector<double> grid_k, log_evidence;
  Eigen::VectorXd d_root, S2, c;  // D^(1/2), S^2, U^T y
  Eigen::MatrixXd V;
  double s2 = 0.0;
  Eigen::MatrixXd inflation() const;
};
PriorScaleEvidence priorScaleEvidence(const Eigen::MatrixXd& A, const Eigen::VectorXd& d,
                                      const Eigen::VectorXd& y, double s2);
PriorScaleEvidence priorScaleEvidence(const MachineModel& model, const BallbarTest& test,
                                      const CalibrationResult& fit, double unit_linear,
                                      double unit_angular);

// The prior's units of `calibrate --prior auto`: 1 um per linear and 3.3 urad per angular
// coefficient (a 1 um straightness over 300 mm), scaled together by choosePriorScale.
constexpr double kPriorUnitLinear = 1e-3, kPriorUnitAngular = 3.3e-6;
// `options` with the prior chosen by the readings' evidence after the unregularised fit
// `free_fit` (the refit with them is the regularised calibration); *scale: the k chosen.
// *evidence (when given): the grid behind the choice, for marginalisePriorScale.
CalibrationOptions evidencePrior(const MachineModel& model, const BallbarTest& test,
                                 const CalibrationResult& free_fit, CalibrationOptions options,
                                 double* scale = nullptr, PriorScaleEvidence* evidence = nullptr);
// The regularised fit's covariance widened by the prior scale's uncertainty
// (PriorScaleEvidence::inflation), when it identifies the free fit's parameters (the evidence's
// order); its per-parameter uncertainties follow. Returns false (the fit unchanged) otherwise.
bool marginalisePriorScale(const PriorScaleEvidence& evidence,
                           const std::vector<int>& free_identified, CalibrationResult* fit);

// The identification uncertainty of a fit for a machine file: the covariance of the identified
// parameters and the joint ranges the readings covered.
IdentificationUncertainty identificationUncertainty(const CalibrationResult& fit,
                                                    const BallbarTest& test, int axes);

// The machine parameters a ball-bar calibration identifies by default: the minimal-complete set
// of the motion model (strategies I-III with the model's preferred list) without the part and
// tool set-up parameters, found at `poses` random configurations.
std::vector<int> defaultCalibrationUnknowns(const MachineModel& model, int poses = 600,
                                            unsigned seed = 1);

// What each of `unknowns` stands for (see absorbedParameters): the motion-model parameters left
// out of the minimal-complete set folded into it, at the same poses as
// defaultCalibrationUnknowns. One list per unknown, in its order.
std::vector<std::vector<AbsorbedTerm>> calibrationAbsorbed(const MachineModel& model,
                                                           const std::vector<int>& unknowns,
                                                           int poses = 600, unsigned seed = 1);

}  // namespace tolver
