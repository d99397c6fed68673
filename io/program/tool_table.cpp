#include "io/program/tool_table.h"

#include <cctype>
#include <cmath>
#include <optional>
#include <sstream>

#include "io/common/io_error.h"
#include "io/common/text_util.h"

namespace tolver {

std::map<int, double> parseLinuxCncToolTable(const std::string& text, const std::string& file,
                                             double unit_mm) {
  std::map<int, double> diameters;
  std::map<int, int> line_of;
  std::istringstream in(text);
  int line = 0;
  for (std::string raw; std::getline(in, raw);) {
    ++line;
    const std::string body = raw.substr(0, raw.find(';'));
    std::optional<int> tool;
    double diameter = 0;
    bool lathe = false;
    size_t i = 0;
    while (i < body.size()) {
      if (std::isspace(static_cast<unsigned char>(body[i]))) {
        ++i;
        continue;
      }
      const int column = static_cast<int>(i) + 1;
      const char letter = static_cast<char>(std::toupper(static_cast<unsigned char>(body[i])));
      size_t end = i + 1;
      while (end < body.size() && !std::isspace(static_cast<unsigned char>(body[end]))) ++end;
      const std::string value = body.substr(i + 1, end - i - 1);
      const std::string word(1, letter);
      if (std::string("TPXYZABCUVWDIJQ").find(letter) == std::string::npos)
        throw InputError(file, line, column, word,
                         "not a word of LinuxCNC's tool table (T P X Y Z A B C U V W D I J Q)");
      const auto v = parseNumber(value);
      if (!v || !std::isfinite(*v))
        throw InputError(file, line, column, word, "expected a number, found '" + value + "'");
      if (letter == 'T') {
        if (*v < 0 || *v != std::floor(*v) || *v > 1e9)
          throw InputError(file, line, column, word, "the tool number must be a whole number");
        tool = static_cast<int>(*v);
      } else if (letter == 'Q') {
        lathe = *v != 0 && *v != 9;  // a lathe tool's orientation
      } else if (letter == 'D') {
        if (std::abs(*v) > 1e4)
          throw InputError(file, line, column, word, "implausible diameter '" + value + "'");
        diameter = *v;
      }
      i = end;
    }
    if (!tool) {
      if (trim(body).empty()) continue;
      throw InputError(file, line, 1, "T", "a tool line starts with T<number>");
    }
    if (line_of.count(*tool))
      throw InputError(file, line, 1, "T",
                       "tool " + std::to_string(*tool) + " is already on line " +
                           std::to_string(line_of[*tool]));
    line_of[*tool] = line;
    diameters[*tool] = lathe ? NAN : diameter * unit_mm;
  }
  if (diameters.empty()) throw InputError(file, 0, 0, "", "no tools in the tool table");
  return diameters;
}

std::map<int, double> readLinuxCncToolTable(const std::string& path, double unit_mm) {
  return parseLinuxCncToolTable(readFile(path), path, unit_mm);
}

}  // namespace tolver
