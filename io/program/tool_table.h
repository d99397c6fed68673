#pragma once
// LinuxCNC's tool table (LinuxCNC documentation, "Tool Table Format"): one tool a line,
//
//   T1 P1 Z0.511 D0.125 ;1/8 end mill
//
// T (the tool number) and P (its pocket) first, then any of X Y Z A B C U V W (offsets), D (the
// diameter), I J (lathe angles), Q (lathe orientation); ';' starts a comment. Lengths are in the
// machine's units (the INI's LINEAR_UNITS: the machine file's control default_units). Used for
// the diameter G41/G42 compensate by (io/program/gcode_reader.h, tool_diameter_mm).
#include <map>
#include <string>

namespace tolver {

// Per tool number, the diameter in mm (unit_mm: mm per unit of the table); NaN for a lathe tool
// (Q other than 0 and 9), whose compensation differs. Throws InputError
// naming file, line, column and word.
std::map<int, double> parseLinuxCncToolTable(const std::string& text, const std::string& file,
                                             double unit_mm);
std::map<int, double> readLinuxCncToolTable(const std::string& path, double unit_mm);

}  // namespace tolver
