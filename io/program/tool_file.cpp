#include "io/program/tool_file.h"

#include <cctype>

#include "io/common/io_error.h"
#include "io/common/text_util.h"

namespace tolver {

std::map<std::string, ToolEntry> parseToolCsv(const std::string& text, const std::string& file) {
  std::map<std::string, ToolEntry> tools;
  forEachCsvRow(text, file, {"tool", "diameter_mm"},
                "missing column (header: tool,type,diameter_mm,corner_radius_mm,length_mm)",
                [&](const CsvRow& row) {
                  auto number = [&](const char* name, bool required) -> double {
                    const std::string c = row.cell(name);
                    if (c.empty() && !required) return -1.0;
                    const auto v = parseNumber(c);
                    if (!v || *v < 0 || *v > 1e4)
                      throw InputError(file, row.line, row.column(name), name,
                                       "expected a length from 0 to 10000 mm, found '" + c + "'");
                    return *v;
                  };
                  std::string key = toUpper(std::string(trim(row.cell("tool"))));
                  if (key.empty())
                    throw InputError(file, row.line, row.column("tool"), "tool", "empty tool");
                  bool digits = true;
                  for (char ch : key)
                    digits = digits && std::isdigit(static_cast<unsigned char>(ch));
                  if (digits) key = "T" + std::to_string(std::stol(key.substr(0, 9)));
                  const std::string type = toLower(std::string(trim(row.cell("type"))));
                  if (!type.empty() && type != "flat" && type != "ball" && type != "bull")
                    throw InputError(file, row.line, row.column("type"), "type",
                                     "expected flat, ball or bull, found '" + type + "'");
                  const double d = number("diameter_mm", true);
                  if (!(d > 0))
                    throw InputError(file, row.line, row.column("diameter_mm"), "diameter_mm",
                                     "the diameter must be positive");
                  double r = number("corner_radius_mm", false);
                  if (r < 0) r = type == "ball" ? d / 2 : 0.0;
                  if (r > d / 2 + 1e-9)
                    throw InputError(file, row.line, row.column("corner_radius_mm"),
                                     "corner_radius_mm",
                                     "the corner radius is larger than half the diameter");
                  ToolEntry e;
                  e.values = {d, r};
                  const double length = number("length_mm", false);
                  if (length > 0) e.values.push_back(length);
                  e.line = row.line;
                  if (tools.count(key))
                    throw InputError(file, row.line, row.column("tool"), "tool",
                                     "tool " + key + " is given twice");
                  tools[key] = e;
                });
  return tools;
}

std::map<std::string, ToolEntry> readToolFile(const std::string& path) {
  return parseToolCsv(readFile(path), path);
}

}  // namespace tolver
