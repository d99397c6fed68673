#include "io/program/setup_file.h"

#include <cctype>
#include <cmath>
#include <sstream>

#include "core/numerics/quantities.h"
#include "core/numerics/units.h"
#include "io/common/io_error.h"
#include "io/common/text_util.h"

namespace tolver {

PartSetup parseSetup(const std::string& text, const std::string& file_name, PartSetup s) {
  const auto lines = splitLines(text);
  for (size_t i = 0; i < lines.size(); ++i) {
    std::string_view l = lines[i];
    if (i == 0 && l.substr(0, 3) == "\xEF\xBB\xBF") l.remove_prefix(3);  // a UTF-8 byte-order mark
    const size_t hash = l.find('#');
    if (hash != std::string_view::npos) l = l.substr(0, hash);
    l = trim(l);
    if (l.empty()) continue;
    const int line = static_cast<int>(i) + 1;
    const size_t eq = l.find('=');
    if (eq == std::string_view::npos)
      throw InputError(file_name, line, 0, "", "expected 'key = value'");
    const std::string key(trim(l.substr(0, eq)));
    std::string value(trim(l.substr(eq + 1)));
    for (char& c : value)
      if (c == ',') c = ' ';
    std::vector<double> v;
    std::istringstream in(value);
    std::string tok;
    while (in >> tok) {
      auto x = parseNumber(tok);
      if (!x) throw InputError(file_name, line, 0, key, "malformed number '" + tok + "'");
      v.push_back(*x);
    }
    auto need = [&](size_t n) {
      if (v.size() != n)
        throw InputError(
            file_name, line, 0, key,
            "expected " + std::to_string(n) + " value(s), found " + std::to_string(v.size()));
    };
    // Each value in its quantity's range, as the command line's (core/numerics/quantities.h).
    auto within = [&](Quantity q) {
      for (double x : v)
        if (const std::string problem = outOfRange(q, x); !problem.empty())
          throw InputError(file_name, line, 0, key, problem);
    };
    const std::string lower = toLower(key);
    if (key == "part_zero_mm") {
      need(3);
      within(Quantity::Position);
      s.part_zero_table = Eigen::Vector3d(v[0], v[1], v[2]);
      s.part_zero_given = true;
    } else if (key == "part_rotation_deg") {
      need(1);
      within(Quantity::PartRotation);
      s.part_rotation = degToRad(v[0]);
      s.part_rotation_given = true;
    } else if (key == "gauge_length_mm") {
      need(1);
      within(Quantity::Length);
      s.gauge_length = v[0];
      s.gauge_length_given = true;
    } else if (lower.size() > 4 && lower[0] == 'g' &&
               lower.compare(lower.size() - 3, 3, "_mm") == 0 &&
               std::isdigit(static_cast<unsigned char>(lower[1]))) {
      // Work offset: g54_mm, g55_mm, g54.1p1_mm, g59.3_mm = x, y, z (machine coordinates).
      need(3);
      within(Quantity::Position);
      s.work_offsets[toUpper(lower.substr(0, lower.size() - 3))] =
          Eigen::Vector3d(v[0], v[1], v[2]);
    } else if (lower.rfind("tool_h", 0) == 0 && lower.size() > 9 &&
               lower.compare(lower.size() - 3, 3, "_mm") == 0) {
      // Tool length of an H number: tool_h2_mm = 100.5.
      need(1);
      const auto h = parseNumber(lower.substr(6, lower.size() - 9));
      if (!h || *h < 0 || *h != std::floor(*h) || *h > 9999)
        throw InputError(file_name, line, 0, key,
                         "expected tool_hN_mm with a whole number N from 0 to 9999");
      within(Quantity::Length);
      s.tool_lengths[static_cast<int>(*h)] = v[0];
    } else {
      throw InputError(file_name, line, 0, key,
                       "unknown key (expected part_zero_mm, part_rotation_deg, gauge_length_mm, "
                       "g54_mm ... g59_mm, tool_hN_mm)");
    }
  }
  return s;
}

PartSetup readSetupFile(const std::string& path, PartSetup base) {
  return parseSetup(readFile(path), path, base);
}

}  // namespace tolver
