#include "io/machine/tolerance_file.h"

#include <cmath>

#include "core/numerics/units.h"
#include "io/common/io_error.h"
#include "io/common/text_util.h"

namespace tolver {

const char* categoryName(ToleranceCategory c) {
  switch (c) {
    case ToleranceCategory::Positional:
      return "positional";
    case ToleranceCategory::LinearPositioning:
      return "linear_positioning";
    case ToleranceCategory::AngularPositioning:
      return "angular_positioning";
    case ToleranceCategory::LinearNonPositioning:
      return "linear_non_positioning";
    case ToleranceCategory::AngularNonPositioning:
      return "angular_non_positioning";
  }
  return "?";
}

std::vector<ToleranceTerm> parseToleranceCsv(const std::string& text, const std::string& file,
                                             const MachineModel& m) {
  std::vector<ToleranceTerm> out;
  forEachCsvRow(
      text, file, {"term", "category", "standard", "unit"}, "missing column",
      [&](const CsvRow& row) {
        const int line = row.line;
        auto cell = [&](const char* name) { return row.cell(name); };
        ToleranceTerm term;
        term.name = cell("term");
        term.parameter = m.findParameter(term.name);
        if (term.parameter < 0)
          throw InputError(file, line, 0, "term", "no parameter named '" + term.name + "'");
        const std::string cat = cell("category");
        bool found = false;
        for (ToleranceCategory k :
             {ToleranceCategory::Positional, ToleranceCategory::LinearPositioning,
              ToleranceCategory::AngularPositioning, ToleranceCategory::LinearNonPositioning,
              ToleranceCategory::AngularNonPositioning})
          if (cat == categoryName(k)) {
            term.category = k;
            found = true;
          }
        if (!found) throw InputError(file, line, 0, "category", "unknown category '" + cat + "'");
        const std::string unit = cell("unit");
        const bool angular = m.parameters[term.parameter].angular;
        double scale = 0.0;
        if (!angular && unit == "mm")
          scale = 1.0;
        else if (!angular && unit == "um")
          scale = umToMm(1.0);
        else if (angular && unit == "rad")
          scale = 1.0;
        else if (angular && unit == "urad")
          scale = 1e-6;
        else if (angular && unit == "mm/m")
          scale = 1e-3;
        else if (angular && unit.rfind("mm/", 0) == 0 && unit.size() > 5 &&
                 unit.substr(unit.size() - 2) == "mm") {
          const auto len = parseNumber(unit.substr(3, unit.size() - 5));
          if (len && *len > 0) scale = 1.0 / *len;
        }
        if (scale == 0.0)
          throw InputError(file, line, 0, "unit",
                           "'" + unit + "' does not suit " + (angular ? "an angular" : "a linear") +
                               " term (mm, um / rad, urad, mm/m, mm/<L>mm)");
        auto number = [&](const char* name, double fallback) {
          const std::string s = cell(name);
          if (s.empty()) {
            if (fallback >= 0) return fallback;
            throw InputError(file, line, 0, name, "missing value");
          }
          const auto v = parseNumber(s);
          if (!v || !(*v > 0))
            throw InputError(file, line, 0, name, "expected a positive number, found '" + s + "'");
          // A tolerance is a machine's: at most 10 mm, or 10 mrad.
          const double limit = angular ? 0.01 : 10.0;
          if (*v * scale > limit)
            throw InputError(file, line, 0, name,
                             "'" + s + "' " + unit + " is beyond any machine tolerance (at most " +
                                 (angular ? "10 mrad" : "10 mm") + ")");
          return *v * scale;
        };
        term.standard = number("standard", -1);
        term.lower = number("lower", term.standard);
        term.upper = number("upper", 3.0 * term.standard);
        if (!cell("reference").empty()) term.reference = number("reference", -1);
        if (!cell("reference_group").empty()) {
          const auto g = parseNumber(cell("reference_group"));
          if (!g || *g < 1 || *g != std::floor(*g) || *g > 1e6)
            throw InputError(file, line, 0, "reference_group",
                             "expected a whole number from 1 to 1000000");
          term.reference_group = static_cast<int>(*g);
        }
        if (!(term.lower <= term.standard || term.lower <= term.upper) || term.lower > term.upper)
          throw InputError(file, line, 0, "upper", "upper bound below the lower bound");
        if (!(term.upper > term.lower * (1.0 + 1e-9)))
          throw InputError(file, line, 0, "upper",
                           "the band from lower to upper is empty: nothing to allocate");
        for (const ToleranceTerm& o : out)
          if (o.parameter == term.parameter)
            throw InputError(file, line, 0, "term", "term given twice");
        out.push_back(term);
      });
  if (out.empty()) throw InputError(file, 0, 0, "", "no terms");
  return out;
}

std::vector<ToleranceTerm> readToleranceFile(const std::string& path, const MachineModel& m) {
  return parseToleranceCsv(readFile(path), path, m);
}

}  // namespace tolver
