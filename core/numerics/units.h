#pragma once
// Units, written once. Inside the code lengths are mm and angles rad; reports give um and urad;
// degrees only where a file or the user says so (NC words, set-up files, options ending _deg).
#include <numbers>

namespace tolver {

constexpr double kPi = std::numbers::pi;

// deg * pi / 180 and rad * 180 / pi, the products the readers and writers always used.
constexpr double degToRad(double deg) { return deg * kPi / 180.0; }
constexpr double radToDeg(double rad) { return rad * 180.0 / kPi; }
constexpr double mmToUm(double mm) { return mm * 1e3; }
constexpr double umToMm(double um) { return um * 1e-3; }
constexpr double radToUrad(double rad) { return rad * 1e6; }
constexpr double uradToRad(double urad) { return urad * 1e-6; }
constexpr double inchToMm(double inch) { return inch * 25.4; }

}  // namespace tolver
