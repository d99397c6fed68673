#include "io/report/verify_report.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/numerics/units.h"
#include "io/common/io_error.h"
#include "io/common/json_text.h"
#include "io/common/text_util.h"
#include "io/report/view3d.h"

namespace tolver {
namespace {

using nlohmann::json;

// mm -> um rounded to the nanometre, as the JSON writes deviations.
double umToTheNanometre(double mm) { return std::round(mm * 1e6) / 1e3; }

json stats(const DeviationStats& s) {
  return {{"samples", s.samples},
          {"min_um", umToTheNanometre(s.min)},
          {"max_um", umToTheNanometre(s.max)},
          {"mean_um", umToTheNanometre(s.mean)},
          {"rms_um", umToTheNanometre(s.rms)}};
}

std::string html(const std::string& s) { return xmlEscape(s); }

int clLine(const VerifyReport& r, int sample) {
  const int c = sample >= 0 ? r.result->cl_index[sample] : -1;
  return c >= 0 && c < static_cast<int>(r.cl_lines.size()) ? r.cl_lines[c] : 0;
}

}  // namespace

std::string verdictName(const VerifyReport& r) {
  if (r.incomplete) return "INCOMPLETE";  // set only when no region is out of tolerance
  if (r.undecided) return "UNDECIDED";    // set only when no sample is clearly out
  return r.result->pass ? "PASS" : "FAIL";
}

static bool attributable(const VerifyResult& v, int i) {
  return v.split.empty() || v.split[i] == Split::Attributable;
}

std::string worstDeviationText(const VerifyResult& v, const OutOfToleranceRegion& g, bool unit) {
  const std::string um = unit ? " um" : "";
  if (!v.total_beyond.empty() && v.total_beyond[g.worst_sample])
    return formatWith("%+.4g", mmToUm(g.worst_deviation)) + um +
           " or deeper (beyond the search range)";
  return formatWith("%+.2f", mmToUm(g.worst_deviation)) + um;
}

std::string regionCause(const VerifyReport& r, const OutOfToleranceRegion& region) {
  if (r.mode == "cl-only") return "machine";
  const int i = region.worst_sample;
  if (!r.result->split.empty() && r.result->split[i] != Split::Attributable)
    return std::string("undetermined (") + splitName(r.result->split[i]) + ")";
  const ToleranceZone& z = r.zones[region.zone];
  const double program = r.result->program[i];
  return classify(program, true, z) == Conformance::In ? "machine" : "program";
}
// What the band holds, in words (report.json's uncertainty.sources).
static std::string bandSources(const VerifyReport& r) {
  std::string s = "the calibration's covariance (tip and tool axis)";
  s += r.band_lack_of_fit_um > 0 ? "; its lack of fit, added to each tip coordinate"
                                 : "; no lack of fit (its test passed, or it had no repeats)";
  s += r.band_spindle_tilt_urad > 0
           ? "; the spindle tilt's stated prior across the tool axis"
           : "; the spindle's tilt left out (no prior stated: a ball-bar cannot see it)";
  return s;
}

std::string formatVerifyJson(const VerifyReport& r) {
  const VerifyResult& v = *r.result;
  json j;
  j["tool"] = "tolver verify";
  j["name"] = r.name;
  j["verdict"] = toLower(verdictName(r));
  if (r.incomplete) j["incomplete"] = r.incomplete_text;
  if (!r.band95_um.empty()) {
    j["uncertainty"] = {
        {"band95_max_um", r.band95_max_um},
        {"undecided_samples", r.undecided_samples},
        {"method",
         "the calibration's covariance carried to the tool's pose at the CL point whose move "
         "cut each sample, along the sample's normal at its contact on the cutter (the tip's "
         "and the tool axis's errors with the contact's lever arm), k = 1.96"},
        {"lack_of_fit_um", r.band_lack_of_fit_um},
        {"spindle_tilt_prior_urad", r.band_spindle_tilt_urad},
        {"sources", bandSources(r)}};
    if (r.undecided) j["uncertainty"]["undecided"] = r.undecided_text;
  }
  j["exit_code"] = r.exit_code;
  j["mode"] = r.mode;
  j["machine"] = {{"name", r.machine_name}, {"file", r.machine_file}};
  j["program"] = {{"file", r.program_file},
                  {"cl_points", r.cl_points},
                  {"placements", r.placements},
                  {"placement_step_mm", r.step_mm},
                  {"cutter", r.cutter}};
  j["part"] = {{"file", r.part_file},
               {"samples", r.samples->size()},
               {"sample_spacing_mm", r.spacing_mm},
               {"regions", r.samples->group_names}};
  if (!r.cad_text.empty()) j["part"]["cad"] = r.cad_text;
  if (!r.region_table.empty()) {
    nlohmann::json rows = nlohmann::json::array();
    for (const RegionSummary& g : r.region_table) {
      nlohmann::json row = {{"region", r.samples->group_names[g.group]},
                            {"area_mm2", g.area_mm2},
                            {"checked_mm2", g.checked_mm2},
                            {"out_mm2", g.out_mm2},
                            {"status", g.status}};
      if (g.group < static_cast<int>(r.samples->group_aliases.size()))
        row["aliases"] = r.samples->group_aliases[g.group];
      if (g.worst_sample >= 0) {
        row["worst_um"] = mmToUm(g.worst_mm);
        row["worst_sample"] = g.worst_sample;
      }
      rows.push_back(row);
    }
    j["part"][r.cad ? "cad_faces" : "region_table"] = rows;
  }
  if (r.has_repair) {
    const auto& m = r.repair;
    j["part"]["repair"] = {{"merged_vertices", m.merged_vertices},
                           {"degenerate_faces", m.degenerate_faces},
                           {"duplicate_faces", m.duplicate_faces},
                           {"reoriented_faces", m.reoriented_faces},
                           {"split_vertices", m.split_vertices},
                           {"holes_filled", m.holes_filled},
                           {"open_borders", m.open_borders},
                           {"closed", m.closed},
                           {"notes", m.notes}};
  }
  json zones = json::array();
  for (const auto& z : r.zones)
    zones.push_back({{"region", z.region},
                     {"spec", z.spec},
                     {"tolerance_um", umToTheNanometre(z.tolerance)},
                     {"lower_um", umToTheNanometre(z.lower)},
                     {"upper_um", umToTheNanometre(z.upper)}});
  j["zones"] = zones;
  j["sign_convention"] =
      "deviation along the outward normal of the nominal surface: + material left, - gouge";
  j["deviation"] = {
      {"total", stats(v.total_stats)},
      {"program", stats(v.program_stats)},
      {"machine", stats(v.machine_stats)},
      {"definitions",
       {{"total", "predicted swept surface - CAD (what the part will be)"},
        {"program", "nominal swept surface - CAD (the program on a perfect machine)"},
        {"machine", "predicted swept - nominal swept (the machine's contribution)"}}}};
  j["split"] = {{"beyond_search_range", v.split_beyond},
                {"cut_boundary", v.split_boundary},
                {"meaning",
                 "total = program + machine at every other machined sample; these samples "
                 "have no program and machine shares (null in the regions, empty in "
                 "deviations.csv)"}};
  j["area"] = {{"total_mm2", v.area},
               {"machined_mm2", v.area_machined},
               {"in_tolerance_mm2", v.area_in},
               {"unmachined_mm2", v.area_unmachined},
               {"edges_not_verified_mm2", v.area_edge},
               {"percent_in_tolerance", v.percent_in}};
  json regions = json::array();
  for (const auto& g : v.regions) {
    regions.push_back(
        {{"kind", conformanceName(g.kind)},
         {"zone", g.zone},
         {"region", r.zones[g.zone].region},
         {"samples", g.samples},
         {"area_mm2", g.area_mm2},
         {"worst_deviation_um", umToTheNanometre(g.worst_deviation)},
         {"worst_excursion_um", umToTheNanometre(g.worst_excursion)},
         {"where_mm", {g.where_w.x(), g.where_w.y(), g.where_w.z()}},
         {"machine_um", attributable(v, g.worst_sample)
                            ? json(umToTheNanometre(v.machine[g.worst_sample]))
                            : json()},
         {"program_um", attributable(v, g.worst_sample)
                            ? json(umToTheNanometre(v.program[g.worst_sample]))
                            : json()},
         {"beyond_search_range", !v.total_beyond.empty() && v.total_beyond[g.worst_sample] != 0},
         {"cause", regionCause(r, g)},
         {"cl_line", clLine(r, g.worst_sample)}});
  }
  j["out_of_tolerance_regions"] = regions;
  if (r.line_pass > 0) {
    json lp = json::array();
    for (const auto& p : r.line_profile)
      lp.push_back({{"cl_line",
                     p.cl_index < static_cast<int>(r.cl_lines.size()) ? r.cl_lines[p.cl_index] : 0},
                    {"arc_length_mm", p.arc_length},
                    {"total_um", umToTheNanometre(p.total)},
                    {"machine_um", umToTheNanometre(p.machine)}});
    j["line_profile"] = {{"pass", r.line_pass}, {"points", lp}};
  }
  json images = json::array();
  for (const auto& [caption, path] : r.images)
    images.push_back(
        {{"caption", caption}, {"file", std::filesystem::path(path).filename().string()}});
  j["images"] = images;
  j["notes"] = r.notes;
  j["seconds"] = std::round(r.seconds * 1000) / 1000;
  json timings = json::object();
  for (const auto& [phase, t] : r.timings) timings[phase] = std::round(t * 1000) / 1000;
  j["timings_s"] = timings;
  return jsonText(j);
}

void writeDeviationsCsv(const VerifyReport& r, TextOut& out) {
  const SurfaceSamples& s = *r.samples;
  const VerifyResult& v = *r.result;
  out +=
      "# tolver verify: signed normal deviation per surface sample, um (+ material left, - gouge); "
      "positions mm in the part frame\n"
      "# program_um and machine_um are empty where the deviation does not split (split: beyond "
      "range, "
      "cut boundary); total_um is empty where the cut reaches the gouge search limit\n"
      "sample,x,y,z,nx,ny,nz,region,zone,state,total_um,program_um,machine_um,cl_line,split";
  // On a calibrated machine, each sample's 95 % band of the machine's share (report.json's
  // uncertainty.band95_max_um is its largest).
  const bool banded = r.band95_um.size() == s.size() && !r.band95_um.empty();
  out += banded ? ",band95_um\n" : "\n";
  // One row per sample, built in place (LineBuilder: the bytes of printf's %.Nf), the regions'
  // CSV fields once.
  std::vector<std::string> region_field(s.group_names.size());
  for (size_t g = 0; g < region_field.size(); ++g) region_field[g] = csvField(s.group_names[g]);
  LineBuilder row;
  for (size_t i = 0; i < s.size(); ++i) {
    const int line = clLine(r, static_cast<int>(i));
    const bool split = attributable(v, static_cast<int>(i));
    const bool beyond = !v.total_beyond.empty() && v.total_beyond[i];
    row.clear();
    row.integer(static_cast<long long>(i));
    for (int k = 0; k < 3; ++k) row.character(',').fixed(s.p_w[i][k], 5);
    for (int k = 0; k < 3; ++k) row.character(',').fixed(s.n_w[i][k], 6);
    row.character(',').text(region_field[s.group[i]]).character(',').integer(v.zone[i]);
    row.character(',').text(conformanceName(v.conformance[i])).character(',');
    if (!beyond) row.fixed(v.machined[i] ? mmToUm(v.total[i]) : 0.0, 4);
    row.character(',');
    if (split) row.fixed(mmToUm(v.program[i]), 4);
    row.character(',');
    if (split) row.fixed(mmToUm(v.machine[i]), 4);
    row.character(',').integer(line).character(',');
    row.text(!v.machined[i] ? "" : v.split.empty() ? "split" : splitName(v.split[i]));
    if (banded) row.character(',').fixed(r.band95_um[i], 4);
    row.character('\n');
    out += row.view();
  }
}

std::string formatDeviationsCsv(const VerifyReport& r) {
  TextOut out;
  writeDeviationsCsv(r, out);
  return out.take();
}

// Long by design: the report's sections in the order the reader meets them, each a few lines.
std::string formatVerifyHtml(const VerifyReport& r) {
  const VerifyResult& v = *r.result;
  std::string h;
  h +=
      "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>tolver verify: " + html(r.name) +
      "</title>\n<style>body{font-family:sans-serif;margin:2em;max-width:1300px;color:#222}"
      "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:4px 10px;"
      "text-align:right}th{background:#eee}td.l,th.l{text-align:left}.pass{background:#2e9f43;"
      "color:#fff;padding:6px 18px;font-size:1.6em}.fail{background:#be0000;color:#fff;"
      "padding:6px 18px;font-size:1.6em}img{max-width:100%;border:1px solid #ddd;margin:6px 0}"
      ".worst{display:flex;flex-wrap:wrap;gap:12px}.card{width:400px}.thumb{width:400px}"
      "</style></head><body>\n";
  h += "<h1>tolver verify: " + html(r.name) + "</h1>\n";
  const std::string verdict = verdictName(r);
  h += std::string("<p><span class=\"") + (verdict == "PASS" ? "pass" : "fail") + "\">" + verdict +
       "</span> ";
  h += verdict == "PASS"
           ? std::string("the part is predicted in tolerance everywhere it is machined.")
       : verdict == "INCOMPLETE" ? html(r.incomplete_text)
       : verdict == "UNDECIDED"  ? html(r.undecided_text)
                                 : "the part is predicted out of tolerance in " +
                                      std::to_string(v.regions.size()) + " region(s).";
  h += "</p>\n";
  // The worst regions first, each with a thumbnail of the map that looks along its normal.
  if (!v.regions.empty()) {
    auto thumbnail = [&](size_t k) -> std::string {
      const std::string want =
          k == 0 ? "map_worst.png" : "map_region" + std::to_string(k + 1) + ".png";
      for (const auto& [caption, path] : r.images)
        if (path.size() >= want.size() &&
            path.compare(path.size() - want.size(), want.size(), want) == 0)
          return "<img class=\"thumb\" alt=\"" + html(caption) + "\" src=\"data:image/png;base64," +
                 base64Encode(readFile(path)) + "\">";
      return "";
    };
    h += "<h2>Worst regions</h2>\n<div class=\"worst\">\n";
    for (size_t k = 0; k < v.regions.size() && k < 3; ++k) {
      const auto& g = v.regions[k];
      char where[96];
      std::snprintf(where, sizeof where, "(%.2f, %.2f, %.2f)", g.where_w.x(), g.where_w.y(),
                    g.where_w.z());
      h += "<div class=\"card\">" + thumbnail(k) + "<p><b>R" + std::to_string(k + 1) + "</b> " +
           conformanceName(g.kind) + " " + worstDeviationText(v, g) + ", " +
           formatWith("%.3f", g.area_mm2) + " mm&sup2;, at " + where + " mm, CL line " +
           std::to_string(clLine(r, g.worst_sample)) + "; cause: " + regionCause(r, g) +
           "</p></div>\n";
    }
    h += "</div>\n";
  }
  h += view3dSection(r);
  h += "<h2>Figures</h2>\n<table>\n";
  auto row = [&](const std::string& k, const std::string& val) {
    h += "<tr><th class=\"l\">" + html(k) + "</th><td class=\"l\">" + html(val) + "</td></tr>\n";
  };
  row("machine", r.machine_name + " (" + r.machine_file + ")");
  row("program", r.program_file + ": " + std::to_string(r.cl_points) + " CL points, " +
                     std::to_string(r.placements) + " tool placements (step " +
                     formatWith("%.3g", r.step_mm) + " mm)");
  row("cutter", r.cutter);
  row("part", r.mode == "cl-only" ? "none: CL-only mode (surfaces through the CL points)"
                                  : r.part_file + ": " + std::to_string(r.samples->size()) +
                                        " samples at " + formatWith("%.3g", r.spacing_mm) + " mm");
  for (const auto& z : r.zones)
    row("zone " + z.region, z.spec + " mm: [" + formatWith("%+.1f", mmToUm(z.lower)) + ", " +
                                formatWith("%+.1f", mmToUm(z.upper)) + "] um");
  row("sign convention", "along the outward normal: + material left, - gouge");
  h +=
      "</table>\n<h2>Deviations (um)</h2>\n<table><tr><th class=\"l\"></th><th>min</th><th>max</th>"
      "<th>mean</th><th>RMS</th><th class=\"l\">what it is</th></tr>\n";
  auto srow = [&](const char* name, const DeviationStats& s, const char* what) {
    h += std::string("<tr><th class=\"l\">") + name + "</th><td>" +
         formatWith("%+.2f", mmToUm(s.min)) + "</td><td>" + formatWith("%+.2f", mmToUm(s.max)) +
         "</td><td>" + formatWith("%+.2f", mmToUm(s.mean)) + "</td><td>" +
         formatWith("%.2f", mmToUm(s.rms)) + "</td><td class=\"l\">" + what + "</td></tr>\n";
  };
  srow("total", v.total_stats, "predicted swept surface - CAD: what the part will be");
  if (r.mode != "cl-only")
    srow("program", v.program_stats, "nominal swept - CAD: the program on a perfect machine");
  srow("machine", v.machine_stats, "predicted swept - nominal swept: the machine's contribution");
  h += "</table>\n<p>Machined area " + formatWith("%.1f", v.area_machined) + " mm&sup2;, " +
       formatWith("%.2f", v.percent_in) + " % of it in tolerance; not machined by this program " +
       formatWith("%.1f", v.area_unmachined) + " mm&sup2; (grey in the maps).</p>\n";
  if (!v.regions.empty()) {
    h += "<h2>Out-of-tolerance regions</h2>\n<table><tr><th>#</th><th class=\"l\">kind</th>"
         "<th class=\"l\">zone</th><th>area mm&sup2;</th><th>worst um</th><th>beyond limit um</th>"
         "<th>machine um</th><th>program um</th><th class=\"l\">cause</th><th class=\"l\">where "
         "(mm)</th>"
         "<th>CL line</th></tr>\n";
    for (size_t k = 0; k < v.regions.size() && k < 50; ++k) {
      const auto& g = v.regions[k];
      char where[96];
      std::snprintf(where, sizeof where, "(%.2f, %.2f, %.2f)", g.where_w.x(), g.where_w.y(),
                    g.where_w.z());
      h += "<tr><td>" + std::to_string(k + 1) + "</td><td class=\"l\">" + conformanceName(g.kind) +
           "</td><td class=\"l\">" + html(r.zones[g.zone].region) + "</td><td>" +
           formatWith("%.3f", g.area_mm2) + "</td><td>" + worstDeviationText(v, g, false) +
           "</td><td>" + formatWith("%.2f", mmToUm(g.worst_excursion)) + "</td><td>" +
           (attributable(v, g.worst_sample) ? formatWith("%+.2f", mmToUm(v.machine[g.worst_sample]))
                                            : std::string("&mdash;")) +
           "</td><td>" +
           (attributable(v, g.worst_sample) ? formatWith("%+.2f", mmToUm(v.program[g.worst_sample]))
                                            : std::string("&mdash;")) +
           "</td><td class=\"l\">" + regionCause(r, g) + "</td><td class=\"l\">" + where +
           "</td><td>" + std::to_string(clLine(r, g.worst_sample)) + "</td></tr>\n";
    }
    if (v.regions.size() > 50)
      h += "<tr><td colspan=\"11\" class=\"l\">... " + std::to_string(v.regions.size() - 50) +
           " more in report.json</td></tr>\n";
    h += "</table>\n<p>cause: <i>program</i> when the program on a perfect machine is already out "
         "of the zone there (scallop, gouge, step), <i>machine</i> when the machine's errors take "
         "it out.</p>\n";
  }
  if (r.region_table.size() > 1) {
    // Out first, then by the worst deviation's size; each row anchored by its region's name.
    std::vector<const RegionSummary*> rows;
    for (const RegionSummary& g : r.region_table) rows.push_back(&g);
    std::stable_sort(rows.begin(), rows.end(), [](const RegionSummary* a, const RegionSummary* b) {
      if ((a->out > 0) != (b->out > 0)) return a->out > 0;
      return std::abs(a->worst_mm) > std::abs(b->worst_mm);
    });
    h += std::string("<h2>") + (r.cad ? "CAD faces" : "Regions") +
         "</h2>\n<table><tr><th class=\"l\">region</th><th class=\"l\">name, colour</th>"
         "<th>area (mm2)</th><th>checked (mm2)</th><th>worst (um)</th><th>out (mm2)</th>"
         "<th class=\"l\">status</th>" +
         (r.view_mesh ? "<th>view</th>" : "") + "</tr>\n";
    for (size_t k = 0; k < rows.size() && k < 200; ++k) {
      const RegionSummary& g = *rows[k];
      const std::string& name = r.samples->group_names[g.group];
      std::string aliases;
      if (g.group < static_cast<int>(r.samples->group_aliases.size()))
        for (const std::string& a : r.samples->group_aliases[g.group])
          aliases += (aliases.empty() ? "" : ", ") + a;
      char cells[200];
      std::snprintf(cells, sizeof cells, "<td>%.1f</td><td>%.1f</td><td>%s</td><td>%.2f</td>",
                    g.area_mm2, g.checked_mm2,
                    g.worst_sample >= 0 ? formatWith("%+.2f", mmToUm(g.worst_mm)).c_str() : "",
                    g.out_mm2);
      // An HTML id holds no space: "face #213" is "region-face-213". The last cell shows the
      // face in the 3D view.
      const std::string show = r.view_mesh ? "<td><a href=\"#view3d\" data-face=\"" +
                                                 std::to_string(g.group) + "\">3D</a></td>"
                                           : std::string();
      h += "<tr id=\"region-" + html(regionHtmlId(name)) + "\"><td class=\"l\">" + html(name) +
           "</td><td class=\"l\">" + html(aliases) + "</td>" + cells + "<td class=\"l\">" +
           g.status + "</td>" + show + "</tr>\n";
    }
    if (rows.size() > 200)
      h += "<tr><td colspan=\"7\" class=\"l\">... " + std::to_string(rows.size() - 200) +
           " more in report.json</td></tr>\n";
    h += "</table>\n";
  }
  if (!r.cad_text.empty()) h += "<p>" + html(r.cad_text) + "</p>\n";
  if (r.has_repair && !r.repair.notes.empty()) {
    h += "<h2>Part mesh</h2>\n<ul>\n";
    for (const auto& n : r.repair.notes) h += "<li>" + html(n) + "</li>\n";
    h += "</ul>\n";
  }
  if (!r.notes.empty()) {
    h += "<h2>Notes</h2>\n<ul>\n";
    for (const auto& n : r.notes) h += "<li>" + html(n) + "</li>\n";
    h += "</ul>\n";
  }
  for (const auto& [caption, path] : r.images) {
    h += "<h3>" + html(caption) + "</h3>\n<img alt=\"" + html(caption) +
         "\" src=\"data:image/png;base64," + base64Encode(readFile(path)) + "\">\n";
  }
  h += "<p style=\"color:#777\">tolver verify, " + formatWith("%.2f", r.seconds) +
       " s</p>\n</body></html>\n";
  return h;
}

}  // namespace tolver
