#include "io/report/diagnosis_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/model/effects.h"
#include "core/numerics/units.h"
#include "io/common/io_error.h"
#include "io/common/json_text.h"
#include "io/common/text_util.h"
#include "io/report/png_plot.h"

namespace tolver {
namespace {

using nlohmann::json;

// JSON has no NaN or infinity: such values are written as null.
json num(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json findingsJson(const ResidualAnalysis& a) {
  json out = json::array();
  for (const ResidualFinding& f : a.findings) {
    json j = {{"variable", f.variable},
              {"test", f.test},
              {"strength", num(f.strength)},
              {"p_value", num(f.p_value)}};
    if (f.test == "periodogram") {
      // A rotary axis's period is a harmonic order, a linear axis's a length with its width.
      j["period"] = num(f.period);
      j["period_unit"] = f.order ? "harmonic order" : "mm";
      if (!f.order) j["period_uncertainty_mm"] = num(f.period_uncertainty);
    }
    out.push_back(j);
  }
  return {{"rms_um", mmToUm(a.rms)},
          {"follows", a.follows},
          {"follows_strength", num(a.follows_strength)},
          {"runs_z", num(a.runs_z)},
          {"runs_p", num(a.runs_p)},
          {"repeated_poses", a.repeats.size()},
          {"repeated_pose_max_span_um",
           mmToUm(a.repeats.empty()
                      ? 0.0
                      : std::max_element(a.repeats.begin(), a.repeats.end(),
                                         [](const RepeatedPose& x, const RepeatedPose& y) {
                                           return x.span_mm < y.span_mm;
                                         })
                            ->span_mm)},
          {"findings", out}};
}

const char* hyperName(const EffectSpec& e) { return traitsOf(e.type).hyper.name; }

json fitJson(const CalibrationResult& f) {
  return {{"status", f.message},
          {"iterations", f.iterations},
          {"unknowns", f.unknowns},
          {"rank", f.rank},
          {"condition", num(f.condition)},
          {"rms_um", mmToUm(f.rms_residual)},
          {"max_um", mmToUm(f.max_residual)},
          {"sigma_um", mmToUm(f.residual_sigma)}};
}

json summaryJson(const PredictionSummary& s) {
  return {{"points", s.points},
          {"max_um", mmToUm(s.max_deviation)},
          {"rms_um", mmToUm(s.rms_deviation)},
          {"max_point", s.max_index},
          {"max_axis_error_urad", radToUrad(s.max_axis_angle)}};
}

// The variable an effect follows, per reading, and its axis label.
std::vector<double> variableOf(const MachineModel& m, const BallbarTest& test, const EffectSpec& e,
                               std::string* label) {
  std::vector<double> v(test.readings.size());
  const bool rotary = e.axis >= 0 && m.axes[e.axis].isRotary();
  const double k = rotary ? radToDeg(1.0) : 1.0;
  const std::string axis = e.axis >= 0 ? m.axes[e.axis].name : "";
  for (size_t i = 0; i < v.size(); ++i) {
    const BallbarReading& r = test.readings[i];
    switch (e.type) {
      case EffectType::Periodic:
        v[i] = r.q[e.axis] - e.period * std::floor(r.q[e.axis] / e.period);
        break;
      case EffectType::Drift:
      case EffectType::Warmup:
        v[i] = r.context.time_s / 60.0;
        break;
      case EffectType::BarLength:
        v[i] = static_cast<double>(i);
        break;
      default:
        v[i] = r.q[e.axis] * k;
    }
  }
  switch (e.type) {
    case EffectType::Periodic:
      *label = axis + " position modulo the period (mm)";
      break;
    case EffectType::Drift:
    case EffectType::Warmup:
      *label = "time since the test began (min)";
      break;
    case EffectType::BarLength:
      *label = "reading, in measurement order (set-ups in colour)";
      break;
    default:
      *label = axis + (rotary ? " angle (deg)" : " position (mm)");
  }
  return v;
}

// Residual series coloured by approach direction (reversal) or set-up (bar length), else one.
std::vector<ScatterSeries> seriesOf(const BallbarTest& test, const EffectSpec& e,
                                    const std::vector<double>& x, const Eigen::VectorXd& r) {
  static const unsigned char colours[4][3] = {
      {40, 90, 200}, {210, 60, 40}, {40, 150, 60}, {150, 80, 170}};
  std::vector<ScatterSeries> s;
  auto groupOf = [&](size_t i) {
    if (e.type == EffectType::Reversal)
      return test.readings[i].context.direction[e.axis] < 0 ? 1 : 0;
    if (e.type == EffectType::BarLength) return test.readings[i].setup % 4;
    return 0;
  };
  for (size_t i = 0; i < x.size(); ++i) {
    const int g = groupOf(i);
    while (static_cast<int>(s.size()) <= g) {
      ScatterSeries n;
      std::copy(colours[s.size()], colours[s.size()] + 3, n.rgb);
      const int k = static_cast<int>(s.size());
      if (e.type == EffectType::Reversal) n.legend = k == 0 ? "approach +" : "approach -";
      if (e.type == EffectType::BarLength) n.legend = "set-up " + std::to_string(k + 1);
      s.push_back(n);
    }
    s[g].x.push_back(x[i]);
    s[g].y.push_back(mmToUm(r[i]));
  }
  return s;
}

// A missing file embeds as an empty image.
std::string imageTag(const std::string& path, const std::string& alt) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return htmlPng(ss.str(), alt);
}

std::string effectKey(const MachineModel& m, const EffectSpec& e) {
  std::string k = traitsOf(e.type).name;
  if (e.axis >= 0) k += "_" + m.axes[e.axis].name + "_" + kComponentNames[e.component];
  return k;
}

}  // namespace

const char* effectUnit(const EffectSpec& spec, double* scale) {
  const bool angular = spec.axis >= 0 && isAngularComponent(spec.component);
  *scale = angular ? radToUrad(1.0) : mmToUm(1.0);
  if (spec.type == EffectType::Drift) return angular ? "urad/h" : "um/h";
  return angular ? "urad" : "um";
}

// One added effect in report.json: its values and uncertainties in the effect's unit, its
// hyperparameter, orders, new information and what it is confounded with.
json addedEffectJson(const MachineModel& m, const AddedEffect& a) {
  double k = 1;
  const char* unit = effectUnit(a.spec, &k);
  json params = json::object(), unc = json::object();
  for (size_t j = 0; j < a.parameters.size(); ++j) {
    const std::string& name = m.parameters[a.parameters[j]].iso_code;
    params[name] = num(a.values[j] * k);
    unc[name] = num(a.uncertainty[j] * k);
  }
  json e = {{"type", traitsOf(a.spec.type).name},
            {"axis", a.spec.axis >= 0 ? json(m.axes[a.spec.axis].name) : json(nullptr)},
            {"component",
             a.spec.component >= 0 ? json(kComponentNames[a.spec.component]) : json(nullptr)},
            {"label", a.label},
            {"unit", unit},
            {"parameters", params},
            {"uncertainty", unc}};
  if (hyperName(a.spec))
    e["hyperparameter"] = {{"name", hyperName(a.spec)},
                           {"value", num(a.hyperparameter)},
                           {"uncertainty", num(a.hyperparameter_uncertainty)}};
  if (a.spec.type == EffectType::Chebyshev || a.spec.type == EffectType::Harmonics)
    e["orders"] = {a.spec.first_order, a.spec.last_order};
  e["new_information"] = a.new_information;
  json conf = json::array();
  for (const AddedEffect::Confounding& c : a.confounded_with) {
    const double f = c.angular ? radToUrad(1.0) : mmToUm(1.0);
    conf.push_back({{"unknown", c.name},
                    {"abs_cosine", c.cosine},
                    {"unit", c.angular ? "urad" : "um"},
                    {"before", c.before * f},
                    {"after", c.after * f}});
  }
  e["partly_confounded_with"] = conf;
  e["equivalent"] = a.equivalent;
  return e;
}

// One candidate in report.json: its scores and verdict.
json candidateJson(const MachineModel& base, const CandidateScore& c) {
  json j = {{"round", c.round},
            {"type", traitsOf(c.spec.type).name},
            {"axis", c.spec.axis >= 0 ? json(base.axes[c.spec.axis].name) : json(nullptr)},
            {"component",
             c.spec.component >= 0 ? json(kComponentNames[c.spec.component]) : json(nullptr)},
            {"label", c.label},
            {"coefficients", c.coefficients},
            {"search_trials", c.trials},
            {"rss_before_um2", num(c.rss_before * mmToUm(1.0) * mmToUm(1.0))},
            {"rss_after_um2", num(c.rss_after * mmToUm(1.0) * mmToUm(1.0))},
            {"f_statistic", num(c.f_statistic)},
            {"p_value", num(c.p_value)},
            {"effective_readings", num(c.effective_readings)},
            {"delta_ic", num(c.delta_ic)},
            {"cv_rms_before_um", num(mmToUm(c.cv_rms_before))},
            {"cv_rms_after_um", num(mmToUm(c.cv_rms_after))},
            {"new_information", num(c.new_information)},
            {"condition", c.condition > 0 ? num(c.condition) : json(nullptr)},
            {"verdict", verdictName(c.verdict)}};
  if (!c.reason.empty()) j["reason"] = c.reason;
  if (hyperName(c.spec)) j[hyperName(c.spec)] = num(hyperparameterValue(c.spec));
  return j;
}

// The JSON document's members in order.
std::string formatDiagnosisJson(const MachineModel& base, const BallbarTest& test,
                                const DiagnosisResult& r, const DiagnosisReportInputs& in) {
  const MachineModel& m = r.machine.model;
  json added = json::array();
  for (const AddedEffect& a : r.added) added.push_back(addedEffectJson(m, a));
  json cands = json::array();
  for (const CandidateScore& c : r.candidates) cands.push_back(candidateJson(base, c));
  json out = {
      {"tool", "tolver diagnose"},
      {"machine", m.name},
      {"machine_file", in.machine_file},
      {"readings_file", in.readings_file},
      {"augmented_machine_file", in.output_file},
      {"readings", test.readings.size()},
      {"setups", test.setups.size()},
      {"verdict", verdictName(r.verdict)},
      {"verdict_text", r.verdict_text},
      {"budget_spent", r.budget_spent},
      {"rounds_done", r.rounds_done},
      {"message", r.message},
      {"lack_of_fit",
       {{"before", lackOfFitJson(r.lack_of_fit_before)},
        {"after", lackOfFitJson(r.lack_of_fit_after)}}},
      {"effects_added", added},
      {"rms_before_um", mmToUm(r.rms_before)},
      {"rms_after_um", mmToUm(r.rms_after)},
      {"cv_rms_before_um", mmToUm(r.cv_rms_before)},
      {"cv_rms_after_um", mmToUm(r.cv_rms_after)},
      {"cross_validation",
       {{"folds", r.folds},
        {"blocks", "contiguous runs of readings within each set-up"},
        {"mean_squared_gain_um2", r.cv_gain_mm2 * 1e6},
        {"mean_squared_gain_standard_error_um2",
         std::isfinite(r.cv_gain_se_mm2) ? json(r.cv_gain_se_mm2 * 1e6) : json(nullptr)},
        {"gain_rule",
         "without held-out readings, confirmed when above twice its standard error over the "
         "folds; else the effects are withdrawn"}}},
      {"ball_positions_file", in.balls_file},
      {"selection",
       {{"method", "forward stepwise"},
        {"significance", "F test on m_eff = m (1 - rho)/(1 + rho), Bonferroni over the round"},
        {"information_criterion", "BIC with m_eff"}}},
      {"base_fit", fitJson(r.base_fit)},
      {"final_fit", fitJson(r.final_fit)},
      {"residual_analysis",
       {{"before", findingsJson(r.analysis_before)}, {"after", findingsJson(r.analysis_after)}}},
      {"candidates", cands},
      {"seconds", in.seconds}};
  auto stats = [](const ResidualStats& x) {
    return json{{"readings", x.readings}, {"rms_um", mmToUm(x.rms)}, {"max_um", mmToUm(x.max)}};
  };
  if (r.heldout_before.readings > 0)
    out["heldout"] = {
        {"file", in.heldout_file},
        {"before", stats(r.heldout_before)},
        {"after", stats(r.heldout_after)},
        {"mean_squared_gain_um2", r.heldout_gain_mm2 * 1e6},
        {"mean_squared_gain_standard_error_um2", r.heldout_gain_se_mm2 * 1e6},
        {"gain_rule",
         "confirmed when above twice its standard error; else the effects are withdrawn"}};
  if (in.written.fit.readings > 0) {
    out["written_files_check"] = {
        {"description", "the written machine file and ball positions, read back, on the readings"},
        {"fit", stats(in.written.fit)}};
    if (in.written.heldout.readings > 0)
      out["written_files_check"]["heldout"] = stats(in.written.heldout);
  }
  if (r.unexplained) {
    const ResidualFinding& u = r.unexplained_finding;
    out["unexplained_structure"] = {
        {"variable", u.variable},
        {"test", u.test},
        {"strength", u.strength},
        {"p_value", u.p_value},
        {"description",
         "the residual after the selection still follows this variable, and no "
         "effect of the library removes it"}};
    if (u.test == "periodogram" && u.order)
      out["unexplained_structure"]["harmonic_order"] = u.period;
    if (u.test == "periodogram" && !u.order) {
      out["unexplained_structure"]["period_mm"] = u.period;
      out["unexplained_structure"]["period_uncertainty_mm"] = u.period_uncertainty;
    }
  }
  if (!r.where.empty()) out["where"] = r.where;
  if (!r.suggestion.empty()) out["suggested_measurement"] = r.suggestion;
  if (!r.withdrawn.empty()) {
    json w = json::array();
    for (const AddedEffect& a : r.withdrawn) w.push_back(a.label);
    out["withdrawn"] = {{"effects", w}, {"reason", r.withdrawn_reason}};
  }
  json removed = json::array(), restored = json::array();
  for (const RemovedReading& g : in.removed) {
    json e = {
        {"line", g.line}, {"residual_um", mmToUm(g.residual)}, {"studentized", g.studentized}};
    if (std::isfinite(g.studentized_after))
      e["studentized_against_final_model"] = g.studentized_after;
    (g.restored ? restored : removed).push_back(e);
  }
  out["gross_readings_removed"] = removed;
  out["gross_readings_restored"] = restored;
  if (in.program) {
    const ProgramComparison& p = *in.program;
    out["program"] = {{"cl_file", p.cl_file},
                      {"before", summaryJson(p.before)},
                      {"after", summaryJson(p.after)},
                      {"change_max_um", mmToUm(p.change_max)},
                      {"change_rms_um", mmToUm(p.change_rms)},
                      {"change_max_line", p.change_max_line}};
  }
  return jsonText(out);
}

namespace {

// What every section of the HTML report reads.
struct DiagnosisView {
  const std::string& dir;  // where the plots go
  const MachineModel& base;
  const BallbarTest& test;
  const DiagnosisResult& r;
  const DiagnosisReportInputs& in;
};

// The head, the inputs and the verdict with where and what would separate it.
std::string htmlVerdict(const DiagnosisView& v) {
  const MachineModel& m = v.r.machine.model;
  const DiagnosisResult& r = v.r;
  const DiagnosisReportInputs& in = v.in;
  const BallbarTest& test = v.test;
  std::string h =
      "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>tolver diagnose: " +
      xmlEscape(m.name) +
      "</title><style>body{font-family:sans-serif;margin:2em;max-width:1400px}"
      "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}"
      "th{background:#eee}td.l,th.l{text-align:left}.pass{color:#070}.note{color:#555}"
      "figure{display:inline-block;margin:0 1em 1em 0}</style></head><body>\n";
  h += "<h1>Diagnosis of " + xmlEscape(m.name) + "</h1>\n";
  h += "<p class=\"note\">Readings: " + xmlEscape(in.readings_file) + " (" +
       std::to_string(test.readings.size()) + " in " + std::to_string(test.setups.size()) +
       " set-ups). Machine: " + xmlEscape(in.machine_file) +
       ". Augmented machine file: " + xmlEscape(in.output_file) + ".</p>\n";
  {
    std::string title = verdictName(r.verdict);
    title[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(title[0])));
    h += "<h2>" + xmlEscape(title) + "</h2>\n<p>" + xmlEscape(r.verdict_text) + "</p>\n";
    if (!r.where.empty()) h += "<p>Where: " + xmlEscape(r.where) + ".</p>\n";
    if (!r.suggestion.empty()) h += "<p>To separate it: " + xmlEscape(r.suggestion) + ".</p>\n";
  }
  return h;
}

// Residual, lack of fit, cross-validated and held-out RMS before and after; the written files.
std::string htmlBeforeAfter(const DiagnosisView& v) {
  const DiagnosisResult& r = v.r;
  const DiagnosisReportInputs& in = v.in;
  std::string h;
  h += "<table><tr><th class=\"l\"></th><th>before</th><th>after</th></tr>";
  h += "<tr><td class=\"l\">residual RMS (µm)</td><td>" + formatWith("%.3f", mmToUm(r.rms_before)) +
       "</td><td>" + formatWith("%.3f", mmToUm(r.rms_after)) + "</td></tr>";
  auto lof = [](const LackOfFit& l) {
    return l.tested ? formatWith("F %.2f", l.f) + formatWith(", p %.2g", l.p_value) +
                          formatWith(" (repeatability %.3f µm)", mmToUm(l.s_pure))
                    : std::string("not tested");
  };
  h += "<tr><td class=\"l\">lack of fit (residual against the repeatability of repeated "
       "poses)</td><td>" +
       lof(r.lack_of_fit_before) + "</td><td>" + lof(r.lack_of_fit_after) + "</td></tr>";
  h += "<tr><td class=\"l\">cross-validated RMS (µm, " + std::to_string(r.folds) +
       " contiguous blocks left out in turn)</td><td>" +
       formatWith("%.3f", mmToUm(r.cv_rms_before)) + "</td><td>" +
       formatWith("%.3f", mmToUm(r.cv_rms_after)) + "</td></tr>";
  if (std::isfinite(r.cv_gain_se_mm2))
    h += "<tr><td class=\"l\">cross-validated mean squared gain (µm², ± its standard error over "
         "the blocks; confirmed above twice it)</td><td></td><td>" +
         formatWith("%.3g", r.cv_gain_mm2 * 1e6) + formatWith(" ± %.2g", r.cv_gain_se_mm2 * 1e6) +
         "</td></tr>";
  if (r.heldout_before.readings > 0)
    h += "<tr><td class=\"l\">held-out readings RMS (µm, " +
         std::to_string(r.heldout_before.readings) + " readings of " + xmlEscape(in.heldout_file) +
         ")</td><td>" + formatWith("%.3f", mmToUm(r.heldout_before.rms)) + "</td><td>" +
         formatWith("%.3f", mmToUm(r.heldout_after.rms)) + "</td></tr>";
  if (in.written.fit.readings > 0) {
    h += "<tr><td class=\"l\">from the written files (" + xmlEscape(in.output_file) + " + " +
         xmlEscape(in.balls_file) + "), fitted readings RMS (µm)</td><td></td><td>" +
         formatWith("%.3f", mmToUm(in.written.fit.rms)) + "</td></tr>";
    if (in.written.heldout.readings > 0)
      h += "<tr><td class=\"l\">from the written files, held-out readings RMS "
           "(µm)</td><td></td><td>" +
           formatWith("%.3f", mmToUm(in.written.heldout.rms)) + "</td></tr>";
  }
  h += "</table>\n";
  return h;
}

// Effects withdrawn, and readings found gross (with t before and after, restored or not).
std::string htmlRemoved(const DiagnosisView& v) {
  const DiagnosisResult& r = v.r;
  const DiagnosisReportInputs& in = v.in;
  std::string h;
  if (!r.withdrawn.empty())
    h += "<p><b>Withdrawn:</b> " + xmlEscape(r.withdrawn_reason) + ".</p>\n";
  if (!in.removed.empty()) {
    h += "<p><b>Readings the base model found gross</b> (studentised residual against the base "
         "fit, then "
         "against the final model; restored when the final model explains them):";
    for (const RemovedReading& g : in.removed)
      h += " line " + std::to_string(g.line) + " (" + formatWith("%+.2f", mmToUm(g.residual)) +
           " µm, t " + formatWith("%.1f", g.studentized) +
           (std::isfinite(g.studentized_after) ? formatWith(" → %.1f", g.studentized_after)
                                               : std::string()) +
           (g.restored ? ", restored)" : ", removed)");
    h += ".</p>\n";
  }
  return h;
}

// The effects added, with their values and uncertainties.
std::string htmlAdded(const DiagnosisView& v) {
  const MachineModel& m = v.r.machine.model;
  const DiagnosisResult& r = v.r;
  std::string h;
  if (!r.added.empty()) {
    h += "<table><tr><th class=\"l\">effect</th><th class=\"l\">parameter</th><th>value</th>"
         "<th>standard uncertainty</th><th class=\"l\">unit</th></tr>";
    for (const AddedEffect& a : r.added) {
      double k = 1;
      const char* unit = effectUnit(a.spec, &k);
      for (size_t j = 0; j < a.parameters.size(); ++j)
        h += "<tr><td class=\"l\">" + xmlEscape(a.label) + "</td><td class=\"l\">" +
             m.parameters[a.parameters[j]].iso_code + "</td><td>" +
             formatWith("%.3f", a.values[j] * k) + "</td><td>" +
             formatWith("%.3f", a.uncertainty[j] * k) + "</td><td class=\"l\">" + unit +
             "</td></tr>";
      if (hyperName(a.spec))
        h += "<tr><td class=\"l\">" + xmlEscape(a.label) + "</td><td class=\"l\">" +
             hyperName(a.spec) + "</td><td>" + formatWith("%.4g", a.hyperparameter) + "</td><td>" +
             formatWith("%.2g", a.hyperparameter_uncertainty) + "</td><td class=\"l\">" +
             (a.spec.type == EffectType::Periodic ? "mm" : "s") + "</td></tr>";
    }
    h += "</table>\n";
  }
  return h;
}

// Residual plots against the variable each effect follows, before and after on one scale.
std::string htmlResidualPlots(const DiagnosisView& v) {
  const MachineModel& m = v.r.machine.model;
  const DiagnosisResult& r = v.r;
  const BallbarTest& test = v.test;
  const std::string& dir = v.dir;
  std::string h;
  // Residual plots against the variable each effect follows.
  std::vector<EffectSpec> shown;
  for (const AddedEffect& a : r.added) shown.push_back(a.spec);
  if (shown.empty()) {  // nothing added: the residuals in measurement order
    EffectSpec e;
    e.type = EffectType::BarLength;
    shown.push_back(e);
  }
  h += "<h2>Residuals before and after</h2>\n";
  for (const EffectSpec& e : shown) {
    std::string label;
    const std::vector<double> x = variableOf(m, test, e, &label);
    const std::string key = effectKey(m, e);
    // Before and after on one scale, so the drop reads off the axes.
    const std::vector<ScatterSeries> before = seriesOf(test, e, x, r.base_fit.residuals);
    const std::vector<ScatterSeries> after = seriesOf(test, e, x, r.final_fit.residuals);
    double y0 = 0, y1 = 0;
    sharedYRange({&before, &after}, &y0, &y1);
    for (int k = 0; k < 2; ++k) {
      const std::string name = "residual_" + key + (k ? "_after.png" : "_before.png");
      const std::string path = (std::filesystem::path(dir) / name).string();
      ScatterChart chart;
      chart.title =
          std::string(k ? "After: " : "Before: ") +
          (e.type == EffectType::BarLength && r.added.empty() ? "residuals" : describeEffect(m, e));
      chart.x_label = label;
      chart.y_label = "residual (µm)";
      chart.series = k ? after : before;
      chart.fixed_y = true;
      chart.y_min = y0;
      chart.y_max = y1;
      writeScatterPng(path, chart);
      h += "<figure>" + imageTag(path, name) + "<figcaption>residual (µm) " +
           (k ? "after" : "before") + " against " + xmlEscape(label) + " (same scale)" +
           "</figcaption></figure>\n";
    }
  }
  return h;
}

// Structure the library does not explain: the residual after, against that variable.
std::string htmlUnexplained(const DiagnosisView& v) {
  const MachineModel& m = v.r.machine.model;
  const DiagnosisResult& r = v.r;
  const BallbarTest& test = v.test;
  const std::string& dir = v.dir;
  std::string h;
  // Structure the library does not explain: the residual after, against that variable.
  if (r.unexplained) {
    const ResidualFinding& u = r.unexplained_finding;
    h += "<h2>Structure the library does not explain</h2>\n<p>After the selection the residual "
         "still follows <b>" +
         xmlEscape(u.variable) + "</b> (" + xmlEscape(u.test) +
         (u.test == "periodogram" ? (u.order ? formatWith(", harmonic order %.0f", u.period)
                                             : formatWith(", period %.2f", u.period) +
                                                   formatWith(" ± %.2f mm", u.period_uncertainty))
                                  : "") +
         ", " + formatWith("%.0f", u.strength * 100) + " % of its variance, p " +
         formatWith("%.1e", u.p_value) + "), and no effect of the library removes it.</p>\n";
    std::vector<double> x(test.readings.size());
    std::string label = "reading, in measurement order";
    int axis = -1;
    for (size_t a = 0; a < m.axes.size(); ++a)
      if (u.variable.rfind(m.axes[a].name, 0) == 0) axis = static_cast<int>(a);
    for (size_t i = 0; i < x.size(); ++i) {
      const BallbarReading& rd = test.readings[i];
      if (u.variable == "time")
        x[i] = rd.context.time_s / 60.0;
      else if (axis >= 0)
        x[i] = rd.q[axis] * (m.axes[axis].isRotary() ? radToDeg(1.0) : 1.0);
      else
        x[i] = static_cast<double>(i);
    }
    if (u.variable == "time")
      label = "time since the test began (min)";
    else if (axis >= 0)
      label = m.axes[axis].name + (m.axes[axis].isRotary() ? " angle (deg)" : " position (mm)");
    ScatterSeries one;
    one.x = x;
    for (Eigen::Index i = 0; i < r.final_fit.residuals.size(); ++i)
      one.y.push_back(mmToUm(r.final_fit.residuals[i]));
    const std::string path = (std::filesystem::path(dir) / "residual_unexplained.png").string();
    ScatterChart chart;
    chart.title = "Unexplained: residual after, against " + u.variable;
    chart.x_label = label;
    chart.y_label = "residual (µm)";
    chart.series = {one};
    writeScatterPng(path, chart);
    h += "<figure>" + imageTag(path, "residual_unexplained.png") +
         "<figcaption>residual (µm) after, against " + xmlEscape(label) +
         "</figcaption></figure>\n";
  }
  return h;
}

// The residual analysis: every variable and test, before and after.
std::string htmlResidualAnalysis(const DiagnosisView& v) {
  const DiagnosisResult& r = v.r;
  std::string h;
  // Residual analysis.
  h += "<h2>Residual analysis</h2>\n<table><tr><th class=\"l\">variable</th><th "
       "class=\"l\">test</th>"
       "<th>strength before</th><th>p before</th><th>strength after</th><th>p after</th></tr>";
  for (const ResidualFinding& f : r.analysis_before.findings) {
    const ResidualFinding* g = nullptr;
    for (const ResidualFinding& x : r.analysis_after.findings)
      if (x.variable == f.variable && x.test == f.test) g = &x;
    h += "<tr><td class=\"l\">" + xmlEscape(f.variable) + "</td><td class=\"l\">" + f.test +
         (f.test == "periodogram" ? (f.order ? formatWith(" (harmonic order %.0f)", f.period)
                                             : formatWith(" (period %.2f", f.period) +
                                                   formatWith(" +- %.2f mm)", f.period_uncertainty))
                                  : "") +
         "</td><td>" + formatWith("%.3f", f.strength) + "</td><td>" +
         formatWith("%.2g", f.p_value) + "</td><td>" + (g ? formatWith("%.3f", g->strength) : "") +
         "</td><td>" + (g ? formatWith("%.2g", g->p_value) : "") + "</td></tr>";
  }
  h += "</table>\n<p class=\"note\">Strength: fraction of the residual variance explained. The "
       "residual follows <b>" +
       xmlEscape(r.analysis_before.follows.empty() ? "nothing in particular"
                                                   : r.analysis_before.follows) +
       "</b> before, <b>" +
       xmlEscape(r.analysis_after.follows.empty() ? "nothing in particular"
                                                  : r.analysis_after.follows) +
       "</b> after.</p>\n";
  return h;
}

// The part program's predicted error before and after.
std::string htmlProgram(const DiagnosisView& v) {
  const DiagnosisReportInputs& in = v.in;
  std::string h;
  if (in.program) {
    const ProgramComparison& p = *in.program;
    h += "<h2>Predicted error of " + xmlEscape(p.cl_file) +
         "</h2>\n<table><tr><th></th><th>max (µm)</th>"
         "<th>RMS (µm)</th></tr><tr><td class=\"l\">before</td><td>" +
         formatWith("%.3f", mmToUm(p.before.max_deviation)) + "</td><td>" +
         formatWith("%.3f", mmToUm(p.before.rms_deviation)) +
         "</td></tr><tr><td class=\"l\">after</td><td>" +
         formatWith("%.3f", mmToUm(p.after.max_deviation)) + "</td><td>" +
         formatWith("%.3f", mmToUm(p.after.rms_deviation)) +
         "</td></tr><tr><td class=\"l\">change</td><td>" +
         formatWith("%.3f", mmToUm(p.change_max)) + "</td><td>" +
         formatWith("%.3f", mmToUm(p.change_rms)) + "</td></tr></table>\n";
  }
  return h;
}

// Every candidate tried, and the page's end.
std::string htmlCandidates(const DiagnosisView& v) {
  const DiagnosisResult& r = v.r;
  const DiagnosisReportInputs& in = v.in;
  const MachineModel& base = v.base;
  std::string h;
  // Candidates.
  h += "<h2>Every candidate tried</h2>\n<table><tr><th>round</th><th class=\"l\">candidate</th>"
       "<th>ΔIC</th><th>p (adjusted)</th><th>m_eff</th><th>cross-validated before (µm)</th>"
       "<th>cross-validated after (µm; — where an earlier test decided)</th><th>new "
       "information</th><th class=\"l\">verdict</th></tr>";
  std::vector<CandidateScore> c = r.candidates;
  std::stable_sort(c.begin(), c.end(), [](const CandidateScore& a, const CandidateScore& b) {
    return a.round != b.round ? a.round < b.round : a.delta_ic > b.delta_ic;
  });
  for (const CandidateScore& s : c)
    h += "<tr><td>" + std::to_string(s.round) + "</td><td class=\"l\">" + xmlEscape(s.label) +
         "</td><td>" + formatWith("%.1f", s.delta_ic) + "</td><td>" +
         formatWith("%.2g", s.p_value) + "</td><td>" + formatWith("%.0f", s.effective_readings) +
         "</td><td>" + formatWith("%.3f", mmToUm(s.cv_rms_before)) + "</td><td>" +
         (std::isfinite(s.cv_rms_after) ? formatWith("%.3f", mmToUm(s.cv_rms_after))
                                        : std::string("—")) +
         "</td><td>" + formatWith("%.3f", s.new_information) + "</td><td class=\"l\">" +
         verdictName(s.verdict) + "</td></tr>";
  h += "</table>\n<p class=\"note\">" + xmlEscape(base.name) + "; " +
       formatWith("%.2f", in.seconds) + " s.</p></body></html>\n";
  return h;
}

}  // namespace

// The report's sections in the order the reader meets them.
std::string writeDiagnosisHtml(const std::string& dir, const MachineModel& base,
                               const BallbarTest& test, const DiagnosisResult& r,
                               const DiagnosisReportInputs& in) {
  const DiagnosisView v{dir, base, test, r, in};
  return htmlVerdict(v) + htmlBeforeAfter(v) + htmlRemoved(v) + htmlAdded(v) +
         htmlResidualPlots(v) + htmlUnexplained(v) + htmlResidualAnalysis(v) + htmlProgram(v) +
         htmlCandidates(v);
}

}  // namespace tolver
