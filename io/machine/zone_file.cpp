#include "io/machine/zone_file.h"

#include <sstream>
#include <stdexcept>

#include "core/numerics/quantities.h"
#include "io/common/io_error.h"
#include "io/common/text_util.h"

namespace tolver {

void checkToleranceSize(double tolerance_mm, bool confirmed, const std::string& file, int line,
                        int column) {
  const std::string problem = outOfRange(Quantity::ProfileTolerance, tolerance_mm, confirmed);
  if (problem.empty()) return;
  throw InputError(file, line, column, "tolerance",
                   problem + (tolerance_mm > rangeOf(Quantity::ProfileTolerance).hi
                                  ? ": give --tolerance-units mm to confirm it"
                                  : ""));
}

std::vector<ToleranceZone> parseZoneCsv(const std::string& text, const std::string& file,
                                        bool large_confirmed) {
  std::vector<ToleranceZone> zones;
  forEachCsvRow(
      text, file, {"region", "tolerance"}, "missing column (header: region,tolerance,uz,u)",
      [&](const CsvRow& row) {
        const int line = row.line;
        auto cell = [&](const char* name) { return row.cell(name); };
        auto column = [&](const char* name) { return row.column(name); };
        auto number = [&](const char* name) {
          const auto v = parseNumber(cell(name));
          if (!v)
            throw InputError(file, line, column(name), name,
                             "'" + cell(name) + "' is not a number");
          return *v;
        };
        const std::string region = cell("region");
        if (region.empty())
          throw InputError(file, line, column("region"), "region", "empty region");
        const double tol = number("tolerance");
        checkToleranceSize(tol, large_confirmed, file, line, column("tolerance"));
        const bool has_uz = !cell("uz").empty(), has_u = !cell("u").empty();
        if (has_uz && has_u)
          throw InputError(file, line, column("u"), "u",
                           "give either uz (ISO) or u (ASME), not both");
        ToleranceZone z;
        try {
          z = has_uz  ? isoUzZone(tol, number("uz"))
              : has_u ? asmeUZone(tol, number("u"))
                      : bilateralZone(tol);
        } catch (const std::invalid_argument& e) {
          throw InputError(file, line, column(has_u ? "u" : "tolerance"), has_u ? "u" : "tolerance",
                           e.what());
        }
        if (region.rfind("box", 0) == 0) {
          std::istringstream in(region.substr(3));
          std::string tok;
          std::vector<double> v;
          while (in >> tok) {
            const auto x = parseNumber(tok);
            if (!x)
              throw InputError(file, line, column("region"), "region",
                               "'" + tok + "' is not a number in the box");
            v.push_back(*x);
          }
          if (v.size() != 6)
            throw InputError(file, line, column("region"), "region",
                             "a box needs six numbers: box x0 y0 z0 x1 y1 z1");
          z.has_box = true;
          z.box_w = Eigen::AlignedBox3d(
              Eigen::Vector3d(std::min(v[0], v[3]), std::min(v[1], v[4]), std::min(v[2], v[5])),
              Eigen::Vector3d(std::max(v[0], v[3]), std::max(v[1], v[4]), std::max(v[2], v[5])));
        }
        z.region = region;
        zones.push_back(z);
      });
  if (zones.empty()) throw InputError(file, 0, 0, "zones", "the file defines no zone");
  return zones;
}

std::vector<ToleranceZone> readZoneFile(const std::string& path, bool large_confirmed) {
  return parseZoneCsv(readFile(path), path, large_confirmed);
}

}  // namespace tolver
