#pragma once
// The per-point table of a prediction (CSV). Columns:
//   index, line, rapid,
//   nominal_x_mm, nominal_y_mm, nominal_z_mm, nominal_i, nominal_j, nominal_k,
//   <axis>_mm | <axis>_deg for each machine axis (joint values, machine-file convention),
//   predicted_x_mm, predicted_y_mm, predicted_z_mm, predicted_i, predicted_j, predicted_k,
//   dev_x_um, dev_y_um, dev_z_um (deviation in the part frame), dev_um (its length),
//   along_axis_um (component along the nominal tool axis), across_axis_um (normal to it),
//   axis_angle_urad (angle between nominal and predicted tool axes), singular (0/1);
// with the identification's uncertainty (a calibrated machine):
//   u_tip_um (1 sigma of the predicted tip, worst direction), u_along_axis_um (along the tool
//   axis), u_axis_urad (1 sigma of the tool axis), outside_calibrated (0/1: a joint beyond the
//   ranges the calibration readings covered), cov_xx_um2, cov_xy_um2, cov_xz_um2, cov_yy_um2,
//   cov_yz_um2, cov_zz_um2 (the tip's covariance in the part frame: the 95 % band along a unit
//   direction n is 1.96 sqrt(n^T C n))
#include <string>
#include <vector>

#include "core/path/prediction_uncertainty.h"
#include "core/path/tool_path_prediction.h"
#include "io/common/io_error.h"

namespace tolver {

std::string formatPointTable(const MachineModel& model, const std::vector<ClPoint>& nominal,
                             const PredictedPoints& predicted,
                             const std::vector<PoseUncertainty>* uncertainty = nullptr);
// The same, written in pieces (into a file as it is made).
void writePointTable(TextOut& out, const MachineModel& model, const std::vector<ClPoint>& nominal,
                     const PredictedPoints& predicted,
                     const std::vector<PoseUncertainty>* uncertainty = nullptr);
// The same in parts, for a program predicted in blocks: the header line, then each block's rows
// (first_index: the index of the block's first point in the program).
void writePointTableHeader(TextOut& out, const MachineModel& model, bool uncertainty);
void writePointTableRows(TextOut& out, const MachineModel& model,
                         const std::vector<ClPoint>& nominal, const PredictedPoints& predicted,
                         const std::vector<PoseUncertainty>* uncertainty, size_t first_index);

}  // namespace tolver
