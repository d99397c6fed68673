#include "io/compensation_report.h"

#include <cmath>
#include <cstdio>

#include "io/json_text.h"

namespace tolver {
namespace {

nlohmann::json figures(const PathFigures& f) {
  return {{"tip_max_um", f.tip_max_um},     {"tip_rms_um", f.tip_rms_um},
          {"tip_max_line", f.tip_max_line}, {"axis_max_urad", f.axis_max_urad},
          {"axis_rms_urad", f.axis_rms_urad}};
}

}  // namespace

std::string formatCompensationJson(const CompensationReport& r) {
  nlohmann::json j;
  j["machine"] = r.machine;
  j["program"] = r.program;
  j["dialect"] = r.dialect;
  j["output"] = r.output;
  j["points"] = r.points;
  j["before"] = figures(r.before);
  j["after"] = figures(r.after);
  j["after_compensated_points"] = figures(r.after_compensated);
  j["compensated_points"] = r.compensated_points;
  j["after_measured_on"] = "the written program, read back and predicted on the machine";
  if (r.after_band95_max_um >= 0)
    j["after_uncertainty"] = {{"band95_max_um", r.after_band95_max_um},
                              {"band95_median_um", r.after_band95_median_um},
                              {"meaning", "the after is zero only to within the calibration's "
                                          "uncertainty: compensation removes what the model "
                                          "knows, not what it does not"}};
  if (!r.setup_note.empty()) j["setup"] = r.setup_note;
  nlohmann::json jc = nlohmann::json::object();
  for (size_t k = 0; k < r.joint_correction_max.size(); ++k)
    jc[r.joint_correction_max[k].first] = {
        {r.joint_rotary[k] ? "max_urad" : "max_um", r.joint_correction_max[k].second}};
  j["joint_corrections"] = jc;
  j["uncompensated"] = {{"out_of_travel", r.out_of_travel},
                        {"out_of_travel_lines", r.out_of_travel_lines},
                        {"not_converged", r.not_converged},
                        {"left_by_the_writer", r.left_by_writer}};
  j["ill_conditioned"] = {{"points", r.ill_conditioned}, {"lines", r.ill_conditioned_lines}};
  nlohmann::json seg = nlohmann::json::array();
  for (const SegmentFigures& s : r.segments)
    seg.push_back({{"first_line", s.first_line},
                   {"last_line", s.last_line},
                   {"points", s.points},
                   {"before", figures(s.before)},
                   {"after", figures(s.after)}});
  j["segments"] = seg;
  j["notes"] = r.notes;
  return jsonText(j);
}

std::string formatAxisTableCsv(const std::vector<std::string>& axis_names, int axis,
                               const std::vector<double>& position,
                               const std::vector<std::vector<double>>& correction_um,
                               const std::vector<std::string>& header) {
  std::string out;
  for (const std::string& h : header) out += "# " + h + "\n";
  out += "position_" + axis_names[axis] + "_mm";
  for (size_t k = 0; k < axis_names.size(); ++k) out += ",d" + axis_names[k] + "_um";
  out += "\n";
  char buf[64];
  for (size_t i = 0; i < position.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%.3f", position[i]);
    out += buf;
    for (double v : correction_um[i]) {
      std::snprintf(buf, sizeof buf, ",%.4f", std::abs(v) < 5e-5 ? 0.0 : v);
      out += buf;
    }
    out += "\n";
  }
  return out;
}

}  // namespace tolver
