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

// The one rule for a profile tolerance's size, wherever it is given (--tolerance, a zone file):
// above 1 mm it is more likely micrometres written as millimetres (30 for 0.030) than meant, and
// is refused unless confirmed (--tolerance-units mm). Throws InputError(file, line, column,
// "tolerance", ...).
void checkToleranceSize(double tolerance_mm, bool confirmed, const std::string& file, int line,
                        int column);

// Throws InputError naming file, line and column. large_confirmed: tolerances above 1 mm are
// meant (checkToleranceSize).
std::vector<ToleranceZone> parseZoneCsv(const std::string& text, const std::string& file,
                                        bool large_confirmed = false);
std::vector<ToleranceZone> readZoneFile(const std::string& path, bool large_confirmed = false);

}  // namespace tolver
