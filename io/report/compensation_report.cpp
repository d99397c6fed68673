#include "io/report/compensation_report.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "io/common/io_error.h"
#include "io/common/json_text.h"
#include "io/common/text_util.h"
#include "io/report/png_plot.h"

namespace tolver {
namespace {

nlohmann::json figures(const PathFigures& f) {
  return {{"tip_max_um", f.tip_max_um},
          {"tip_rms_um", f.tip_rms_um},
          {"tip_max_line", f.tip_max_line},
          {"axis_max_urad", f.axis_max_urad},
          {"axis_rms_urad", f.axis_rms_urad}};
}

}  // namespace

std::string compensatedJointsCsvHeader(const std::vector<std::string>& axis_names,
                                       const std::vector<bool>& rotary) {
  std::string out = "index,line,status";
  for (const char* when : {"_before", "_after"})
    for (size_t a = 0; a < axis_names.size(); ++a) {
      std::string n = axis_names[a];
      for (char& c : n) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      out += "," + n + (rotary[a] ? "_deg" : "_mm") + when;
    }
  return out + ",tip_after_um,axis_after_urad\n";
}

void writeCompensatedJointsRow(TextOut& out, size_t index, int line, std::string_view status,
                               const double* before, const double* after, size_t axes,
                               double tip_after_um, double axis_after_urad) {
  LineBuilder row;
  row.integer(static_cast<long long>(index)).character(',').integer(line).character(',');
  row.text(status);
  for (const double* q : {before, after})
    for (size_t a = 0; a < axes; ++a) row.character(',').fixed(q[a], 9);
  row.character(',').fixed(tip_after_um, 6).character(',').fixed(axis_after_urad, 6);
  row.character('\n');
  out += row.view();
}

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
  if (!r.joints_file.empty()) j["joints_file"] = r.joints_file;
  if (r.after_band95_max_um >= 0)
    j["after_uncertainty"] = {{"band95_max_um", r.after_band95_max_um},
                              {"band95_median_um", r.after_band95_median_um},
                              {"axis_band95_max_urad", r.after_axis_band95_max_urad},
                              {"axis_band95_median_urad", r.after_axis_band95_median_urad},
                              {"radii",
                               "95 % of the tip's distance (3-D) and of the tool "
                               "axis's angle (2-D)"},
                              {"tip_lack_of_fit_um", r.after_lack_of_fit_um},
                              {"axis_spindle_tilt_prior_urad", r.after_tilt_prior_urad},
                              {"meaning",
                               "the after is zero only to within the calibration's "
                               "uncertainty: compensation removes what the model "
                               "knows, not what it does not"}};
  if (!r.setup_note.empty()) j["setup"] = r.setup_note;
  if (!r.process.empty()) j["process"] = {{"file", r.process}, {"compensated", r.process_applied}};
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

namespace {

// A missing file embeds as an empty image.
std::string embedded(const std::string& path, const std::string& alt) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return htmlPng(ss.str(), alt);
}

std::string row(const char* what, const PathFigures& f) {
  char buf[400];
  std::snprintf(
      buf, sizeof buf,
      "<tr><td>%s</td><td>%.4f</td><td>%d</td><td>%.4f</td><td>%.3f</td><td>%.3f</td></tr>\n", what,
      f.tip_max_um, f.tip_max_line, f.tip_rms_um, f.axis_max_urad, f.axis_rms_urad);
  return buf;
}

}  // namespace

