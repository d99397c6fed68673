#include "io/report/allocation_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "io/common/io_error.h"
#include "io/common/json_text.h"
#include "io/common/text_util.h"
#include "io/machine/tolerance_file.h"
#include "io/report/png_plot.h"

namespace tolver {

double displayValue(const MachineModel& m, const ToleranceTerm& t, double v) {
  return m.parameters[t.parameter].angular ? v * 1e3 : v;
}
const char* displayUnit(const MachineModel& m, const ToleranceTerm& t) {
  return m.parameters[t.parameter].angular ? "mm/m" : "mm";
}

namespace {

// The figures every file of the report shows.
struct AllocationView {
  const MachineModel& m;
  const std::vector<ToleranceTerm>& terms;
  const AllocationModel& a;
  const AllocationResult& r;
  const AllocationReportInputs& in;
  const AllocationSolution* chosen;  // null when no allocation meets the limits
};

// allocation.csv: the Table 4 of this machine.
void writeAllocationCsv(const AllocationView& v, const std::string& dir) {
  const MachineModel& m = v.m;
  const std::vector<ToleranceTerm>& terms = v.terms;
  const AllocationSolution* chosen = v.chosen;
  std::string table = "term,parameter,category,unit,standard,optimised,lower,upper,reference\n";
  for (size_t i = 0; i < terms.size(); ++i) {
    const ToleranceTerm& t = terms[i];
    table += csvField(t.name) + "," + csvField(m.parameters[t.parameter].iso_code) + "," +
             categoryName(t.category) + "," + displayUnit(m, t) + "," +
             formatWith("%.6g", displayValue(m, t, t.standard)) + "," +
             (chosen ? formatWith("%.6g", displayValue(m, t, chosen->T[i])) : "") + "," +
             formatWith("%.6g", displayValue(m, t, t.lower)) + "," +
             formatWith("%.6g", displayValue(m, t, t.upper)) + "," +
             (std::isnan(t.reference) ? "" : formatWith("%.6g", displayValue(m, t, t.reference))) +
             "\n";
  }
  writeFileAtomically(dir + "/allocation.csv", table);
}

// pareto.csv: the front, one solution a row.
void writeParetoCsv(const AllocationView& v, const std::string& dir) {
  const MachineModel& m = v.m;
  const std::vector<ToleranceTerm>& terms = v.terms;
  const AllocationResult& r = v.r;
  std::string front = "m1,m2,cost,loss,worst_dx_mm,worst_dy_mm,worst_dz_mm,chosen";
  for (const auto& t : terms) front += "," + csvField(t.name);
  front += "\n";
  for (size_t k = 0; k < r.front.size(); ++k) {
    const auto& s = r.front[k];
    front += formatWith("%.8g", s.m1) + "," + formatWith("%.8g", s.m2) + "," +
             formatWith("%.8g", s.cost) + "," + formatWith("%.8g", s.loss) + "," +
             formatWith("%.6f", s.worst_exact[0]) + "," + formatWith("%.6f", s.worst_exact[1]) +
             "," + formatWith("%.6f", s.worst_exact[2]) + "," +
             (static_cast<int>(k) == r.chosen ? "1" : "0");
    for (size_t i = 0; i < terms.size(); ++i)
      front += "," + formatWith("%.6g", displayValue(m, terms[i], s.T[i]));
    front += "\n";
  }
  writeFileAtomically(dir + "/pareto.csv", front);
}

// pareto.png: M1 (x) against M2 (y); the standard in grey, the chosen point in red, the published
// allocation in orange when the tolerance file gives every term's.
void writeParetoPng(const AllocationView& v, const std::string& dir) {
  const MachineModel& m = v.m;
  const std::vector<ToleranceTerm>& terms = v.terms;
  const AllocationModel& a = v.a;
  const AllocationResult& r = v.r;
  const AllocationSolution* chosen = v.chosen;
  ScatterSeries all, std_pt, ch;
  for (const auto& s : r.front) {
    all.x.push_back(s.m1);
    all.y.push_back(s.m2);
  }
  std_pt.x = {r.standard.m1};
  std_pt.y = {r.standard.m2};
  std_pt.rgb[0] = std_pt.rgb[1] = std_pt.rgb[2] = 150;
  std_pt.radius = 5;
  if (chosen) {
    ch.x = {chosen->m1};
    ch.y = {chosen->m2};
  }
  ch.rgb[0] = 220;
  ch.rgb[1] = 30;
  ch.rgb[2] = 30;
  ch.radius = 6;
  all.legend = "Pareto front";
  std_pt.legend = "standard tolerances";
  ch.legend = "chosen";
  // The published allocation, where the tolerance file gives one for every term, in this model.
  ScatterSeries pub;
  {
    Eigen::VectorXd Tref(terms.size());
    bool complete = !terms.empty();
    for (size_t i = 0; i < terms.size(); ++i) {
      Tref[static_cast<Eigen::Index>(i)] = terms[i].reference;
      complete = complete && !std::isnan(terms[i].reference);
    }
    if (complete && r.correlation.group.size() == terms.size()) {
      pub.x = {manufacturingCost(m, terms, Tref, a) + qualityLoss(m, terms, Tref, a)};
      pub.y = {spreadObjective(terms, r.correlation, Tref)};
      pub.rgb[0] = 240, pub.rgb[1] = 150, pub.rgb[2] = 0;
      pub.radius = 6;
      pub.legend = "published";
    }
  }
  ScatterChart chart;
  chart.title = "Cost and quality loss against spread (NSGA-II front)";
  chart.x_label = "M1: manufacturing cost + quality loss (minimised)";
  chart.y_label = "M2: spread within correlation groups (maximised)";
  chart.series = {all, std_pt, ch, pub};
  writeScatterPng(dir + "/pareto.png", chart);
}

// report.json.
std::string allocationJson(const AllocationView& v) {
  const MachineModel& m = v.m;
  const std::vector<ToleranceTerm>& terms = v.terms;
  const AllocationModel& a = v.a;
  const AllocationResult& r = v.r;
  const AllocationReportInputs& in = v.in;
  const AllocationSolution* chosen = v.chosen;
  using nlohmann::json;
  json j;
  j["machine_file"] = in.machine_file;
  j["tolerance_file"] = in.tolerance_file;
  j["gauge_length_mm"] = in.gauge_length;
  j["workspace_poses"] = in.poses;
  j["limits_mm"] = {a.limits[0], a.limits[1], a.limits[2]};
  j["combination"] = a.rss ? "root-sum-square" : "worst case over the error signs";
  j["cost_model"] = {{"h_p", a.h_p},
                     {"h_a", a.h_a},
                     {"h_d", a.h_d},
                     {"r", a.r},
                     {"units", "t = T/2 in mm for lengths and mm/m for angles"}};
  j["quality_loss"] = {
      {"weight", a.loss_weight},
      {"distribution", a.loss_normal ? "normal, t = 3 sigma" : "uniform in [-t, t]"}};
  j["optimiser"] = {{"algorithm", "NSGA-II (pagmo)"},
                    {"population", in.options.population},
                    {"generations", in.options.generations},
                    {"seed", in.options.seed},
                    {"constraint_handling", r.constraint_handling},
                    {"compromise_rule",
                     "the front point closest to the ideal point (least M1, "
                     "largest M2), both objectives normalised over the front"}};
  j["standard"] = {
      {"cost", r.standard.cost},
      {"loss", r.standard.loss},
      {"m1", r.standard.m1},
      {"m2", r.standard.m2},
      {"worst_mm",
       {r.standard.worst_exact[0], r.standard.worst_exact[1], r.standard.worst_exact[2]}},
      {"feasible", r.standard_feasible}};
  json groups = json::array();
  for (const auto& g : r.correlation.members) {
    json names = json::array();
    for (int i : g) names.push_back(terms[i].name);
    groups.push_back(names);
  }
  j["correlation_groups"] = groups;
  json ref_groups = json::object();
  for (const auto& t : terms)
    if (t.reference_group > 0) ref_groups[std::to_string(t.reference_group)].push_back(t.name);
  if (!ref_groups.empty()) j["reference_groups"] = ref_groups;
  j["pareto_front_size"] = r.front.size();
  if (chosen) {
    j["chosen"] = {
        {"cost", chosen->cost},
        {"loss", chosen->loss},
        {"m1", chosen->m1},
        {"m2", chosen->m2},
        {"worst_mm", {chosen->worst_exact[0], chosen->worst_exact[1], chosen->worst_exact[2]}},
        {"cost_saving_percent", 100.0 * (1.0 - chosen->cost / r.standard.cost)}};
    json t = json::array();
    for (size_t i = 0; i < terms.size(); ++i)
      t.push_back({{"term", terms[i].name},
                   {"unit", displayUnit(m, terms[i])},
                   {"standard", displayValue(m, terms[i], terms[i].standard)},
                   {"optimised", displayValue(m, terms[i], chosen->T[i])}});
    j["terms"] = t;
  } else {
    j["chosen"] = nullptr;
    j["message"] = "no allocation within the bounds meets the limits";
  }

  return jsonText(j);
}

// report.html: the head, the inputs, the standard and the chosen allocation.
std::string htmlSummary(const AllocationView& v) {
  const MachineModel& m = v.m;
  const AllocationModel& a = v.a;
  const AllocationResult& r = v.r;
  const AllocationReportInputs& in = v.in;
  const AllocationSolution* chosen = v.chosen;
  std::string h =
      "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>tolver allocation</title>"
      "<style>body{font-family:sans-serif;max-width:60em;margin:2em auto}"
      "table{border-collapse:collapse}td,th{border:1px solid #bbb;padding:2px 8px;text-align:right}"
      "th{background:#eee}.bad{color:#b00}.ok{color:#070}</style></head><body>";
  h += "<h1>Tolerance allocation: " + m.name + "</h1>";
  h += "<p>Machine file <code>" + in.machine_file + "</code>, tolerances <code>" +
       in.tolerance_file + "</code>, tool gauge length " + formatWith("%.1f", in.gauge_length) +
       " mm, " + std::to_string(in.poses) + " workspace poses, errors combined by " +
       (a.rss ? "root-sum-square" : "worst case over their signs") +
       ". Limits |dx|, |dy|, |dz| &le; " + formatWith("%.4f", a.limits[0]) + ", " +
       formatWith("%.4f", a.limits[1]) + ", " + formatWith("%.4f", a.limits[2]) + " mm.</p>";
  auto worst = [&](const Eigen::Vector3d& w) {
    std::string s;
    for (int d = 0; d < 3; ++d)
      s += std::string("<span class=\"") + (w[d] <= a.limits[d] ? "ok" : "bad") + "\">" +
           formatWith("%.4f", w[d]) + "</span> ";
    return s;
  };
  h += "<p>Standard tolerances: cost " + formatWith("%.5g", r.standard.cost) + ", worst errors " +
       worst(r.standard.worst_exact) + "mm" +
       (r.standard_feasible ? "" : " &mdash; <b class=\"bad\">they break the limits</b>") + ".</p>";
  if (chosen)
    h += "<p>Chosen allocation: cost " + formatWith("%.5g", chosen->cost) + " (" +
         formatWith("%+.1f", -100.0 * (1.0 - chosen->cost / r.standard.cost)) +
         " % against the standard), worst errors " + worst(chosen->worst_exact) +
         "mm, checked with the nonlinear model.</p>";
  else
    h += "<p class=\"bad\">No allocation within the bounds meets the limits: loosen the limits or "
         "allow tighter tolerances (lower bounds).</p>";
  return h;
}

// The Pareto front (the PNG embedded).
std::string htmlFront(const std::string& dir) {
  std::string h;
  h += "<h2>Pareto front</h2><p>M1 = cost + quality loss (x, minimised) against M2 (y, maximised); "
       "grey: the standard tolerances, red: the chosen compromise, orange: the published "
       "allocation (when the tolerance file gives it).</p>";
  h += "<img alt=\"Pareto front\" src=\"data:image/png;base64," +
       base64Encode(readFile(dir + "/pareto.png")) + "\">";
  return h;
}

// The tolerances, like the paper's Table 4.
std::string htmlTolerances(const AllocationView& v) {
  const MachineModel& m = v.m;
  const std::vector<ToleranceTerm>& terms = v.terms;
  const AllocationSolution* chosen = v.chosen;
  std::string h;
  h += "<h2>Tolerances (like the paper's Table "
       "4)</h2><table><tr><th>term</th><th>category</th><th>unit</th><th>standard</"
       "th><th>optimised</th><th>paper</th></tr>";
  for (size_t i = 0; i < terms.size(); ++i) {
    const auto& t = terms[i];
    h += "<tr><td>" + t.name + "</td><td>" + categoryName(t.category) + "</td><td>" +
         displayUnit(m, t) + "</td><td>" + formatWith("%.5g", displayValue(m, t, t.standard)) +
         "</td><td>" + (chosen ? formatWith("%.5g", displayValue(m, t, chosen->T[i])) : "") +
         "</td><td>" +
         (std::isnan(t.reference) ? "" : formatWith("%.5g", displayValue(m, t, t.reference))) +
         "</td></tr>";
  }
  h += "</table>";
  return h;
}

// The comparison with the published allocation, when the tolerance file gives one.
std::string htmlComparison(const AllocationView& v) {
  const MachineModel& m = v.m;
  const std::vector<ToleranceTerm>& terms = v.terms;
  const AllocationModel& a = v.a;
  std::string h;
  bool has_reference = false;
  for (const auto& t : terms) has_reference |= !std::isnan(t.reference);
  if (has_reference) {
    Eigen::VectorXd Tref(terms.size());
    bool complete = true;
    for (size_t i = 0; i < terms.size(); ++i) {
      Tref[i] = terms[i].reference;
      complete &= !std::isnan(Tref[i]);
    }
    h += "<h2>Comparison with the published allocation</h2><p>";
    if (complete) {
      h += "The published values (column <i>paper</i>) cost " +
           formatWith("%.5g", manufacturingCost(m, terms, Tref, a)) + " in this cost model";
    }
    h += ". Differences come from how the accuracy is evaluated: here the tool-tip error is taken "
         "over the whole working volume and rotary ranges with this machine file's travel and "
         "tool length, the error values stacked " +
         std::string(a.rss ? "root-sum-square" : "in the worst case over their signs") +
         ", with the exact model's lever arms. Under such stacking even the standard tolerances "
         "can exceed the limits, and the allocation must then tighten rather than loosen. Some "
         "published optima lie below their own lower bound (for example the A-axis turning error) "
         "or change their reference length between columns; they are shown as printed, converted "
         "to mm/m.</p>";
  }
  return h;
}

// The correlation groups, and the published classes.
std::string htmlGroups(const AllocationView& v) {
  const std::vector<ToleranceTerm>& terms = v.terms;
  const AllocationResult& r = v.r;
  std::string h;
  h += "<h2>Correlation groups</h2><ol>";
  for (const auto& g : r.correlation.members) {
    h += "<li>";
    for (int i : g) h += terms[i].name + " ";
    h += "</li>";
  }
  h += "</ol>";
  int max_ref = 0;
  for (const auto& t : terms) max_ref = std::max(max_ref, t.reference_group);
  if (max_ref > 0) {
    h += "<p>Published classes:</p><ol>";
    for (int g = 1; g <= max_ref; ++g) {
      h += "<li>";
      for (const auto& t : terms)
        if (t.reference_group == g) h += t.name + " ";
      h += "</li>";
    }
    h += "</ol>";
  }
  return h;
}

// The method, with this run's constants.
std::string htmlMethod(const AllocationView& v) {
  const AllocationModel& a = v.a;
  const AllocationResult& r = v.r;
  std::string h;
  h += "<h2>Method</h2><p>Cost C = &Sigma; (h<sub>i</sub> t<sub>i</sub>)<sup>-r</sup> with t = T/2 "
       "in mm for lengths and mm/m for angles; h<sub>p</sub> = " +
       formatWith("%g", a.h_p) + ", h<sub>a</sub> = " + formatWith("%g", a.h_a) +
       ", h<sub>d</sub> = " + formatWith("%g", a.h_d) + ", r = " + formatWith("%g", a.r) +
       ". Quality loss: the signal-to-noise ratio &eta;<sub>i</sub> = &minus;10 log<sub>10</sub> "
       "E[y<sub>i</sub><sup>2</sup>] "
       "with the error value y<sub>i</sub> " +
       std::string(a.loss_normal ? "normal with t = 3&sigma; (E = t&sup2;/9)"
                                 : "uniform in &plusmn;t (E = t&sup2;/3)") +
       ", weights &lambda;<sub>i</sub> = (1/&eta;<sub>i</sub>)/&Sigma;(1/&eta;<sub>j</sub>), L = " +
       formatWith("%g", a.loss_weight) +
       " &Sigma; &lambda;<sub>i</sub> t<sub>i</sub><sup>2</sup>. M1 = C + L is minimised and M2 "
       "(the tolerance "
       "spread over the correlation groups) maximised by NSGA-II; the chosen compromise is the "
       "front "
       "point closest to the ideal point, both objectives normalised over the front. " +
       r.constraint_handling + ".</p></body></html>\n";
  return h;
}

}  // namespace

// The report's files in the order they are written: allocation.csv, pareto.csv, pareto.png,
// report.json, report.html (one section after another).
void writeAllocationReport(const std::string& dir, const MachineModel& m,
                           const std::vector<ToleranceTerm>& terms, const AllocationModel& a,
                           const AllocationResult& r, const AllocationReportInputs& in) {
  const AllocationView v{m, terms, a, r, in, r.chosen >= 0 ? &r.front[r.chosen] : nullptr};
  writeAllocationCsv(v, dir);
  writeParetoCsv(v, dir);
  writeParetoPng(v, dir);
  writeFileAtomically(dir + "/report.json", allocationJson(v));
  writeFileAtomically(dir + "/report.html", htmlSummary(v) + htmlFront(dir) + htmlTolerances(v) +
                                                htmlComparison(v) + htmlGroups(v) + htmlMethod(v));
}

}  // namespace tolver
