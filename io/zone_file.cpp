#include "io/zone_file.h"

#include <map>
#include <sstream>
#include <stdexcept>

#include "io/io_error.h"
#include "io/text_util.h"

namespace tolver {

std::vector<ToleranceZone> parseZoneCsv(const std::string& text, const std::string& file) {
  const auto lines = splitLines(text);
  std::map<std::string, int> col;
  std::vector<ToleranceZone> zones;
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string_view t = trim(lines[i]);
    if (t.empty() || t[0] == '#') continue;
    const int line = static_cast<int>(i) + 1;
    const auto c = splitCsvLine(lines[i]);
    if (col.empty()) {
      for (size_t k = 0; k < c.size(); ++k) col[c[k]] = static_cast<int>(k);
      for (const char* r : {"region", "tolerance"})
        if (!col.count(r)) throw InputError(file, line, 0, r, "missing column (header: region,tolerance,uz,u)");
      continue;
    }
    auto cell = [&](const char* name) -> std::string {
      auto it = col.find(name);
      return it == col.end() || it->second >= static_cast<int>(c.size()) ? std::string() : c[it->second];
    };
    auto column = [&](const char* name) { return col.count(name) ? col[name] + 1 : 0; };
    auto number = [&](const char* name) {
      const auto v = parseNumber(cell(name));
      if (!v) throw InputError(file, line, column(name), name, "'" + cell(name) + "' is not a number");
      return *v;
    };
    const std::string region = cell("region");
    if (region.empty()) throw InputError(file, line, column("region"), "region", "empty region");
    const double tol = number("tolerance");
    const bool has_uz = !cell("uz").empty(), has_u = !cell("u").empty();
    if (has_uz && has_u)
      throw InputError(file, line, column("u"), "u", "give either uz (ISO) or u (ASME), not both");
    ToleranceZone z;
    try {
      z = has_uz ? isoUzZone(tol, number("uz")) : has_u ? asmeUZone(tol, number("u")) : bilateralZone(tol);
    } catch (const std::invalid_argument& e) {
      throw InputError(file, line, column(has_u ? "u" : "tolerance"), has_u ? "u" : "tolerance", e.what());
    }
    if (region.rfind("box", 0) == 0) {
      std::istringstream in(region.substr(3));
      std::string tok;
      std::vector<double> v;
      while (in >> tok) {
        const auto x = parseNumber(tok);
        if (!x) throw InputError(file, line, column("region"), "region", "'" + tok + "' is not a number in the box");
        v.push_back(*x);
      }
      if (v.size() != 6)
        throw InputError(file, line, column("region"), "region", "a box needs six numbers: box x0 y0 z0 x1 y1 z1");
      z.has_box = true;
      z.box_w = Eigen::AlignedBox3d(Eigen::Vector3d(std::min(v[0], v[3]), std::min(v[1], v[4]), std::min(v[2], v[5])),
                                    Eigen::Vector3d(std::max(v[0], v[3]), std::max(v[1], v[4]), std::max(v[2], v[5])));
    }
    z.region = region;
    zones.push_back(z);
  }
  if (zones.empty()) throw InputError(file, 0, 0, "zones", "the file defines no zone");
  return zones;
}

std::vector<ToleranceZone> readZoneFile(const std::string& path) {
  return parseZoneCsv(readFile(path), path);
}

}  // namespace tolver
