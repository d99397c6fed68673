#include "io/report/calibration_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "core/numerics/units.h"
#include "io/common/json_text.h"
#include "io/common/text_util.h"
#include "io/machine/ballbar_file.h"
#include "io/machine/machine_file.h"

namespace tolver {

// Long by design: the JSON document's members in order, each a line or two.
nlohmann::json lackOfFitJson(const LackOfFit& l) {
  if (!l.tested)
    return {{"tested", false},
            {"reason",
             "no pose is measured twice (or too few degrees of freedom): the model's "
             "adequacy cannot be tested"}};
  return {{"tested", true},
          {"repeated_poses", l.poses},
          {"readings_at_them", l.repeats},
          {"df_pure_error", l.df_pure},
          {"df_lack_of_fit", l.df_lack},
          {"repeatability_um", mmToUm(l.s_pure)},
          {"fit_sigma_um", mmToUm(l.s_fit)},
          {"f", l.f},
          {"p_value", l.p_value},
          {"missing_rms_um", mmToUm(l.missing_rms)}};
}

std::string describeLackOfFit(const LackOfFit& l, double alpha) {
  if (!l.tested)
    return "not tested: no pose is measured twice, so the model's adequacy cannot be judged";
  char buf[320];
  std::snprintf(
      buf, sizeof buf,
      "repeatability %.3f um (%d poses, %.0f df) against the fit's %.3f um: F %.2f, p %.2g: %s",
      mmToUm(l.s_pure), l.poses, l.df_pure, mmToUm(l.s_fit), l.f, l.p_value,
      l.p_value < alpha ? "the model misses " : "no significant lack of fit (level ");
  std::string out = buf;
  if (l.p_value < alpha)
    out += formatWith("%.3f um RMS beyond the repeatability", mmToUm(l.missing_rms));
  else
    out += formatWith("%.2g)", alpha);
  return out;
}

std::string formatCalibrationJson(const MachineModel& m, const BallbarTest& test,
                                  const CalibrationResult& r, const CalibrationReportInputs& in) {
  using nlohmann::json;
  auto unitScale = [&](int p) { return m.parameters[p].angular ? radToUrad(1.0) : mmToUm(1.0); };
  auto unitName = [&](int p) { return m.parameters[p].angular ? "urad" : "um"; };
  json j;
  j["machine_file"] = in.machine_file;
  j["readings_file"] = in.readings_file;
  j["identified_machine_file"] = in.output_file;
  j["readings"] = test.readings.size();
  j["setups"] = test.setups.size();
  j["status"] = r.status == CalibrationStatus::Converged ? "converged" : r.message;
  j["iterations"] = r.iterations;
  j["unknowns"] = r.unknowns;
  j["rank"] = r.rank;
  j["condition_number"] = r.condition;
  j["residual_rms_um"] = mmToUm(r.rms_residual);
  j["residual_max_um"] = mmToUm(r.max_residual);
  j["residual_sigma_um"] = mmToUm(r.residual_sigma);
  j["lack_of_fit"] = lackOfFitJson(lackOfFit(test, r.residuals, r.unknowns));
  j["method"] =
      "Gauss-Newton with the SVD pseudo-inverse of the column-scaled identification Jacobian "
      "(rank tolerance 1e-9 of the largest singular value); uncertainties from s^2 (J^T J)^-1; "
      "observability = 1/sqrt(variance inflation factor) of the column-scaled Jacobian";
  json params = json::array();
  for (size_t k = 0; k < r.identified.size(); ++k) {
    const int p = r.identified[k];
    params.push_back({{"name", m.parameters[p].thesis_name},
                      {"iso_code", m.parameters[p].iso_code},
                      {"unit", unitName(p)},
                      {"value", r.params[p] * unitScale(p)},
                      {"uncertainty", r.uncertainty[k] * unitScale(p)},
                      {"observability", r.observability[k]}});
  }
  for (size_t k = 0; k < r.identified.size(); ++k) {
    const int p = r.identified[k];
    const auto it = std::find(in.unknowns.begin(), in.unknowns.end(), p);
    if (it == in.unknowns.end() || in.absorbed.empty()) continue;
    const auto& terms = in.absorbed[it - in.unknowns.begin()];
    if (terms.empty()) continue;
    json a = json::array();
    for (const AbsorbedTerm& t : terms)
      a.push_back({{"iso_code", m.parameters[t.parameter].iso_code},
                   {"name", m.parameters[t.parameter].thesis_name},
                   {"coefficient", t.coefficient},
                   {"unit", std::string(unitName(p)) + " per " + unitName(t.parameter)}});
    params[k]["stands_for"] = standsFor(m, p, terms, 1000);
    params[k]["absorbs"] = a;
  }
  j["parameters"] = params;
  json held = json::array();
  for (int p : r.held)
    held.push_back({{"name", m.parameters[p].thesis_name},
                    {"iso_code", m.parameters[p].iso_code},
                    {"held_at", r.params[p] * unitScale(p)},
                    {"unit", unitName(p)}});
  j["held_parameters"] = held;
  if (!r.held.empty())
    j["warning"] =
        "the readings cannot see the held parameters: predictions that depend on them "
        "are unverified";
  json balls = json::array();
  for (size_t s = 0; s < test.setups.size() && s < r.ball_errors.size(); ++s) {
    const auto& e = r.ball_errors[s];
    const auto& u = r.ball_uncertainty[s];
    balls.push_back(
        {{"setup", test.setups[s].id},
         {"table_ball_error_um",
          {mmToUm(e.table_w.x()), mmToUm(e.table_w.y()), mmToUm(e.table_w.z())}},
         {"table_ball_uncertainty_um",
          {mmToUm(u.table_w.x()), mmToUm(u.table_w.y()), mmToUm(u.table_w.z())}},
         {"tool_ball_error_um", {mmToUm(e.tool_t.x()), mmToUm(e.tool_t.y()), mmToUm(e.tool_t.z())}},
         {"tool_ball_uncertainty_um",
          {mmToUm(u.tool_t.x()), mmToUm(u.tool_t.y()), mmToUm(u.tool_t.z())}}});
  }
  j["ball_errors"] = balls;
  auto stats = [](const ResidualStats& x) {
    return json{{"readings", x.readings}, {"rms_um", mmToUm(x.rms)}, {"max_um", mmToUm(x.max)}};
  };
  if (!in.balls_file.empty()) j["ball_positions_file"] = in.balls_file;
  if (!in.heldout.file.empty())
    j["heldout"] = {{"file", in.heldout.file},
                    {"before", stats(in.heldout.before)},
                    {"after", stats(in.heldout.after)},
                    {"before_means", "the prior machine file with the nominal ball positions"}};
  j["written_files_check"] = {
      {"description", "the written machine file and ball positions, read back, on the readings"},
      {"fit", stats(in.written.fit)}};
  if (in.written.heldout.readings > 0)
    j["written_files_check"]["heldout"] = stats(in.written.heldout);
  json removed = json::array();
  for (const RemovedReading& g : in.removed)
    removed.push_back(
        {{"line", g.line}, {"residual_um", mmToUm(g.residual)}, {"studentized", g.studentized}});
  j["gross_readings_removed"] = removed;
  return jsonText(j);
}

std::string standsFor(const MachineModel& m, int p, const std::vector<AbsorbedTerm>& terms,
                      int max_terms) {
  std::string s = m.parameters[p].iso_code;
  char buf[96];
  int n = 0;
  for (const AbsorbedTerm& t : terms) {
    if (n == max_terms) {
      std::snprintf(buf, sizeof buf, " (+%d more)", static_cast<int>(terms.size()) - n);
      s += buf;
      break;
    }
    const double c = t.coefficient;
    const std::string& name = m.parameters[t.parameter].iso_code;
    if (std::abs(c - 1.0) < 1e-3)
      s += " + " + name;
    else if (std::abs(c + 1.0) < 1e-3)
      s += " - " + name;
    else {
      std::snprintf(buf, sizeof buf, " %s %.3g ", c < 0 ? "-" : "+", std::abs(c));
      s += buf + name;
    }
    ++n;
  }
  return s;
}

WrittenCheck checkWrittenFiles(const std::string& machine_file, const std::string& balls_file,
                               const BallbarTest& fit, const BallbarTest& heldout,
                               const PartSetup* setup) {
  Machine m = readMachineFile(machine_file);
  if (setup) m.model.setup = *setup;
  const std::vector<BallErrors> balls = readBallPositionsFile(balls_file, fit);
  const ForwardKinematics fk(m.model, m.params);
  WrittenCheck c;
  c.fit = residualStats(ballbarResiduals(fk, fit, balls));
  if (!heldout.readings.empty()) c.heldout = residualStats(ballbarResiduals(fk, heldout, balls));
  return c;
}

std::string formatBallbarGcode(const MachineModel& m, const BallbarTest& plan, double feed,
                               double dwell_s) {
  std::string o = "%\n(tolver ball-bar plan: " + m.name + ")\n";
  o += "(NC values = nc_sign * joint value, relative to the machine file's zero: apply your work "
       "offset)\n";
  o += "G90 G94 G21\n";
  char buf[256];
  int current = -1, n = 0;
  for (const BallbarReading& r : plan.readings) {
    if (r.setup != current) {
      current = r.setup;
      const BallbarSetup& s = plan.setups[r.setup];
      std::snprintf(
          buf, sizeof buf,
          "(SET-UP %d: TABLE BALL %.3f %.3f %.3f IN W, TOOL BALL %.3f %.3f %.3f IN T)\nM0\n", s.id,
          s.table_ball_w.x(), s.table_ball_w.y(), s.table_ball_w.z(), s.tool_ball_t.x(),
          s.tool_ball_t.y(), s.tool_ball_t.z());
      o += buf;
    }
    std::string rot, lin;
    for (size_t a = 0; a < m.axes.size(); ++a) {
      const Axis& ax = m.axes[a];
      const double v = ax.nc_sign * (ax.isRotary() ? radToDeg(r.q[a]) : r.q[a]);
      std::snprintf(buf, sizeof buf, " %s%.4f", ax.name.c_str(), v);
      (ax.isRotary() ? rot : lin) += buf;
    }
    ++n;
    if (!rot.empty()) o += "N" + std::to_string(10 * n) + " G0" + rot + "\n";
    std::snprintf(buf, sizeof buf, " F%.0f\nG4 P%.1f\n", feed, dwell_s);
    o += "G1" + lin + buf;
  }
  o += "M30\n%\n";
  return o;
}

}  // namespace tolver
