#include "io/program/probe_file.h"

#include <cmath>

#include "core/numerics/quantities.h"
#include "core/numerics/units.h"
#include "io/common/io_error.h"
#include "io/common/text_util.h"

namespace tolver {
namespace {

std::string axisColumn(const Axis& ax) {
  return toLower(ax.name) + (ax.isRotary() ? "_deg" : "_mm");
}

}  // namespace

std::vector<ProbedPoint> parseProbeCsv(const std::string& text, const std::string& file,
                                       const MachineModel& model) {
  std::vector<ProbedPoint> points;
  forEachCsvRow(
      text, file, {"part_x_mm", "part_y_mm", "part_z_mm"},
      "missing column (header: part_x_mm,part_y_mm,part_z_mm and one column per axis)",
      [&](const CsvRow& row) {
        auto number = [&](const std::string& name, double limit) {
          if (row.column(name.c_str()) == 0)
            throw InputError(file, row.line, 0, name, "missing column");
          const std::string c = row.cell(name.c_str());
          if (c.empty())
            throw InputError(file, row.line, row.column(name.c_str()), name, "missing value");
          const auto v = parseNumber(c);
          if (!v)
            throw InputError(file, row.line, row.column(name.c_str()), name,
                             "'" + c + "' is not a number");
          if (!(std::abs(*v) <= limit))
            throw InputError(file, row.line, row.column(name.c_str()), name,
                             "'" + c + "' is out of range (within " + formatNumber(limit) + ")");
          return *v;
        };
        // A value of a quantity with its range (core/numerics/quantities.h), as the options'.
        auto quantity = [&](const std::string& name, Quantity q) {
          const double v = number(name, INFINITY);
          if (const std::string problem = outOfRange(q, v); !problem.empty())
            throw InputError(file, row.line, row.column(name.c_str()), name, problem);
          return v;
        };
        ProbedPoint p;
        p.line = row.line;
        p.q.resize(model.axes.size());
        for (size_t a = 0; a < model.axes.size(); ++a) {
          const Axis& ax = model.axes[a];
          const double v = ax.isRotary() ? number(axisColumn(ax), 1e4)
                                         : quantity(axisColumn(ax), Quantity::Position);
          p.q[a] = ax.isRotary() ? degToRad(v) : v;
        }
        if (!row.cell("tram_x_urad").empty() || !row.cell("tram_y_urad").empty()) {
          // A spindle tram: the tool axis against the table at these joints, nothing else.
          for (const char* other : {"part_x_mm", "part_y_mm", "part_z_mm", "part_nx", "part_ny",
                                    "part_nz", "probe_length_mm"})
            if (!row.cell(other).empty())
              throw InputError(
                  file, row.line, row.column(other), other,
                  "a tram row (tram_x_urad, tram_y_urad) takes joints only: leave this empty");
          p.tram = true;
          p.tilt = Eigen::Vector2d(uradToRad(number("tram_x_urad", 1e5)),
                                   uradToRad(number("tram_y_urad", 1e5)));
          points.push_back(p);
          return;
        }
        p.p_w = Eigen::Vector3d(quantity("part_x_mm", Quantity::Position),
                                quantity("part_y_mm", Quantity::Position),
                                quantity("part_z_mm", Quantity::Position));
        const int given = !row.cell("part_nx").empty() + !row.cell("part_ny").empty() +
                          !row.cell("part_nz").empty();
        if (given == 3) {
          const Eigen::Vector3d n(number("part_nx", 1e6), number("part_ny", 1e6),
                                  number("part_nz", 1e6));
          if (n.norm() < 1e-9)
            throw InputError(file, row.line, row.column("part_nx"), "part_nx",
                             "the probing direction is zero");
          p.n_w = n.normalized();
        } else if (given != 0) {
          throw InputError(file, row.line, 0, "part_nx",
                           "give all of part_nx, part_ny, part_nz or none");
        }
        p.probe_length = model.setup.gauge_length;
        if (!row.cell("probe_length_mm").empty()) {
          p.probe_length = quantity("probe_length_mm", Quantity::Length);
        }
        points.push_back(p);
      });
  if (points.empty()) throw InputError(file, 0, 0, "points", "the file has no probed point");
  return points;
}

std::vector<ProbedPoint> readProbeFile(const std::string& path, const MachineModel& model) {
  return parseProbeCsv(readFile(path), path, model);
}

std::string formatProbeCsv(const MachineModel& model, const std::vector<ProbedPoint>& points) {
  std::string out = "part_x_mm,part_y_mm,part_z_mm";
  for (const Axis& ax : model.axes) out += "," + axisColumn(ax);
  out += ",part_nx,part_ny,part_nz,probe_length_mm";
  const bool trams = hasTram(points);
  out += trams ? ",tram_x_urad,tram_y_urad\n" : "\n";
  for (const ProbedPoint& p : points) {
    std::string row = p.tram ? ",,"
                             : formatNumber(p.p_w.x()) + "," + formatNumber(p.p_w.y()) + "," +
                                   formatNumber(p.p_w.z());
    for (size_t a = 0; a < model.axes.size(); ++a)
      row += "," + formatNumber(model.axes[a].isRotary() ? radToDeg(p.q[a]) : p.q[a]);
    if (p.n_w.isZero() || p.tram)
      row += ",,,";
    else
      row += "," + formatNumber(p.n_w.x()) + "," + formatNumber(p.n_w.y()) + "," +
             formatNumber(p.n_w.z());
    row += "," + (p.tram ? std::string() : formatNumber(p.probe_length));
    if (trams)
      row += p.tram ? "," + formatNumber(radToUrad(p.tilt.x())) + "," +
                          formatNumber(radToUrad(p.tilt.y()))
                    : ",,";
    out += row + "\n";
  }
  return out;
}

}  // namespace tolver
