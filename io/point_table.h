#pragma once
// The per-point table of a prediction (CSV). Columns:
//   index, line, rapid,
//   nominal_x_mm, nominal_y_mm, nominal_z_mm, nominal_i, nominal_j, nominal_k,
//   <axis>_mm | <axis>_deg for each machine axis (joint values, machine-file convention),
//   predicted_x_mm, predicted_y_mm, predicted_z_mm, predicted_i, predicted_j, predicted_k,
//   dev_x_um, dev_y_um, dev_z_um (deviation in the part frame), dev_um (its length),
//   along_axis_um (component along the nominal tool axis), across_axis_um (normal to it),
//   axis_angle_urad (angle between nominal and predicted tool axes), singular (0/1)
#include <string>
#include <vector>

#include "core/tool_path_prediction.h"

namespace tolver {

std::string formatPointTable(const MachineModel& model, const std::vector<ClPoint>& nominal,
                             const std::vector<PredictedPoint>& predicted);

}  // namespace tolver
