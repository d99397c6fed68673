#pragma once
// Tool file (CSV, mm, '#' comments; header first): the geometry of the tools a posted program
// selects, for posts that write none in comments.
//
//   tool,type,diameter_mm,corner_radius_mm,length_mm
//   1,flat,10,0,40                 T1 (also written T1)
//   ENTFRAESER_D8_N_90GRAD,flat,8  a Sinumerik tool name (T="...")
//   2,ball,6,,30                   ball: the corner radius is half the diameter
//
// tool: the number (with or without its T) or the name, case-insensitive; type (optional): flat,
// ball or bull; corner_radius_mm and length_mm optional (0, and 3 diameters when absent).
#include <map>
#include <string>
#include <vector>

namespace tolver {

struct ToolEntry {
  std::vector<double> values;  // diameter, corner radius[, length] (mm): TLDATA's order
  int line = 0;
};

// Keys: "T<n>" for a number, the upper-case name otherwise. Throws InputError naming file, line
// and column.
std::map<std::string, ToolEntry> parseToolCsv(const std::string& text, const std::string& file);
std::map<std::string, ToolEntry> readToolFile(const std::string& path);

}  // namespace tolver
