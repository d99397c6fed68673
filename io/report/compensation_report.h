#pragma once
// The JSON report of `tolver compensate`: the predicted tool-path error before and after, along
// the program and per segment (a run of cutting moves between rapids), the joint corrections,
// the points left uncompensated and why. Lengths in um, angles in urad, joint corrections in um
// (prismatic) and urad (rotary).
#include <string>
#include <string_view>
#include <vector>

#include "io/common/io_error.h"

namespace tolver {

struct PathFigures {
  double tip_max_um = 0, tip_rms_um = 0, axis_max_urad = 0, axis_rms_urad = 0;
  int tip_max_line = 0;
};

struct SegmentFigures {
  int first_line = 0, last_line = 0, points = 0;
  PathFigures before, after;
};

struct CompensationReport {
  std::string machine, program, dialect, output;
  int points = 0;
  PathFigures before, after;      // after: predicted on the written file, read back
  PathFigures after_compensated;  // the same over the points the file compensates
  int compensated_points = 0;
  // The model's 95 % radii of the after (calibrated machine): the tip's distance and the tool
  // axis's angle, and what they hold beyond the calibration's covariance: its lack of fit (per
  // tip coordinate) and the spindle tilt's stated prior (0: none stated, the axis band leaves
  // the tilt out).
  double after_band95_max_um = -1;
  double after_band95_median_um = -1;
  double after_axis_band95_max_urad = -1;
  double after_axis_band95_median_urad = -1;
  double after_lack_of_fit_um = 0, after_tilt_prior_urad = 0;
  std::string joints_file;  // the per-point joints (CSV), before and after
  std::string setup_note;   // the set-up the machine's share is taken after
  // --process: the process file and what of it the program compensates (in words); the before
  // and after are then measured against where the process needs the tool.
  std::string process, process_applied;
  std::vector<std::pair<std::string, double>> joint_correction_max;  // axis, um or urad
  std::vector<bool> joint_rotary;
  int ill_conditioned = 0, out_of_travel = 0, not_converged = 0, left_by_writer = 0;
  std::vector<int> ill_conditioned_lines, out_of_travel_lines;
  std::vector<SegmentFigures> segments;
  std::vector<std::string> notes;
};

std::string formatCompensationJson(const CompensationReport& r);

// The joints of every point (CSV), written a row at a time: index, line, status (compensated,
// ill_conditioned, out_of_travel, not_converged, kept: left as written), then <axis>_before and
// <axis>_after per machine axis (mm or deg, machine-file convention) and the after's tip and
// axis error (um, urad): the header line, then one row per point (before, after: one value per
// axis).
std::string compensatedJointsCsvHeader(const std::vector<std::string>& axis_names,
                                       const std::vector<bool>& rotary);
void writeCompensatedJointsRow(TextOut& out, size_t index, int line, std::string_view status,
                               const double* before, const double* after, size_t axes,
                               double tip_after_um, double axis_after_urad);

// The report directory: report.json, report.html (the figures, the segments, the notes) and the
// charts tip_deviation.png and tool_axis.png (before and after along the program, one scale),
// embedded in the HTML. Per point: the source line, tip deviation (um) and axis error (urad)
// before and after. Throws InputError when it cannot render or write.
void writeCompensationReport(const std::string& dir, const CompensationReport& r,
                             const std::vector<int>& line, const std::vector<double>& tip_before_um,
                             const std::vector<double>& tip_after_um,
                             const std::vector<double>& axis_before_urad,
                             const std::vector<double>& axis_after_urad);

// A linear axis's compensation table (CSV): '#' header lines (the grid, the reference, the sign
// convention), then position_<axis>_mm and one correction column per prismatic axis, um.
std::string formatAxisTableCsv(const std::vector<std::string>& axis_names, int axis,
                               const std::vector<double>& position,
                               const std::vector<std::vector<double>>& correction_um,
                               const std::vector<std::string>& header);

}  // namespace tolver
