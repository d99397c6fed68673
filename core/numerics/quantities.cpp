#include "core/numerics/quantities.h"

#include <charconv>
#include <cmath>
#include <limits>

namespace tolver {
namespace {

// The shortest text that reads back as v; whole numbers written out (100000, not 1e+05).
std::string shortest(double v) {
  char buf[400];
  const bool whole = std::isfinite(v) && v == std::floor(v) && std::abs(v) < 1e15;
  const auto r = whole ? std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed)
                       : std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

}  // namespace

QuantityRange rangeOf(Quantity q) {
  switch (q) {
    case Quantity::Position:
      return {-1e5, 1e5, false, "mm", "a position"};
    case Quantity::Length:
      return {0.0, 1e5, false, "mm", "a gauge or tool length"};
    case Quantity::BarLength:
      return {0.0, 1e5, true, "mm", "a bar length"};
    case Quantity::PartRotation:
      return {-360.0, 360.0, false, "deg", "a part rotation"};
    case Quantity::ProfileTolerance:
      return {0.0, 1.0, true, "mm", "a profile tolerance"};
    case Quantity::SpindleTilt:
      return {0.0, 1e5, false, "urad", "a spindle tilt"};
  }
  return {0.0, 0.0, false, "", ""};
}

std::string outOfRange(Quantity q, double v, bool confirmed) {
  const QuantityRange r = rangeOf(q);
  const double hi =
      q == Quantity::ProfileTolerance && confirmed ? std::numeric_limits<double>::infinity() : r.hi;
  const bool inside = std::isfinite(v) && (r.lo_open ? v > r.lo : v >= r.lo) && v <= hi;
  if (inside) return "";
  std::string expected = std::string("expected ") + r.what + " ";
  if (q == Quantity::ProfileTolerance) {
    // The usual slip is a tolerance in um given as mm: say so.
    if (std::isfinite(v) && v > r.hi)
      return shortest(v) + " mm is not a plausible profile tolerance: tolerances are in mm (" +
             shortest(v / 1000.0) + " for " + shortest(v) + " um)";
    expected += confirmed ? "above 0 mm" : "above 0 and up to 1 mm";
  } else if (r.lo_open) {
    expected += "above " + shortest(r.lo) + " and up to " + shortest(r.hi) + " " + r.unit;
  } else {
    expected += "from " + shortest(r.lo) + " to " + shortest(r.hi) + " " + r.unit;
  }
  return expected + ", found " + shortest(v);
}

}  // namespace tolver
