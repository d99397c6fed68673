#pragma once
// Closing the loop: after a ball-bar calibration, find what the model failed to
// explain, trace it to an effect the model lacks (core/model/effects.h), add it, refit, and report
// the error before and after. Nothing is added when nothing is missing.
//
// Forward stepwise selection. Each round linearises the fit at its solution (identification
// Jacobian J of the identified unknowns, residual r) and scores every candidate effect by the
// readings' derivatives G with respect to its coefficients:
//  * fit:  the least-squares fit of r on [J G] (the candidate's columns projected off J), RSS
//          before and after;
//  * significance: an F test of the RSS reduction with the effective number of readings
//          m_eff = m (1 - rho) / (1 + rho), rho the lag-1 autocorrelation of the candidate's
//          residuals within a set-up (correlated residuals carry less information), Bonferroni
//          over the round's tests (a hyperparameter search counts its independent trials);
//  * information criterion: dIC = m_eff ln(RSS_before / RSS_after) - k ln(m_eff) (BIC with
//          m_eff; k counts the coefficients and the searched hyperparameter), positive = better;
//  * cross-validation over held-out blocks: contiguous runs of readings (each set-up cut into
//          `blocks_per_setup` runs), the model refitted without the block predicts it;
//  * identifiability: the part of the candidate's columns that the base model cannot produce
//          (smallest singular value of the projected, unit-norm columns; below
//          `min_new_information` the effect is confounded with the base model) and the condition
//          number of the column-scaled augmented Jacobian.
// The best qualifying candidate (largest dIC) is added, the augmented model refitted by
// calibrate() (nonlinear, with uncertainties), and the next round starts; a round with no
// qualifying candidate ends the selection.
#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "core/calibration/ballbar.h"
#include "core/calibration/calibration.h"
#include "core/diagnosis/residual_analysis.h"
#include "core/model/machine_model.h"

