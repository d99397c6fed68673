#include "io/machine/ballbar_file.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <map>

#include "core/numerics/quantities.h"
#include "core/numerics/units.h"
#include "io/common/io_error.h"
#include "io/common/text_util.h"

namespace tolver {
namespace {

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string setupText(int id) {
  std::string s = "set-up ";
  s += std::to_string(id);
  return s;
}

std::string axisColumn(const Axis& ax) { return lower(ax.name) + (ax.isRotary() ? "_deg" : "_mm"); }

}  // namespace

// Long by design: one reader over the header and the rows, each value checked against its
// plausible range where it is read (the messages name line and column).
BallbarFile parseBallbarCsv(const std::string& text, const std::string& file, const MachineModel& m,
                            bool require_length) {
  BallbarFile out;
  std::vector<std::string> required = {"setup",           "table_ball_x_mm", "table_ball_y_mm",
                                       "table_ball_z_mm", "tool_ball_x_mm",  "tool_ball_y_mm",
                                       "tool_ball_z_mm"};
  for (const Axis& ax : m.axes) required.push_back(axisColumn(ax));
  if (require_length) required.push_back("length_mm");
  std::vector<int> dir_col(m.axes.size(), -1);
  bool has_time = false;
  auto header = [&](const CsvHeader& h) {
    std::map<std::string, bool> known;
    for (const std::string& r : required) known[r] = true;
    known["time_s"] = true;
    known["length_mm"] = true;
    for (size_t a = 0; a < m.axes.size(); ++a) {
      const std::string d = lower(m.axes[a].name) + "_dir";
      known[d] = true;
      if (h.has(d)) {
        dir_col[a] = h.columns.at(d);
        out.has_directions = true;
      }
    }
    has_time = h.has("time_s");
    for (const auto& [name, k] : h.columns)
      if (!known.count(name)) out.warnings.push_back("ignored column '" + name + "'");
  };
  std::map<int, int> setup_index;  // file id -> index
  std::map<int, int> setup_line;
  auto row = [&](const CsvRow& csv) {
    const int line = csv.line;
    const std::vector<std::string>& cells = *csv.cells;
    auto value = [&](const std::string& name) {
      const int k = csv.column(name) - 1;
      if (k < 0 || k >= static_cast<int>(cells.size()) || cells[k].empty())
        throw InputError(file, line, 0, name, "missing value");
      const auto v = parseNumber(cells[k]);
      if (!v) throw InputError(file, line, 0, name, "malformed number '" + cells[k] + "'");
      // Plausible ranges: lengths and positions as everywhere (core/numerics/quantities.h),
      // rotary axis values within 1e4 deg (an endless axis), times from 0 to 1e9 s; nothing
      // absurd reaches the model.
      const bool deg = name.size() > 4 && name.compare(name.size() - 4, 4, "_deg") == 0;
      const bool mm = name.size() > 3 && name.compare(name.size() - 3, 3, "_mm") == 0;
      std::string problem;
      if (name == "length_mm")
        problem = outOfRange(Quantity::BarLength, *v);
      else if (mm)
        problem = outOfRange(Quantity::Position, *v);
      else if (name == "time_s" && !(*v >= 0 && *v <= 1e9))
        problem = "expected 0 to 1e9 s";
      else if (deg && !(std::abs(*v) <= 1e4))
        problem = "expected within 1e4 deg";
      if (!problem.empty())
        throw InputError(file, line, k + 1, name, "'" + cells[k] + "': " + problem);
      return *v;
    };
    BallbarReading r;
    r.line = line;
    const double sid = value("setup");
    if (sid != std::floor(sid)) throw InputError(file, line, 0, "setup", "expected an integer");
    const Eigen::Vector3d bw(value("table_ball_x_mm"), value("table_ball_y_mm"),
                             value("table_ball_z_mm"));
    const Eigen::Vector3d bt(value("tool_ball_x_mm"), value("tool_ball_y_mm"),
                             value("tool_ball_z_mm"));
    const int id = static_cast<int>(sid);
    auto it = setup_index.find(id);
    if (it == setup_index.end()) {
      BallbarSetup s;
      s.id = id;
      s.table_ball_w = bw;
      s.tool_ball_t = bt;
      it = setup_index.emplace(id, static_cast<int>(out.test.setups.size())).first;
      setup_line[id] = line;
      out.test.setups.push_back(s);
    } else {
      const BallbarSetup& s = out.test.setups[it->second];
      if ((s.table_ball_w - bw).norm() > 1e-9 || (s.tool_ball_t - bt).norm() > 1e-9)
        throw InputError(file, line, 0, "setup",
                         "set-up " + std::to_string(id) + " has other ball positions at line " +
                             std::to_string(setup_line[id]));
    }
    r.setup = it->second;
    r.q.resize(m.axes.size());
    for (size_t a = 0; a < m.axes.size(); ++a) {
      const double v = value(axisColumn(m.axes[a]));
      r.q[a] = m.axes[a].isRotary() ? degToRad(v) : v;
      if (dir_col[a] >= 0) {
        const std::string name = lower(m.axes[a].name) + "_dir";
        const double d = value(name);
        if (d != 1.0 && d != -1.0) throw InputError(file, line, 0, name, "expected +1 or -1");
        r.context.direction[a] = static_cast<signed char>(d);
      }
    }
    if (require_length) {
      r.length = value("length_mm");
      if (!(r.length > 0)) throw InputError(file, line, 0, "length_mm", "must be positive");
    }
    if (has_time) r.context.time_s = value("time_s");
    out.test.readings.push_back(r);
  };
  forEachCsvRow(text, file, required, "missing column", row, header);
  if (out.test.readings.empty()) throw InputError(file, 0, 0, "", "no rows");
  if (!out.has_directions) deriveDirections(out.test);
  return out;
}

BallbarFile readBallbarFile(const std::string& path, const MachineModel& model,
                            bool require_length) {
  return parseBallbarCsv(readFile(path), path, model, require_length);
}

std::string formatBallbarCsv(const MachineModel& m, const BallbarTest& test, bool with_length,
                             const std::vector<std::string>& comments) {
  std::string out;
  for (const std::string& c : comments) out += "# " + c + "\n";
  out +=
      "setup,table_ball_x_mm,table_ball_y_mm,table_ball_z_mm,tool_ball_x_mm,tool_ball_y_mm,"
      "tool_ball_z_mm";
  for (const Axis& ax : m.axes) {
    out += ",";
    out += axisColumn(ax);
  }
  bool any_time = false;
  for (const BallbarReading& r : test.readings) any_time |= !std::isnan(r.context.time_s);
  if (any_time) out += ",time_s";
  if (with_length) out += ",length_mm";
  out += "\n";
  // Fixed precision: 1e-6 mm and 1e-6 deg for positions, 1e-7 mm for lengths (0.1 nm).
  char buf[64];
  auto put = [&](const char* fmt, double v) {
    std::snprintf(buf, sizeof buf, fmt, v);
    out += ",";
    out += buf;
  };
  for (const BallbarReading& r : test.readings) {
    const BallbarSetup& s = test.setups[r.setup];
    out += std::to_string(s.id);
    for (int k = 0; k < 3; ++k) put("%.6f", s.table_ball_w[k]);
    for (int k = 0; k < 3; ++k) put("%.6f", s.tool_ball_t[k]);
    for (size_t a = 0; a < m.axes.size(); ++a)
      put("%.6f", m.axes[a].isRotary() ? radToDeg(r.q[a]) : r.q[a]);
    if (any_time) put("%.3f", r.context.time_s);
    if (with_length) put("%.7f", r.length);
    out += "\n";
  }
  return out;
}

void alignHeldout(BallbarTest& heldout, const BallbarTest& fit, const std::string& file,
                  const std::string& fit_file) {
  std::vector<int> to_fit(heldout.setups.size(), -1);
  for (size_t k = 0; k < heldout.setups.size(); ++k) {
    const BallbarSetup& h = heldout.setups[k];
    int first_line = 0;
    for (const BallbarReading& r : heldout.readings)
      if (r.setup == static_cast<int>(k)) {
        first_line = r.line;
        break;
      }
    for (size_t j = 0; j < fit.setups.size(); ++j)
      if (fit.setups[j].id == h.id) to_fit[k] = static_cast<int>(j);
    if (to_fit[k] < 0)
      throw InputError(file, first_line, 0, "setup",
                       setupText(h.id) + " is not in the fit readings " + fit_file +
                           ": held-out readings must come from the fit's set-ups");
    const BallbarSetup& f = fit.setups[to_fit[k]];
    if ((f.table_ball_w - h.table_ball_w).norm() > 1e-6 ||
        (f.tool_ball_t - h.tool_ball_t).norm() > 1e-6)
      throw InputError(file, first_line, 0, "setup",
                       setupText(h.id) + " has other nominal ball positions than in " + fit_file);
  }
  for (BallbarReading& r : heldout.readings) r.setup = to_fit[r.setup];
  heldout.setups = fit.setups;
  for (const BallbarReading& h : heldout.readings)
    for (const BallbarReading& f : fit.readings)
      if (f.setup == h.setup && (f.q - h.q).cwiseAbs().maxCoeff() < 1e-6)
        throw InputError(file, h.line, 0, "pose",
                         std::string("the fit readings measured this pose (") + fit_file +
                             " line " + std::to_string(f.line) +
                             "): a held-out reading must be a pose the fit did not use");
}

std::string formatBallPositionsCsv(const BallbarTest& test, const std::vector<BallErrors>& balls,
                                   const std::vector<BallErrors>* uncertainty,
                                   const std::vector<std::string>& comments) {
  std::string out;
  for (const std::string& c : comments) out += "# " + c + "\n";
  out +=
      "setup,table_ball_x_mm,table_ball_y_mm,table_ball_z_mm,tool_ball_x_mm,tool_ball_y_mm,"
      "tool_ball_z_mm";
  if (uncertainty)
    out += ",u_table_x_um,u_table_y_um,u_table_z_um,u_tool_x_um,u_tool_y_um,u_tool_z_um";
  out += "\n";
  char buf[64];
  for (size_t k = 0; k < test.setups.size(); ++k) {
    const BallbarSetup& s = test.setups[k];
    out += std::to_string(s.id);
    const Eigen::Vector3d w = s.table_ball_w + balls[k].table_w,
                          t = s.tool_ball_t + balls[k].tool_t;
    for (int i = 0; i < 3; ++i) (out += ",") += formatNumber(w[i]);
    for (int i = 0; i < 3; ++i) (out += ",") += formatNumber(t[i]);
    if (uncertainty) {
      for (int i = 0; i < 3; ++i) {
        std::snprintf(buf, sizeof buf, ",%.4f", mmToUm((*uncertainty)[k].table_w[i]));
        out += buf;
      }
      for (int i = 0; i < 3; ++i) {
        std::snprintf(buf, sizeof buf, ",%.4f", mmToUm((*uncertainty)[k].tool_t[i]));
        out += buf;
      }
    }
    out += "\n";
  }
  return out;
}

std::vector<BallErrors> parseBallPositionsCsv(const std::string& text, const std::string& file,
                                              const BallbarTest& test) {
  std::vector<BallErrors> out(test.setups.size());
  std::vector<int> seen(test.setups.size(), 0);
  forEachCsvRow(text, file,
                {"setup", "table_ball_x_mm", "table_ball_y_mm", "table_ball_z_mm", "tool_ball_x_mm",
                 "tool_ball_y_mm", "tool_ball_z_mm"},
                "missing column", [&](const CsvRow& row) {
                  auto value = [&](const char* name) {
                    const std::string c = row.cell(name);
                    const auto v = parseNumber(c);
                    if (!v)
                      throw InputError(file, row.line, row.column(name), name,
                                       c.empty() ? "missing value" : "malformed number");
                    return *v;
                  };
                  const double id = value("setup");
                  int k = -1;
                  for (size_t j = 0; j < test.setups.size(); ++j)
                    if (test.setups[j].id == id) k = static_cast<int>(j);
                  if (k < 0) return;  // a set-up these readings do not use
                  if (seen[k])
                    throw InputError(file, row.line, row.column("setup"), "setup",
                                     "set-up " + std::to_string(test.setups[k].id) +
                                         " given twice (first at line " + std::to_string(seen[k]) +
                                         ")");
                  seen[k] = row.line;
                  const Eigen::Vector3d w(value("table_ball_x_mm"), value("table_ball_y_mm"),
                                          value("table_ball_z_mm"));
                  const Eigen::Vector3d t(value("tool_ball_x_mm"), value("tool_ball_y_mm"),
                                          value("tool_ball_z_mm"));
                  out[k].table_w = w - test.setups[k].table_ball_w;
                  out[k].tool_t = t - test.setups[k].tool_ball_t;
                  // A centre more than 10 mm from the nominal one is another set-up, not an error.
                  if (out[k].table_w.norm() > 10.0 || out[k].tool_t.norm() > 10.0)
                    throw InputError(file, row.line, 0, "setup",
                                     "set-up " + std::to_string(test.setups[k].id) +
                                         ": ball centres more than 10 mm from the readings' "
                                         "nominal ones (another set-up?)");
                });
  for (size_t k = 0; k < seen.size(); ++k)
    if (!seen[k])
      throw InputError(
          file, 0, 0, "setup",
          "no ball positions for set-up " + std::to_string(test.setups[k].id) + " of the readings");
  return out;
}

std::vector<BallErrors> readBallPositionsFile(const std::string& path, const BallbarTest& test) {
  return parseBallPositionsCsv(readFile(path), path, test);
}

}  // namespace tolver
