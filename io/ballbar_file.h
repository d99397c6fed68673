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

#include "core/ballbar.h"
#include "core/machine_model.h"

namespace tolver {

struct BallbarFile {
  BallbarTest test;
  std::vector<std::string> warnings;
  bool has_directions = false;
};

// Throws InputError naming file, line and column on a bad row.
BallbarFile readBallbarFile(const std::string& path, const MachineModel& model, bool require_length);
BallbarFile parseBallbarCsv(const std::string& text, const std::string& file_name,
                            const MachineModel& model, bool require_length);

// with_length: write length_mm (readings) or not (a plan). comments: lines written after "# ".
std::string formatBallbarCsv(const MachineModel& model, const BallbarTest& test, bool with_length,
                             const std::vector<std::string>& comments);

}  // namespace tolver
