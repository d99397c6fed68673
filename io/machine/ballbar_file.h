#pragma once
// Ball-bar readings and plans (CSV). Lines starting with '#' are comments; the first other line
// names the columns; rows are in measurement order. Columns, by name:
//   setup                                       integer set-up number
//   table_ball_x_mm, table_ball_y_mm, table_ball_z_mm   nominal table-ball centre in w
//   tool_ball_x_mm, tool_ball_y_mm, tool_ball_z_mm      nominal tool-ball centre in t
//   <axis>_mm or <axis>_deg                     one per machine axis, lower case (x_mm, a_deg),
//                                               joint values in the machine file's convention
//   length_mm                                   measured ball-to-ball distance (readings only)
// Optional: time_s (seconds since the test began), <axis>_dir (+1 or -1, the direction the axis
// last moved in; derived from the row before when absent). Other columns are ignored with a
// warning. A plan has the same columns without length_mm.
#include <string>
#include <vector>

#include "core/calibration/ballbar.h"
#include "core/model/machine_model.h"

namespace tolver {

struct BallbarFile {
  BallbarTest test;
  std::vector<std::string> warnings;
  bool has_directions = false;
};

// Throws InputError naming file, line and column on a bad row.
BallbarFile readBallbarFile(const std::string& path, const MachineModel& model,
                            bool require_length);
BallbarFile parseBallbarCsv(const std::string& text, const std::string& file_name,
                            const MachineModel& model, bool require_length);

// with_length: write length_mm (readings) or not (a plan). comments: lines written after "# ".
std::string formatBallbarCsv(const MachineModel& model, const BallbarTest& test, bool with_length,
                             const std::vector<std::string>& comments);

// Held-out readings: readings of the fit's set-ups that the fit does not use. Renumbers the
// held-out test's set-ups to the fit's (by set-up number). A set-up the fit lacks, other
// nominal ball positions, or a pose the fit already measured (same set-up and joints to 1e-6):
// InputError naming the held-out file and line.
void alignHeldout(BallbarTest& heldout, const BallbarTest& fit, const std::string& heldout_file,
                  const std::string& fit_file);

// Identified ball positions per set-up (CSV), written by calibrate and diagnose beside the
// machine file they identify: the two files together reproduce the fit's readings
// (simulate-ballbar --balls). Columns:
//   setup                                              set-up number, as in the readings
//   table_ball_x_mm, table_ball_y_mm, table_ball_z_mm  identified table-ball centre in w
//   tool_ball_x_mm, tool_ball_y_mm, tool_ball_z_mm     identified tool-ball centre in t
//   u_table_x_um ... u_tool_z_um                       standard uncertainties (optional)
// The identified centres absorb the machine's constant terms that a ball-bar cannot tell from
// ball positions; they are the set-up of these readings, not of a part.
std::string formatBallPositionsCsv(const BallbarTest& test, const std::vector<BallErrors>& balls,
                                   const std::vector<BallErrors>* uncertainty,
                                   const std::vector<std::string>& comments);
// The ball errors of test's set-ups (the file's centre minus the test's nominal one), matched by
// set-up number. A set-up of the test missing from the file, a set-up twice, a malformed
// number: InputError naming file, line and column.
std::vector<BallErrors> readBallPositionsFile(const std::string& path, const BallbarTest& test);
std::vector<BallErrors> parseBallPositionsCsv(const std::string& text, const std::string& file,
                                              const BallbarTest& test);

}  // namespace tolver
