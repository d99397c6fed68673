#pragma once
// The range policy: one accepted range per physical quantity, applied wherever a value of that
// quantity enters tolver (a command-line option through the pipeline's inputs, a file's field, a
// library function's input), so that a value refused on the command line is refused in a file
// and the other way round. Lengths in mm, angles in deg (as files and options give them).
//
// The ranges are generous bounds of what a machine tool and its part can be, not tolerances: a
// value beyond them is a unit slip or a damaged file (a part offset of 10^7 mm, a 900 mm profile
// tolerance), and running on it would give a report that looks valid.
#include <string>

namespace tolver {

enum class Quantity {
  Position,          // a point or offset in a machine or part frame: |v| <= 1e5 mm
  Length,            // a gauge or tool length: 0 <= v <= 1e5 mm
  BarLength,         // a ball-bar's length: 0 < v <= 1e5 mm
  PartRotation,      // the part's rotation on the table: |v| <= 360 deg
  ProfileTolerance,  // a profile tolerance zone's width: 0 < v <= 1 mm unless confirmed
  SpindleTilt,  // the spindle's tilt a ball-bar cannot see (its standard deviation): 0 to 1e5 urad
};

struct QuantityRange {
  double lo, hi;
  bool lo_open;      // lo itself is refused (a length that must be positive)
  const char* unit;  // "mm", "deg" or "urad"
  const char* what;  // "a position", ... (for the message)
};

QuantityRange rangeOf(Quantity q);

// Empty when v is finite and inside q's range; otherwise one clause saying what was expected and
// what was found ("expected a gauge or tool length from 0 to 1e5 mm, found -3").
// ProfileTolerance: confirmed lifts the 1 mm bound (a tolerance meant in mm above 1 mm); above
// it, the clause says what the value would be if meant in um (callers say how to confirm).
std::string outOfRange(Quantity q, double v, bool confirmed = false);

}  // namespace tolver
