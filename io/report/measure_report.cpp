#include "io/report/measure_report.h"

#include <cmath>
#include <nlohmann/json.hpp>

#include "core/numerics/units.h"
#include "io/common/text_util.h"

namespace tolver {
namespace {

std::string um(double mm) { return std::isfinite(mm) ? formatWith("%.4f", mmToUm(mm)) : ""; }
std::string mm(double v) { return formatWith("%.5f", v); }

nlohmann::json numberOrNull(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

}  // namespace

std::string formatMeasureCsv(const MeasureReport& r) {
  std::string out =
      "line,x_mm,y_mm,z_mm,foot_x_mm,foot_y_mm,foot_z_mm,nx,ny,nz,measured_um,predicted_um,"
      "program_um,machine_um,residual_um,residual_after_um,instrument_um,cl_line,tool,set,"
      "status,region,operation\n";
  for (const MeasureRow& w : r.rows) {
    std::vector<std::string> c = {std::to_string(w.line),
                                  mm(w.p_w.x()),
                                  mm(w.p_w.y()),
                                  mm(w.p_w.z()),
                                  mm(w.foot_w.x()),
                                  mm(w.foot_w.y()),
                                  mm(w.foot_w.z()),
                                  formatWith("%.6f", w.n_w.x()),
                                  formatWith("%.6f", w.n_w.y()),
                                  formatWith("%.6f", w.n_w.z()),
                                  um(w.measured),
                                  um(w.predicted),
                                  um(w.program),
                                  um(w.machine),
                                  um(w.residual),
                                  um(w.residual_after),
                                  um(w.instrument),
                                  w.cl_line > 0 ? std::to_string(w.cl_line) : "",
                                  std::to_string(w.tool + 1),
                                  w.held_out ? "held-out" : "fit",
                                  w.status,
                                  w.region,
                                  w.operation};
    out += csvLine(c) + "\n";
  }
  return out;
}

std::string formatMeasureJson(const MeasureReport& r) {
  nlohmann::json j;
  j["tool"] = "tolver measure";
  j["name"] = r.name;
  j["machine"] = r.machine_file;
  j["program"] = r.program_file;
  j["part"] = r.part_file;
  j["points"] = {{"file", r.points_file},
                 {"total", r.rows.size()},
                 {"used", r.used},
                 {"beyond_search_range", r.beyond_range},
                 {"not_machined", r.unmachined},
                 {"beyond_an_edge", r.off_face},
                 {"search_mm", r.search_mm},
                 {"heldout_every", r.heldout_every}};
  j["deviation_um"] = {{"measured_rms", mmToUm(r.measured_rms)},
                       {"predicted_rms", mmToUm(r.predicted_rms)},
                       {"residual_rms", mmToUm(r.residual_rms)},
                       {"residual_max", mmToUm(r.residual_max)}};
  const PartTrace& t = r.trace;
  j["trace"] = {{"verdict", t.verdict},
                {"verdict_text", t.verdict_text},
                {"fit_points", t.fit_points},
                {"heldout_points", t.heldout_points},
                {"before_um",
                 {{"fit_rms", mmToUm(t.fit_rms_before)},
                  {"heldout_rms", mmToUm(t.heldout_rms_before)},
                  {"heldout_max", mmToUm(t.heldout_max_before)}}},
                {"after_um",
                 {{"fit_rms", mmToUm(t.fit_rms_after)},
                  {"heldout_rms", mmToUm(t.heldout_rms_after)},
                  {"heldout_max", mmToUm(t.heldout_max_after)}}}};
  const PartTrace::LackOfFit& l = t.lack_of_fit;
  j["trace"]["lack_of_fit"] = {{"tested", l.tested},
                               {"places_repeated", l.places},
                               {"repeatability_um", mmToUm(l.s_pure)},
                               {"f", l.f},
                               {"df_lack", l.df_lack},
                               {"df_pure", l.df_pure},
                               {"p_value", l.p_value},
                               {"missing_rms_um", mmToUm(l.missing_rms)}};
  if (r.worst_row >= 0) {
    const MeasureRow& w = r.rows[r.worst_row];
    j["largest_residual_after"] = {
        {"line", w.line},          {"residual_um", mmToUm(w.residual_after)},
        {"x_mm", w.p_w.x()},       {"y_mm", w.p_w.y()},
        {"z_mm", w.p_w.z()},       {"cl_line", w.cl_line},
        {"tool", w.tool + 1},      {"region", w.region},
        {"operation", w.operation}};
  }
  nlohmann::json groups = nlohmann::json::array();
  for (const TraceGroup& g : t.groups) {
    nlohmann::json e = {{"effect", g.name},
                        {"added", g.added},
                        {"f", g.f},
                        {"p_value", g.p_value},
                        {"heldout_gain_um2", g.heldout_gain_um2},
                        {"heldout_gain_se_um2", g.heldout_gain_se_um2},
                        {"reason", g.reason},
                        {"confounded_with", g.confounded}};
    if (g.added) {
      nlohmann::json v = nlohmann::json::array();
      for (Eigen::Index k = 0; k < g.values.size(); ++k)
        v.push_back(
            {{"name", k < static_cast<Eigen::Index>(g.value_names.size()) ? g.value_names[k]
                                                                          : std::string("value")},
             {"value", numberOrNull(g.values[k])},
             {"sd", numberOrNull(g.sd[k])}});
      e["values"] = v;
    }
    groups.push_back(e);
  }
  j["trace"]["effects"] = groups;
  j["notes"] = r.notes;
  j["images"] = r.images;
  j["machine_file_written"] =
      r.machine_written.empty() ? nlohmann::json() : nlohmann::json(r.machine_written);
  return j.dump(2) + "\n";
}

std::string processKey(const std::string& group, const std::string& value_name) {
  std::string key = group + " " + value_name;
  for (char& ch : key)
    if (ch == ' ') ch = '_';
  return key;
}

std::string formatProcessFile(const MeasureReport& r) {
  std::string out = "# tolver process corrections, learned by tolver measure from " +
                    r.points_file + "\n# " + r.trace.verdict_text + "\n";
  if (!r.process_from.empty())
    out += "# the prediction already held " + r.process_from + ": its values are included\n";
  for (const MeasureReport::Correction& c : r.corrections)
    out += c.key + " " + formatWith("%.9g", c.value) +
           (std::isfinite(c.sd) ? "  # +- " + formatWith("%.3g", c.sd) : "  # carried over") + "\n";
  return out;
}

}  // namespace tolver
