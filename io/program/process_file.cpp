#include "io/program/process_file.h"

#include <cctype>
#include <cmath>
#include <sstream>

#include "io/common/io_error.h"
#include "io/common/text_util.h"

namespace tolver {
namespace {

// "cutter_radius_T3_dR_mm" -> tool 2 and the rest "dR_mm"; no T<k>: tool 0.
int toolOf(const std::string& rest, std::string* tail) {
  if (rest.size() > 1 && rest[0] == 'T' && std::isdigit(static_cast<unsigned char>(rest[1]))) {
    size_t i = 1;
    int k = 0;
    while (i < rest.size() && std::isdigit(static_cast<unsigned char>(rest[i])) && k < 100000)
      k = 10 * k + (rest[i++] - '0');
    if (k >= 100000 || (i < rest.size() && rest[i] != '_')) return -1;  // not a tool number
    *tail = i < rest.size() ? rest.substr(i + 1) : "";
    return k - 1;
  }
  *tail = rest;
  return 0;
}

}  // namespace

ProcessCorrections parseProcessFile(const std::string& text, const std::string& file) {
  ProcessCorrections c;
  Eigen::Vector3d t = Eigen::Vector3d::Zero(), w = Eigen::Vector3d::Zero();
  const std::vector<std::string> lines = splitLines(text);
  for (size_t i = 0; i < lines.size(); ++i) {
    std::string l = lines[i];
    if (const size_t h = l.find('#'); h != std::string::npos) l.resize(h);
    const std::string_view tl = trim(l);
    if (tl.empty()) continue;
    const int line = static_cast<int>(i) + 1;
    const size_t sp = tl.find_first_of(" \t");
    if (sp == std::string_view::npos)
      throw InputError(file, line, 1, std::string(tl), "expected 'key value'");
    const std::string key(tl.substr(0, sp));
    const std::string value(trim(tl.substr(sp + 1)));
    const auto v = parseNumber(value);
    if (!v)
      throw InputError(file, line, static_cast<int>(sp) + 2, key,
                       "'" + value + "' is not a number");
    if (!(std::abs(*v) <= 1.0))
      throw InputError(file, line, static_cast<int>(sp) + 2, key,
                       "'" + value + "' is beyond 1 mm or 1 rad: not a correction");
    static const char* setup_keys[6] = {"set-up_x_mm",        "set-up_y_mm",
                                        "set-up_z_mm",        "set-up_about_x_rad",
                                        "set-up_about_y_rad", "set-up_about_z_rad"};
    bool done = false;
    for (int k = 0; k < 6; ++k)
      if (key == setup_keys[k]) {
        (k < 3 ? t : w)[k % 3] = *v;
        done = true;
      }
    if (done) continue;
    std::string tail;
    if (key.rfind("cutter_radius_", 0) == 0) {
      const int tool = toolOf(key.substr(14), &tail);
      if (tail == "dR_mm" && tool >= 0) {
        c.radius_mm[tool] = *v;
        continue;
      }
    } else if (key.rfind("tool_length_", 0) == 0) {
      const int tool = toolOf(key.substr(12), &tail);
      if (tail == "dL_mm" && tool >= 0) {
        c.length_mm[tool] = *v;
        continue;
      }
    } else if (key == "thermal_drift_spindle_growth_mm/h") {
      c.drift_mm_per_h = *v;
      continue;
    } else if (key.rfind("tool_deflection_", 0) == 0) {
      const int tool = toolOf(key.substr(16), &tail);
      if (tail == "across_the_feed_mm" && tool >= 0) {
        c.across_feed_mm[tool] = *v;
        continue;
      }
      if (tail == "off_the_surface_mm" && tool >= 0) {
        c.not_applied.push_back(key);
        continue;
      }
    } else if (key.rfind("stock_", 0) == 0 || key.rfind("tool_offset_", 0) == 0 ||
               key.rfind("machine_", 0) == 0) {
      c.not_applied.push_back(key);
      continue;
    }
    throw InputError(file, line, 1, key,
                     "unknown key (set-up_*, cutter_radius_*, tool_length_*, "
                     "thermal_drift_*, tool_deflection_*, stock_*, tool_offset_*, machine_*)");
  }
  c.part_error.linear() = (Eigen::AngleAxisd(w.z(), Eigen::Vector3d::UnitZ()) *
                           Eigen::AngleAxisd(w.y(), Eigen::Vector3d::UnitY()) *
                           Eigen::AngleAxisd(w.x(), Eigen::Vector3d::UnitX()))
                              .toRotationMatrix();
  c.part_error.translation() = t;
  return c;
}

ProcessCorrections readProcessFile(const std::string& path) {
  return parseProcessFile(readFile(path), path);
}

}  // namespace tolver
