#pragma once
// Probed points (CSV): the set-up a shop measures, for predict and verify (--probed).
// '#' lines are comments; the first other line names the columns:
//   part_x_mm, part_y_mm, part_z_mm   the probe tip's nominal point in the part frame w (the
//                                     touched surface point offset by the stylus radius)
//   <axis>_mm / <axis>_deg            the joint values the control recorded at the touch, one
//                                     per machine axis, lower case, machine-file convention
//   part_nx, part_ny, part_nz         (optional) the probing direction in w: only the
//                                     coordinate along it is measured; absent: a full point
//   probe_length_mm                   (optional) probe tip below the gauge point; default the
//                                     set-up's gauge length
//   tram_x_urad, tram_y_urad          (optional) a spindle tram instead of a touch: the x and y
//                                     components of the unit tool axis in the table frame at
//                                     the row's joints (a test indicator swept over the table);
//                                     the row's part point, direction and length stay empty
#include <string>
#include <vector>

#include "core/model/machine_model.h"
#include "core/path/probed_setup.h"

namespace tolver {

std::vector<ProbedPoint> parseProbeCsv(const std::string& text, const std::string& file,
                                       const MachineModel& model);
std::vector<ProbedPoint> readProbeFile(const std::string& path, const MachineModel& model);
// The CSV text of points (full points when n_w is zero), as parseProbeCsv reads it.
std::string formatProbeCsv(const MachineModel& model, const std::vector<ProbedPoint>& points);

}  // namespace tolver
