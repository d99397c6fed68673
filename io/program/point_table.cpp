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
  char buf[512];
  LineBuilder line;  // the line's numbers as printf's %.Nf writes them (io/common/text_util.h)
  auto put = [&](double v, int decimals) { line.character(',').fixed(v, decimals); };
  for (size_t i = 0; i < nominal.size(); ++i) {
    const ClPoint& c = nominal[i];
    const PredictedPoint& p = predicted[i];
    line.clear();
    line.integer(static_cast<long long>(i)).character(',').integer(c.line).character(',');
    line.integer(c.rapid ? 1 : 0);
    for (int k = 0; k < 3; ++k) put(c.p_w[k], 6);
    for (int k = 0; k < 3; ++k) put(c.u_w[k], 9);
    for (size_t a = 0; a < model.axes.size(); ++a)
      put(model.axes[a].isRotary() ? radToDeg(p.q[a]) : p.q[a], 6);
    const Eigen::Vector3d d = p.deviation_w * mmToUm(1.0);
    for (int k = 0; k < 3; ++k) put(p.p_pred_w[k], 6);
    for (int k = 0; k < 3; ++k) put(p.u_pred_w[k], 9);
    for (int k = 0; k < 3; ++k) put(d[k], 4);
    put(d.norm(), 4);
    put(mmToUm(p.along_axis), 4);
    put(mmToUm(p.across_axis), 4);
    put(radToUrad(p.axis_angle), 4);
    line.character(',').integer(p.singular ? 1 : 0);
    out += line.view();
    if (uncertainty) {
      const PoseUncertainty& u = (*uncertainty)[i];
      std::snprintf(buf, sizeof buf, ",%.4f,%.4f,%.4f,%d", mmToUm(u.tip),
                    mmToUm(PredictionUncertainty::along(u, c.u_w)), radToUrad(u.axis),
                    u.outside ? 1 : 0);
      out += buf;
      // The tip's covariance in the part frame (um^2): the band along any unit direction n is
      // 1.96 sqrt(n^T C n).
      const Eigen::Matrix3d C = u.tip_covariance_w * (mmToUm(1.0) * mmToUm(1.0));
      std::snprintf(buf, sizeof buf, ",%.6g,%.6g,%.6g,%.6g,%.6g,%.6g", C(0, 0), C(0, 1), C(0, 2),
                    C(1, 1), C(1, 2), C(2, 2));
      out += buf;
    }
    out += "\n";
  }
}

}  // namespace tolver