namespace tolver {

struct DiagnosisOptions {
  int blocks_per_setup = 6;  // cross-validation: contiguous runs per set-up
  double alpha = 1e-3;       // family-wise significance level of a round
  // Confounded (no new information) below this: the part of the candidate's unit columns the
  // base model cannot produce. A partly confounded effect (above it) is judged like any other,
  // by its significance and its cross-validated gain, and reported with what it is confounded
  // with.
  double min_new_information = 1e-3;
  double max_condition = 1e8;  // column-scaled, of the augmented identification Jacobian
  int max_effects = 4;
  std::vector<EffectType> types;  // candidate types; empty: every type
  // Parameters to identify in the base fit; empty: defaultCalibrationUnknowns(model).
  std::vector<int> base_unknowns;
  // Readings of the same set-ups that no fit uses (aligned to the test's set-ups); when given,
  // they judge the final model against the base one, otherwise cross-validation does.
  const BallbarTest* heldout = nullptr;
  // A time budget, s (0: none): once spent, no further round starts; the model is the one the
  // rounds done made (DiagnosisResult::budget_spent). The first round always runs.
  double max_seconds = 0.0;
};

enum class CandidateVerdict {
  Added,
  Outscored,
  NotSignificant,
  NoPredictiveGain,
  Confounded,
  NotIdentifiable,
  RefitFailed,  // the nonlinear refit with it did not converge or did not lower the residual
  Implausible,  // its fitted value lies beyond what the effect can be on a machine tool
                // (plausibleCoefficientLimit, by more than twice its uncertainty)
};
const char* verdictName(CandidateVerdict v);

struct CandidateScore {
  EffectSpec spec;    // with the hyperparameter found by search
  std::string label;  // describeEffect()
  int round = 0;      // selection round (1-based)
  int coefficients = 0;
  int trials = 1;                            // independent trials of its hyperparameter search
  double rss_before = 0.0, rss_after = 0.0;  // mm^2
  double f_statistic = 0.0;
  double p_value = 1.0;  // Bonferroni-adjusted over the round
  double effective_readings = 0.0;
  double delta_ic = 0.0;
  // mm; cv_rms_after NaN when the candidate failed an earlier test (significance, confounding),
  // so that its cross-validation could not change its verdict and was not computed.
  double cv_rms_before = 0.0, cv_rms_after = 0.0;
  double new_information = 0.0;
  double condition = 0.0;  // computed for candidates that pass the other tests
  CandidateVerdict verdict = CandidateVerdict::NotSignificant;
  std::string reason;  // why a refit rejected it
};

struct AddedEffect {
  EffectSpec spec;
  std::string label;
  std::vector<int> parameters;  // indices in the augmented model
  Eigen::VectorXd values;       // mm or rad (or mm per hour for drift)
  Eigen::VectorXd uncertainty;  // standard uncertainty, same units
  double hyperparameter = NAN;  // period (mm) or time constant (s)
  double hyperparameter_uncertainty = NAN;
  // Partial confounding: identified unknowns whose readings' derivatives resemble one of the
  // effect's (|cosine| >= 0.5), with their values in the fit before and after the effect was
  // added (parameter units, mm or rad; ball coordinates in mm). The effect's new information
  // is the part of its columns the base model cannot produce (1: independent).
  double new_information = 1.0;
  struct Confounding {
    std::string name;  // ISO code, or "ball 2 tool z"
    bool angular = false;
    double cosine = 0.0;
    double before = 0.0, after = 0.0;
  };
  std::vector<Confounding> confounded_with;
  // Other candidates the readings cannot tell from this one (their columns span the same
  // space: e.g. a rotation about x of Y, of X or of an A axis about x): equally true names.
  std::vector<std::string> equivalent;
};

// The one verdict a diagnosis gives, which everything below it in a report supports.
enum class DiagnosisVerdict {
  EffectsAdded,    // effects added, and the model then fits to the repeatability (or untested)
  NothingMissing,  // nothing added, and nothing left: no structure, no lack of fit
  Incomplete,      // something is missing that the library does not explain (lack of fit, or
                   // structure left), with or without effects added
  NothingAdded,    // effects were found but the final check withdrew them
};
const char* verdictName(DiagnosisVerdict v);

struct DiagnosisResult {
  bool ok = false;
  bool budget_spent = false;  // max_seconds ran out: rounds after rounds_done were not run
  int rounds_done = 0;
  std::string message;
  DiagnosisVerdict verdict = DiagnosisVerdict::NothingMissing;
  std::string verdict_text;  // one line: what the verdict means here, with its figures
  // Lack of fit of the base and the final fits (core/diagnosis/residual_analysis.h).
  LackOfFit lack_of_fit_before, lack_of_fit_after;
  // When the verdict is Incomplete: where the final residual is largest and what it follows
  // most (even below significance), and the measurement that would separate it.
  std::string where, suggestion;
  Machine machine;  // augmented model with the final identified values
  CalibrationResult base_fit, final_fit;
  std::vector<AddedEffect> added;
  std::vector<CandidateScore> candidates;
  double rms_before = 0.0, rms_after = 0.0;        // mm, in-sample
  double cv_rms_before = 0.0, cv_rms_after = 0.0;  // mm, cross-validated
  int folds = 0;
  // On options.heldout (readings == 0 when none): the base fit, and the final model.
  ResidualStats heldout_before, heldout_after;
  // The held-out gain: mean over the held-out readings of r_before^2 - r_after^2, and its
  // standard error (mm^2; 0 without held-out readings). A gain under twice its standard error
  // is not confirmed, and the effects are withdrawn.
  double heldout_gain_mm2 = 0, heldout_gain_se_mm2 = 0;
  // The same over the cross-validation: each reading's r_before^2 - r_after^2 predicted without
  // its fold, the mean and its standard error over the folds (mm^2). Without held-out readings
  // it decides: under twice its standard error the effects are not confirmed and withdrawn.
  double cv_gain_mm2 = 0, cv_gain_se_mm2 = 0;
  // The effects the selection added but the final check rejected (the augmented model
  // predicted worse than the base one); then `added` is empty and `machine` the base model.
  std::vector<AddedEffect> withdrawn;
  std::string withdrawn_reason;
  // Structure the library does not explain: after the selection, the residual still follows a
  // variable (the first finding of analysis_after, p < 1e-3) that no candidate removed.
  bool unexplained = false;
  ResidualFinding unexplained_finding;
  ResidualAnalysis analysis_before, analysis_after;
};

// progress(done, total): candidates scored in the current round (may be empty).
DiagnosisResult diagnose(const Machine& machine, const BallbarTest& test,
                         const DiagnosisOptions& options = {},
                         const std::function<void(int, int)>& progress = {});

// The fold of each reading: contiguous runs, blocks_per_setup per set-up.
std::vector<int> contiguousFolds(const BallbarTest& test, int blocks_per_setup, int* folds);

}  // namespace tolver
