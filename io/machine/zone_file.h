#pragma once
// Profile tolerance zones file (CSV, mm, '#' comments), one zone per row, header first:
//
//   region,tolerance,uz,u
//   *,0.05,,                            bilateral +-0.025 everywhere
//   top,0.02,+0.005,                    ISO 1101 UZ: zone centre 5 um towards material left
//   box 0 0 30 40 40 45,0.03,,0.01      ASME Y14.5 U: 10 um of the 30 um outside the material
//
// region: "*" (every sample), a region of the part mesh (an OBJ group, a glTF or 3MF mesh
// name), or "box x0 y0 z0 x1 y1 z1" (the samples inside an axis-aligned box of the part frame,
// mm). uz and u are optional and exclusive. A sample takes the last row that holds it.
#include <string>
#include <vector>

#include "geometry/tolerance_zone.h"

namespace tolver {

// Throws InputError naming file, line and column.
std::vector<ToleranceZone> parseZoneCsv(const std::string& text, const std::string& file);
std::vector<ToleranceZone> readZoneFile(const std::string& path);

}  // namespace tolver
