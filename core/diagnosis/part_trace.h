#pragma once
// Tracing a machined part's residual: measured normal deviations (a CMM's, or the machine's probe)
// minus the predicted ones, explained by candidate effects the prediction lacks, each a few
// parameters whose effect on the normal deviation at a measured point is linear to first order:
//
//   set-up        the part's pose on the table off by t, w (the part sat at p + t + w x p):
//                 the path seen from the part moves the other way, -n . (t + w x p); values
//                 reported at the part's origin
//   cutter radius tool k's effective radius off by dR:           dR * s_R (its length preset to
//                 the tip: s_R = -(1 - n.a) on a ball, -|n across the axis| on a flat or
//                 bull-nose cutter, whose floor never moves)
//   tool length   tool k's length off by dL (its tip further out): -dL * (n . a)
//   tool offset   tool k's tip off by d (several tools only):      n . d
//   stock         a uniform normal offset c (stock left, deflection that the same everywhere): c
//   thermal drift the spindle growing along its axis at a constant rate g (mm/h) from the
//                 program's start, the time t_h the program's clock at the cut: -g t_h (n . a)
//   tool deflection tool k pushed off the surface by e (across its axis, away from the material)
//                 and sideways of its feed by s (along a x f, f the move's direction: climb and
//                 conventional passes take opposite signs), the engagement taken as uniform:
//                 e |n - (n.a) a| + s n . (a x f)
//   machine       calibrated parameters theta off by dtheta:        m . dtheta, m the point's row
//                 (n . (J_tip + J_rot x r)) with the calibration's covariance as their prior.
//
// Selection as diagnose's (core/diagnosis/diagnosis.h): forward, one group at a time, the group
// whose F test against the current model is strongest; it is added only when that test holds
// (p < alpha) and the held-out points' squared residuals fall by more than twice their standard
// error. Nothing is added when nothing is missing. Groups whose fit on these points is as good as
// the added one's (within 2 % of its gain) are named as confounded with it: the points cannot tell
// them apart (a set-up's z and a tool's length on a flat face, always). A group whose values fall
// outside their physical range (kPlausible below) is reported as implausible and not added, and
// the next is tried. Groups are ranked by BIC
// (m log(RSS_with / RSS_without) + q log m), so that six values must buy more than one.
#include <Eigen/Core>
#include <string>
#include <vector>

namespace tolver {

// One measured point as the prediction sees it (mm; w the part frame).
struct TracePoint {
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();      // on the nominal surface
  Eigen::Vector3d n_w = Eigen::Vector3d::UnitZ();     // outward unit normal
  Eigen::Vector3d axis_w = Eigen::Vector3d::UnitZ();  // the cutting tool's axis (tip -> spindle)
  double radius_sensitivity = -1.0;                   // s_R above
  int tool = 0;                                       // index of the tool that cut it
  double residual = 0.0;                              // measured - predicted, mm
  bool held_out = false;
  int repeat = -1;      // points measured at the same place share an index (>= 0); -1: once
  double time_h = NAN;  // the program's clock when the point was cut (h); NAN: no feed rates
  Eigen::Vector3d feed_w = Eigen::Vector3d::Zero();  // unit direction of the cutting move; 0: none
};

// The physical ranges beyond which a traced value is implausible (mm, mm/h): a spindle's thermal
// growth reaches 20-60 um in its first hour (ISO 230-3 tests), a finishing cutter deflects by
// tens of um.
struct PlausibleRange {
  double drift_mm_per_h = 0.1;
  double deflection_mm = 0.2;
};

struct TraceOptions {
  double alpha = 1e-3;
  // The calibrated machine's parameters: one row per point (points x parameters, d deviation /
  // d parameter) and their prior covariance (mm, rad); empty: no machine group.
  Eigen::MatrixXd machine_rows;
  Eigen::MatrixXd machine_covariance;
  std::vector<std::string> machine_names;
  int tools = 1;
  PlausibleRange plausible;
};

struct TraceGroup {
  std::string name;                      // "set-up", "cutter radius T2", ...
  std::vector<std::string> value_names;  // each value's name with its unit
  Eigen::VectorXd values, sd;            // fitted alone on the fit points (mm, rad)
  Eigen::MatrixXd covariance;            // of the values in the final model (added groups)
  double f = 0, p_value = 1;  // against the model before it (the last round it was tried)
  double rss_fit = 0;         // mm^2, on the fit points, the current model with it
  double heldout_gain_um2 = 0, heldout_gain_se_um2 = 0;  // mean drop of r^2 on held-out points
  bool added = false;
  std::string reason;                   // why added or not
  std::vector<std::string> confounded;  // groups these points cannot tell from it
};

struct PartTrace {
  std::vector<TraceGroup> groups;  // ranked: the added ones first in order, then by F
  std::vector<int> added;          // indices into groups, in the order added
  Eigen::VectorXd residual_after;  // per point, mm: the residual with the added effects
  int fit_points = 0, heldout_points = 0;
  double fit_rms_before = 0, fit_rms_after = 0;          // mm
  double heldout_rms_before = 0, heldout_rms_after = 0;  // mm
  double heldout_max_before = 0, heldout_max_after = 0;  // mm
  double sigma_after = 0;  // residual sigma of the final model on the fit points, mm
  // The final model against the repeatability of points measured more than once (fit points):
  // SS_pe within the repeats, F = (SS_lof / df_lof) / (SS_pe / df_pe), as the ball-bar's.
  struct LackOfFit {
    bool tested = false;
    int places = 0;  // places measured more than once
    double df_pure = 0, df_lack = 0, s_pure = 0, f = 0, p_value = 1;
    double missing_rms = 0;  // mm: sqrt(max(0, sigma_after^2 - s_pure^2))
  } lack_of_fit;
  // "effects added", "nothing added" (no candidate passes), or "unexplained" (the final model
  // fails the lack-of-fit test: it misses more than the repeatability, whatever was added).
  std::string verdict, verdict_text;
};

PartTrace tracePart(const std::vector<TracePoint>& points, const TraceOptions& options = {});

}  // namespace tolver
