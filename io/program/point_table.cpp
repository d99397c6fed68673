#include "io/program/point_table.h"

#include <cctype>
#include <cmath>
#include <cstdio>

#include "core/numerics/units.h"
#include "io/common/text_util.h"

namespace tolver {

std::string formatPointTable(const MachineModel& model, const std::vector<ClPoint>& nominal,
                             const PredictedPoints& predicted,
                             const std::vector<PoseUncertainty>* uncertainty) {
  TextOut out;
  writePointTable(out, model, nominal, predicted, uncertainty);
  return out.take();
}

void writePointTable(TextOut& out, const MachineModel& model, const std::vector<ClPoint>& nominal,
                     const PredictedPoints& predicted,
                     const std::vector<PoseUncertainty>* uncertainty) {
  writePointTableHeader(out, model, uncertainty != nullptr);
  writePointTableRows(out, model, nominal, predicted, uncertainty, 0);
}

void writePointTableHeader(TextOut& out, const MachineModel& model, bool uncertainty) {
  out += "index,line,rapid,nominal_x_mm,nominal_y_mm,nominal_z_mm,nominal_i,nominal_j,nominal_k";
  for (const Axis& ax : model.axes) {
    std::string n = ax.name;
    for (char& c : n) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    out += "," + n + (ax.isRotary() ? "_deg" : "_mm");
  }
  out +=
      ",predicted_x_mm,predicted_y_mm,predicted_z_mm,predicted_i,predicted_j,predicted_k,"
      "dev_x_um,dev_y_um,dev_z_um,dev_um,along_axis_um,across_axis_um,axis_angle_urad,singular";
  out += uncertainty ? ",u_tip_um,u_along_axis_um,u_axis_urad,outside_calibrated,"
                       "cov_xx_um2,cov_xy_um2,cov_xz_um2,cov_yy_um2,cov_yz_um2,cov_zz_um2\n"
                     : "\n";
}

void writePointTableRows(TextOut& out, const MachineModel& model,
                         const std::vector<ClPoint>& nominal, const PredictedPoints& predicted,
                         const std::vector<PoseUncertainty>* uncertainty, size_t first_index) {
  LineBuilder line;  // the line's numbers as printf's %.Nf writes them (io/common/text_util.h)
  auto put = [&](double v, int decimals) { line.character(',').fixed(v, decimals); };
  const int axes = static_cast<int>(model.axes.size());
  using F = PredictedPoints;
  // The arrays of the prediction, read in place (a point assembled as a value would allocate
  // its joint vector).
  const double* tip[3] = {predicted.field(F::kTipX), predicted.field(F::kTipY),
                          predicted.field(F::kTipZ)};
  const double* axis[3] = {predicted.field(F::kAxisX), predicted.field(F::kAxisY),
                           predicted.field(F::kAxisZ)};
  const double* dev[3] = {predicted.field(F::kDevX), predicted.field(F::kDevY),
                          predicted.field(F::kDevZ)};
  const double *along = predicted.field(F::kAlong), *across = predicted.field(F::kAcross),
               *angle = predicted.field(F::kAngle);
  const unsigned char* singular = predicted.singular();
  for (size_t i = 0; i < nominal.size(); ++i) {
    const ClPoint& c = nominal[i];
    line.clear();
    line.integer(static_cast<long long>(first_index + i)).character(',').integer(c.line);
    line.character(',').integer(c.rapid ? 1 : 0);
    for (int k = 0; k < 3; ++k) put(c.p_w[k], 6);
    for (int k = 0; k < 3; ++k) put(c.u_w[k], 9);
    for (int a = 0; a < axes && a < predicted.axes(); ++a) {
      const double q = predicted.q(a)[i];
      put(model.axes[a].isRotary() ? radToDeg(q) : q, 6);
    }
    const Eigen::Vector3d d = Eigen::Vector3d(dev[0][i], dev[1][i], dev[2][i]) * mmToUm(1.0);
    for (int k = 0; k < 3; ++k) put(tip[k][i], 6);
    for (int k = 0; k < 3; ++k) put(axis[k][i], 9);
    for (int k = 0; k < 3; ++k) put(d[k], 4);
    put(d.norm(), 4);
    put(mmToUm(along[i]), 4);
    put(mmToUm(across[i]), 4);
    put(radToUrad(angle[i]), 4);
    line.character(',').integer(singular[i] ? 1 : 0);
    if (uncertainty) {
      const PoseUncertainty& u = (*uncertainty)[i];
      put(mmToUm(u.tip), 4);
      put(mmToUm(PredictionUncertainty::along(u, c.u_w)), 4);
      put(radToUrad(u.axis), 4);
      line.character(',').integer(u.outside ? 1 : 0);
      // The tip's covariance in the part frame (um^2): the band along any unit direction n is
      // 1.96 sqrt(n^T C n).
      const Eigen::Matrix3d C = u.tip_covariance_w * (mmToUm(1.0) * mmToUm(1.0));
      for (const double v : {C(0, 0), C(0, 1), C(0, 2), C(1, 1), C(1, 2), C(2, 2)})
        line.character(',').general(v, 6);
    }
    line.character('\n');
    out += line.view();
  }
}

}  // namespace tolver
