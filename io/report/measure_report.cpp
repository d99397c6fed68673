#include "io/report/measure_report.h"

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

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

std::string describeTracedValues(const TraceGroup& g) {
  std::string out;
  for (Eigen::Index k = 0; k < g.values.size(); ++k) {
    const std::string& n =
        k < static_cast<Eigen::Index>(g.value_names.size()) ? g.value_names[k] : "value";
    const bool angle = n.find("rad") != std::string::npos;
    const bool rate = n.size() > 2 && n.compare(n.size() - 2, 2, "/h") == 0;
    const double v = angle ? radToUrad(g.values[k]) : mmToUm(g.values[k]);
    const double sd = angle ? radToUrad(g.sd[k]) : mmToUm(g.sd[k]);
    out += (out.empty() ? "" : " ") + n.substr(0, n.rfind(' ')) + formatWith(" %+.3g", v) +
           formatWith(" +- %.2g ", sd) + (angle ? "urad" : (rate ? "um/h" : "um")) + ";";
  }
  return out;
}

namespace {

std::string cell(const std::string& text) { return "<td>" + xmlEscape(text) + "</td>"; }
std::string number(const std::string& text) { return "<td class=\"n\">" + text + "</td>"; }
std::string cellUm(double mm) { return number(formatWith("%.2f", mmToUm(mm))); }

}  // namespace

std::string formatMeasureHtml(const MeasureReport& r, const std::string& dir) {
  const PartTrace& t = r.trace;
  std::string h =
      "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>tolver measure</title>"
      "<style>body{font-family:sans-serif;margin:2em;max-width:70em}table{border-collapse:"
      "collapse;margin:0.5em 0}td,th{border:1px solid #999;padding:3px 8px}td.n{text-align:right}"
      ".added{background:#e6f4e6}img{max-width:48%;margin:0.5%}"
      "</style></head><body>\n<h1>tolver measure</h1>\n";
  h += "<p><b>" + xmlEscape(t.verdict_text) + "</b></p>\n";
  h +=
      "<p>machine " + xmlEscape(r.machine_file) + "<br>program " + xmlEscape(r.program_file) +
      "<br>part " + xmlEscape(r.part_file) + "<br>points " + xmlEscape(r.points_file) + ": " +
      std::to_string(r.rows.size()) + " read, " + std::to_string(r.used) + " used (" +
      std::to_string(t.fit_points) + " fit, " + std::to_string(t.heldout_points) + " held out), " +
      std::to_string(r.beyond_range) + " beyond the search range, " + std::to_string(r.off_face) +
      " beyond an edge, " + std::to_string(r.unmachined) + " on faces not machined" +
      (r.process_from.empty() ? "" : "<br>process corrections held: " + xmlEscape(r.process_from)) +
      "</p>\n";
  h += "<h2>Deviation along the surface normal (µm)</h2><table><tr><th></th><th>RMS</th>"
       "<th>max</th></tr>\n<tr>" +
       cell("measured") + cellUm(r.measured_rms) + "<td></td></tr>\n<tr>" + cell("predicted") +
       cellUm(r.predicted_rms) + "<td></td></tr>\n<tr>" + cell("residual (measured - predicted)") +
       cellUm(r.residual_rms) + cellUm(r.residual_max) + "</tr></table>\n";
  h += "<h2>Before and after the effects added (µm)</h2><table><tr><th></th><th>held-out RMS</th>"
       "<th>held-out max</th><th>fit points RMS</th></tr>\n<tr>" +
       cell("before") + cellUm(t.heldout_rms_before) + cellUm(t.heldout_max_before) +
       cellUm(t.fit_rms_before) + "</tr>\n<tr>" + cell("after") + cellUm(t.heldout_rms_after) +
       cellUm(t.heldout_max_after) + cellUm(t.fit_rms_after) + "</tr></table>\n";
  const PartTrace::LackOfFit& l = t.lack_of_fit;
  h += "<p>adequacy: " +
       (l.tested ? formatWith("%.0f places measured more than once, repeatability ", l.places) +
                       formatWith("%.2f µm; ", mmToUm(l.s_pure)) +
                       formatWith("lack of fit F %.3g", l.f) + formatWith(" (%.0f", l.df_lack) +
                       formatWith(", %.0f), ", l.df_pure) + formatWith("p %.2g", l.p_value)
                 : std::string("not tested (no place measured twice)")) +
       "</p>\n";
  h += "<h2>Candidate effects</h2><table><tr><th>effect</th><th>added</th><th>values</th>"
       "<th>F</th><th>p</th><th>held-out gain (µm²)</th><th>why</th></tr>\n";
  for (const TraceGroup& g : t.groups) {
    std::string why = g.reason;
    if (!g.confounded.empty() && why.find("confounded") == std::string::npos) {
      why += "; confounded with";
      for (size_t k = 0; k < g.confounded.size(); ++k) why += (k ? ", " : " ") + g.confounded[k];
    }
    h += std::string(g.added ? "<tr class=\"added\">" : "<tr>") + cell(g.name) +
         cell(g.added ? "yes" : "no") + cell(g.added ? describeTracedValues(g) : "") +
         number(formatWith("%.3g", g.f)) + number(formatWith("%.2g", g.p_value)) +
         number(formatWith("%.3g", g.heldout_gain_um2) +
                formatWith(" ± %.2g", g.heldout_gain_se_um2)) +
         cell(why) + "</tr>\n";
  }
  h += "</table>\n";
  if (r.worst_row >= 0) {
    const MeasureRow& w = r.rows[r.worst_row];
    h += "<h2>Largest residual after</h2><p>" +
         xmlEscape(formatWith("%+.2f µm at (", mmToUm(w.residual_after)) +
                   formatWith("%.3f, ", w.p_w.x()) + formatWith("%.3f, ", w.p_w.y()) +
                   formatWith("%.3f) mm", w.p_w.z()) + ", points line " + std::to_string(w.line) +
                   (w.region.empty() ? "" : ", region " + w.region) + ", CL line " +
                   std::to_string(w.cl_line) + ", tool " + std::to_string(w.tool + 1) +
                   (w.operation.empty() ? "" : ", operation " + w.operation)) +
         "</p>\n";
  }
  h += "<h2>Corrections written (process.txt" +
       std::string(r.machine_written.empty() ? "" : ", " + r.machine_written) +
       ")</h2><table><tr><th>key</th><th>value</th><th>SD</th></tr>\n";
  for (const MeasureReport::Correction& c : r.corrections)
    h += "<tr>" + cell(c.key) + number(formatWith("%.6g", c.value)) +
         number(std::isfinite(c.sd) ? formatWith("%.3g", c.sd) : "carried over") + "</tr>\n";
  h += "</table>\n";
  if (!r.images.empty()) {
    h += "<h2>Residual maps and histograms</h2>\n<p>";
    for (const std::string& name : r.images) {
      std::ifstream in(dir + "/" + name, std::ios::binary);
      std::stringstream bytes;
      bytes << in.rdbuf();
      h += htmlPng(bytes.str(), name);
    }
    h += "</p>\n";
  }
  if (!r.notes.empty()) {
    h += "<h2>Notes</h2><ul>";
    for (const std::string& n : r.notes) h += "<li>" + xmlEscape(n) + "</li>";
    h += "</ul>\n";
  }
  h += "<p>Per point: residuals.csv; everything above: report.json.</p></body></html>\n";
  return h;
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
