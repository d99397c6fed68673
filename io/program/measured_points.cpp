#include "io/program/measured_points.h"

#include <cmath>

#include "io/common/io_error.h"
#include "io/common/text_util.h"

namespace tolver {
namespace {

constexpr double kLimit = 1e6;  // mm: a coordinate beyond 1 km is not a part's

std::vector<std::string> splitNumbers(const std::string& line) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : line) {
    if (c == ',' || c == ';' || c == ' ' || c == '\t') {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

bool numericLine(const std::string& line) {
  const std::vector<std::string> cells = splitNumbers(line);
  if (cells.size() < 3) return false;
  for (const std::string& c : cells)
    if (!parseNumber(c)) return false;
  return true;
}

void checkNormal(MeasuredPoint& p, const std::string& file, int column) {
  const double len = p.n.norm();
  if (!(len > 1e-9))
    throw InputError(file, p.line, column, "nx", "the normal is zero: give a direction or none");
  p.n /= len;
}

std::vector<MeasuredPoint> parseAsc(const std::vector<std::string>& lines,
                                    const std::string& file) {
  std::vector<MeasuredPoint> out;
  size_t columns = 0;
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string_view t = trim(lines[i]);
    if (t.empty() || t[0] == '#' || t[0] == '/') continue;
    const std::vector<std::string> cells = splitNumbers(std::string(t));
    const int line = static_cast<int>(i) + 1;
    if (columns == 0) columns = cells.size();
    if (cells.size() != columns)
      throw InputError(file, line, 0, "x",
                       "expected " + std::to_string(columns) +
                           " numbers as on the first line, got " + std::to_string(cells.size()));
    MeasuredPoint p;
    p.line = line;
    double v[6] = {0, 0, 0, 0, 0, 0};
    for (size_t k = 0; k < cells.size() && k < 6; ++k) {
      static const char* names[6] = {"x", "y", "z", "nx", "ny", "nz"};
      const auto x = parseNumber(cells[k]);
      if (!x)
        throw InputError(file, line, static_cast<int>(k) + 1, names[k],
                         "'" + cells[k] + "' is not a number");
      if (!(std::abs(*x) <= kLimit))
        throw InputError(file, line, static_cast<int>(k) + 1, names[k],
                         "'" + cells[k] + "' is out of range (within 1e6 mm)");
      v[k] = *x;
    }
    p.p = Eigen::Vector3d(v[0], v[1], v[2]);
    if (cells.size() >= 6) {
      p.n = Eigen::Vector3d(v[3], v[4], v[5]);
      checkNormal(p, file, 4);
    }
    out.push_back(p);
  }
  return out;
}

}  // namespace

std::vector<MeasuredPoint> parseMeasuredPoints(const std::string& text, const std::string& file) {
  const std::vector<std::string> lines = splitLines(text);
  for (const std::string& l : lines) {
    const std::string_view t = trim(l);
    if (t.empty() || t[0] == '#' || t[0] == '/') continue;
    if (numericLine(std::string(t))) return parseAsc(lines, file);
    break;
  }
  std::vector<MeasuredPoint> out;
  std::string xs = "x_mm", ys = "y_mm", zs = "z_mm", ds = "deviation_mm";
  bool nominal_table = false;
  forEachCsvRow(
      text, file, {}, "",
      [&](const CsvRow& row) {
        auto number = [&](const std::string& name) {
          const std::string c = row.cell(name);
          if (c.empty()) throw InputError(file, row.line, row.column(name), name, "missing value");
          const auto v = parseNumber(c);
          if (!v)
            throw InputError(file, row.line, row.column(name), name, "'" + c + "' is not a number");
          if (!(std::abs(*v) <= kLimit))
            throw InputError(file, row.line, row.column(name), name,
                             "'" + c + "' is out of range (within 1e6 mm)");
          return *v;
        };
        MeasuredPoint p;
        p.line = row.line;
        p.p = Eigen::Vector3d(number(xs), number(ys), number(zs));
        const int given =
            !row.cell("nx").empty() + !row.cell("ny").empty() + !row.cell("nz").empty();
        if (given == 3) {
          p.n = Eigen::Vector3d(number("nx"), number("ny"), number("nz"));
          checkNormal(p, file, row.column("nx"));
        } else if (given != 0) {
          throw InputError(file, row.line, row.column("nx"), "nx",
                           "give all three of nx, ny, nz or none");
        }
        if (!row.cell(ds).empty()) {
          p.deviation = number(ds);
          p.has_deviation = true;
        }
        if (nominal_table) {  // the measured point: the nominal moved by the deviation along n
          if (given != 3 || !p.has_deviation)
            throw InputError(file, row.line, given != 3 ? row.column("nx") : row.column(ds),
                             given != 3 ? "nx" : ds,
                             "a deviation table (nominal_x_mm, ...) needs the normal and the "
                             "deviation on every row");
          p.p += p.deviation * p.n;
        }
        out.push_back(p);
      },
      [&](const CsvHeader& h) {
        if (!h.has("x_mm") && h.has("x")) xs = "x", ys = "y", zs = "z";
        if (!h.has("x_mm") && h.has("actual_x_mm"))
          xs = "actual_x_mm", ys = "actual_y_mm", zs = "actual_z_mm";
        if (!h.has("x_mm") && !h.has("x") && !h.has("actual_x_mm") && h.has("nominal_x_mm")) {
          xs = "nominal_x_mm", ys = "nominal_y_mm", zs = "nominal_z_mm";
          nominal_table = true;
        }
        if (!h.has("deviation_mm") && h.has("deviation")) ds = "deviation";
        for (const std::string& c : {xs, ys, zs})
          if (!h.has(c))
            throw InputError(file, h.line, 0, c,
                             "missing column (header: x_mm,y_mm,z_mm[,nx,ny,nz][,deviation_mm])");
      });
  return out;
}

std::vector<MeasuredPoint> readMeasuredPoints(const std::string& path) {
  std::vector<MeasuredPoint> p = parseMeasuredPoints(readFile(path), path);
  if (p.empty()) throw InputError(path, 0, 0, "x_mm", "no measured points");
  return p;
}

}  // namespace tolver