void writeCompensationReport(const std::string& dir, const CompensationReport& r,
                             const std::vector<int>& line, const std::vector<double>& tip_before_um,
                             const std::vector<double>& tip_after_um,
                             const std::vector<double>& axis_before_urad,
                             const std::vector<double>& axis_after_urad) {
  namespace fs = std::filesystem;
  std::vector<std::string> images;
  auto chart = [&](const char* name, const char* title, const char* y_label,
                   const std::vector<double>& before, const std::vector<double>& after) {
    ScatterChart c;
    c.title = title;
    c.x_label = "program line";
    c.y_label = y_label;
    ScatterSeries b, a;
    b.legend = "before";
    b.rgb[0] = 210, b.rgb[1] = 60, b.rgb[2] = 40;
    a.legend = "after (the written program)";
    a.radius = 2;
    for (size_t i = 0; i < line.size(); ++i) {
      b.x.push_back(line[i]);
      b.y.push_back(before[i]);
      a.x.push_back(line[i]);
      a.y.push_back(after[i]);
    }
    c.series = {b, a};
    const std::string path = (fs::path(dir) / name).string();
    writeScatterPng(path, c);
    images.push_back(embedded(path, title));
  };
  chart("tip_deviation.png", "Tool-tip deviation along the program", "tip deviation (µm)",
        tip_before_um, tip_after_um);
  chart("tool_axis.png", "Tool-axis error along the program", "tool-axis error (µrad)",
        axis_before_urad, axis_after_urad);
  std::string h =
      "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>tolver compensate</title>"
      "<style>body{font-family:sans-serif;margin:2em}table{border-collapse:collapse}"
      "td,th{border:1px solid #999;padding:3px 8px;text-align:right}</style></head><body>\n";
  h += "<h1>tolver compensate</h1>\n<p>machine " + xmlEscape(r.machine) + "<br>program " +
       xmlEscape(r.program) + " (" + xmlEscape(r.dialect) + "), " + std::to_string(r.points) +
       " tool positions<br>written " + xmlEscape(r.output) + "</p>\n";
  if (!r.setup_note.empty()) h += "<p>set-up: " + xmlEscape(r.setup_note) + "</p>\n";
  if (!r.process.empty())
    h += "<p>process (" + xmlEscape(r.process) + "): " + xmlEscape(r.process_applied) + "</p>\n";
  h += "<table><tr><th></th><th>tip max (µm)</th><th>at line</th><th>tip RMS (µm)</th><th>axis max "
       "(µrad)</th>"
       "<th>axis RMS (µrad)</th></tr>\n";
  h += row("before", r.before) +
       row("after (the written program, read back and predicted)", r.after);
  h += row(("after, the " + std::to_string(r.compensated_points) + " points compensated").c_str(),
           r.after_compensated);
  h += "</table>\n";
  if (r.after_band95_max_um >= 0) {
    char buf[300];
    std::snprintf(
        buf, sizeof buf,
        "<p>The after is zero only to within the calibration's uncertainty: 95 %% band median %.3f "
        "µm, max %.3f µm. Compensation removes what the model knows, not what it does not.</p>\n",
        r.after_band95_median_um, r.after_band95_max_um);
    h += buf;
  }
  for (const std::string& img : images) h += "<figure>" + img + "</figure>\n";
  h += "<h2>Joint corrections (largest)</h2><table>";
  for (size_t k = 0; k < r.joint_correction_max.size(); ++k) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "<tr><td>%s</td><td>%.3f %s</td></tr>",
                  xmlEscape(r.joint_correction_max[k].first).c_str(),
                  r.joint_correction_max[k].second, r.joint_rotary[k] ? "µrad" : "µm");
    h += buf;
  }
  h += "</table>\n<h2>Segments</h2><table><tr><th>lines</th><th>points</th><th>before max (µm)</th>"
       "<th>after max (µm)</th></tr>\n";
  for (const SegmentFigures& sg : r.segments) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "<tr><td>%d-%d</td><td>%d</td><td>%.3f</td><td>%.4f</td></tr>\n",
                  sg.first_line, sg.last_line, sg.points, sg.before.tip_max_um,
                  sg.after.tip_max_um);
    h += buf;
  }
  h += "</table>\n<h2>Left as programmed</h2><ul>";
  h += "<li>" + std::to_string(r.out_of_travel) +
       " points whose compensating joints leave travel</li>";
  h += "<li>" + std::to_string(r.ill_conditioned) +
       " points near a singular pose (tool axis left as programmed)</li>";
  for (const std::string& n : r.notes) h += "<li>" + xmlEscape(n) + "</li>";
  h += "</ul></body></html>\n";
  OutputSet out;
  out.add((fs::path(dir) / "report.json").string(), formatCompensationJson(r));
  out.add((fs::path(dir) / "report.html").string(), h);
  out.commit();
}

}  // namespace tolver
