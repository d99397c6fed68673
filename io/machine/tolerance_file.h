#pragma once
// Tolerance files for allocation (CSV, '#' comments). Columns, by name:
//   term       a parameter name, ISO code or alias of the machine file (dx_x, EXX.c0, COY)
//   category   positional | linear_positioning | angular_positioning | linear_non_positioning |
//              angular_non_positioning   ([Cai] Table 3)
//   standard   the standard full tolerance band
//   unit       mm | um | rad | urad | mm/m | mm/<L>mm (a deviation over a length, e.g. mm/1000mm)
//   lower, upper (optional)  bounds of the band, same unit; default standard and 3 x standard
//   reference (optional)     a published allocation to compare with, same unit
//   reference_group (optional) a published correlation class (1, 2, ...)
#include <string>
#include <vector>

#include "core/allocation/tolerance_allocation.h"
#include "core/model/machine_model.h"

namespace tolver {

// Throws InputError naming file, line and column.
std::vector<ToleranceTerm> readToleranceFile(const std::string& path, const MachineModel& model);
std::vector<ToleranceTerm> parseToleranceCsv(const std::string& text, const std::string& file,
                                             const MachineModel& model);
const char* categoryName(ToleranceCategory c);

}  // namespace tolver
