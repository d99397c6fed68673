#pragma once
// An independent machining simulation, for judging tolver measure on data its own code did not
// generate: its own reading of an APT file's GOTO lines, its own placements (0.02 mm apart,
// linear in the tip and the axis: a three-axis program's moves are exactly that), and its own
// envelope of a ball-end cutter: the material left along a line p + s n is where that line first
// enters a ball, over every placement (a hash grid of the balls' centres; no code of tolver's
// sweep). Process effects: the ball's radius (its length preset to the tip), the tool's length,
// the part's pose on the table, the spindle's thermal growth along the program's own clock (its
// FEDRAT words, rapids at 10 m/min), the cutter pushed sideways of its feed. Used by
// tests/measure_test.cpp and tools/make_measured_sample.cpp.
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "geometry/triangle_mesh.h"

namespace indep_cut {

struct Ball {
  Eigen::Vector3d centre;
};

struct Effect {
  double radius_error_mm = 0;  // the ball's true radius is R + this (its tip preset)
  double length_error_mm = 0;  // the tool's true length is longer by this: tip further out
  Eigen::Isometry3d part_error = Eigen::Isometry3d::Identity();  // the part's true pose on the
                                                                 // table, in the part frame
  // Outside any candidate of measure's: the ball's centre waves along z with x (a screw's
  // periodic error of the machine's X), amplitude mm and period mm.
  double wave_mm = 0, wave_period_mm = 10;
  double drift_mm_per_h = 0;        // the tool grows along its axis at this rate from the start
  double deflection_across_mm = 0;  // the ball pushed along a x f (f the move's direction)
  // A machine's error the calibration missed: the tool's displacement from the programmed tip
  // (part frame, mm), written as a formula in the test (e.g. an axis's scale error).
  std::function<Eigen::Vector3d(const Eigen::Vector3d&)> machine_error;
};

// GOTO/x,y,z[,i,j,k] lines of an APT file (the axis modal, +z at first); a GOTO after RAPID is a
// rapid move (not cut).
struct Cl {
  Eigen::Vector3d tip, axis;
  bool rapid;
  double feed_mm_min = 0;  // the last FEDRAT/MMPM before it (0: none)
};
inline std::vector<Cl> readGotos(const std::string& path) {
  std::ifstream in(path);
  std::vector<Cl> out;
  std::string line;
  bool rapid = false;
  double feed = 0;
  while (std::getline(in, line)) {
    if (line.rfind("RAPID", 0) == 0) rapid = true;
    if (line.rfind("FEDRAT/MMPM,", 0) == 0) feed = std::stod(line.substr(12));
    if (line.rfind("GOTO/", 0) != 0) continue;
    std::stringstream ss(line.substr(5));
    double v[6] = {0, 0, 0, 0, 0, 1};  // GOTO/x,y,z: the tool axis as before
    if (!out.empty())
      v[3] = out.back().axis.x(), v[4] = out.back().axis.y(), v[5] = out.back().axis.z();
    std::string cell;
    for (int k = 0; k < 6 && std::getline(ss, cell, ','); ++k) v[k] = std::stod(cell);
    out.push_back({Eigen::Vector3d(v[0], v[1], v[2]),
                   Eigen::Vector3d(v[3], v[4], v[5]).normalized(), rapid, feed});
    rapid = false;
  }
  return out;
}

class Simulator {
 public:
  Simulator(const std::vector<Cl>& cl, double radius, const Effect& e)
      : r_(radius + e.radius_error_mm) {
    // The part sits at part_error on the table: the path the machine runs, seen from the part,
    // is the inverse of that pose applied to the programmed one.
    const Eigen::Isometry3d inv = e.part_error.inverse();
    double clock_h = 0;  // when the tool reaches cl[i - 1]
    for (size_t i = 1; i < cl.size(); ++i) {
      const double len = (cl[i].tip - cl[i - 1].tip).norm();
      const double move_h = len / (cl[i].rapid ? 10000.0 : cl[i].feed_mm_min) / 60.0;
      if (cl[i].rapid) {
        clock_h += move_h;
        continue;
      }
      const Eigen::Vector3d f =
          len > 0 ? Eigen::Vector3d((cl[i].tip - cl[i - 1].tip) / len) : Eigen::Vector3d::Zero();
      const int steps = std::max(1, static_cast<int>(std::ceil(len / 0.02)));
      for (int k = 0; k <= steps; ++k) {
        const double t = static_cast<double>(k) / steps;
        const Eigen::Vector3d a = ((1 - t) * cl[i - 1].axis + t * cl[i].axis).normalized();
        const double grown = e.drift_mm_per_h * (clock_h + t * move_h);
        const Eigen::Vector3d tip = (1 - t) * cl[i - 1].tip + t * cl[i].tip -
                                    (e.length_error_mm + grown) * a +
                                    e.deflection_across_mm * a.cross(f);
        const Eigen::Vector3d moved = e.machine_error ? tip + e.machine_error(tip) : tip;
        Eigen::Vector3d c = inv * (moved + r_ * a);
        c.z() += e.wave_mm * std::sin(2 * M_PI * c.x() / e.wave_period_mm);
        balls_[key(c)].push_back({c});
      }
      clock_h += move_h;
    }
  }
  // The machined surface along p + s n (n outward): the smallest s where the line enters a ball,
  // within [-range, range]; NAN when none reaches it.
  double surface(const Eigen::Vector3d& p, const Eigen::Vector3d& n, double range) const {
    double best = INFINITY;
    const int reach = static_cast<int>(std::ceil((r_ + range) / kCell));
    const std::array<int, 3> k0 = cell(p);
    for (int dx = -reach; dx <= reach; ++dx)
      for (int dy = -reach; dy <= reach; ++dy)
        for (int dz = -reach; dz <= reach; ++dz) {
          const auto it = balls_.find(pack({k0[0] + dx, k0[1] + dy, k0[2] + dz}));
          if (it == balls_.end()) continue;
          for (const Ball& b : it->second) {
            const Eigen::Vector3d d = p - b.centre;
            const double bb = d.dot(n), cc = d.squaredNorm() - r_ * r_;
            const double disc = bb * bb - cc;
            if (disc < 0) continue;
            const double s = -bb - std::sqrt(disc);
            if (s >= -range && s <= range) best = std::min(best, s);
          }
        }
    return std::isfinite(best) ? best : NAN;
  }

 private:
  static constexpr double kCell = 2.0;
  static std::array<int, 3> cell(const Eigen::Vector3d& p) {
    return {static_cast<int>(std::floor(p.x() / kCell)),
            static_cast<int>(std::floor(p.y() / kCell)),
            static_cast<int>(std::floor(p.z() / kCell))};
  }
  static long long pack(const std::array<int, 3>& k) {
    return ((static_cast<long long>(k[0]) + 100000) * 200000 + (k[1] + 100000)) * 200000 +
           (k[2] + 100000);
  }
  static long long key(const Eigen::Vector3d& p) { return pack(cell(p)); }
  double r_;
  std::map<long long, std::vector<Ball>> balls_;
};

// Points on the part's faces (area-weighted), measured on the simulated part: the foot moved
// along the face's normal to the machined surface, plus probe noise. Points the simulator does
// not machine, or within 1.5 mm of the part's border, are not measured.
// times > 1: each place measured that many times (the noise drawn again each time).
inline std::string measuredCsv(const tolver::TriangleMesh& mesh, const Simulator& sim, int count,
                               unsigned seed, double noise_mm, int times = 1) {
  std::mt19937 rng(seed);
  std::vector<double> cum;
  double total = 0;
  for (size_t f = 0; f < mesh.faces.size(); ++f) cum.push_back(total += mesh.faceArea(f));
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> g(0, noise_mm);
  std::string out = "# simulated CMM points\nx_mm,y_mm,z_mm,nx,ny,nz\n";
  int made = 0;
  for (int tries = 0; made < count && tries < 50 * count; ++tries) {
    const size_t f = std::lower_bound(cum.begin(), cum.end(), u(rng) * total) - cum.begin();
    const Eigen::Vector3i& t = mesh.faces[f];
    double a = u(rng), b = u(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    const Eigen::Vector3d p = mesh.vertices[t[0]] +
                              a * (mesh.vertices[t[1]] - mesh.vertices[t[0]]) +
                              b * (mesh.vertices[t[2]] - mesh.vertices[t[0]]);
    const Eigen::Vector3d n = mesh.faceNormal(static_cast<int>(f));
    if (n.z() < 0.3) continue;  // the sculptured top only (the finish cuts nothing else)
    if (std::abs(p.x()) > 38 || std::abs(p.y()) > 28) continue;  // clear of the border
    const double s = sim.surface(p, n, 0.2);
    if (std::isnan(s)) continue;
    for (int k = 0; k < times; ++k) {
      const Eigen::Vector3d q = p + (s + g(rng)) * n;
      char line[200];
      std::snprintf(line, sizeof line, "%.6f,%.6f,%.6f,%.9f,%.9f,%.9f\n", q.x(), q.y(), q.z(),
                    n.x(), n.y(), n.z());
      out += line;
    }
    made += times;
  }
  return out;
}

// The sculptured finish as a three-axis program: the same ball centres with the tool upright (a
// ball's envelope depends on its centre's path alone), so joint-linear moves are CL-linear and
// the part's slopes let the ball's radius show (-(1 - n.z) per unit of radius).
inline std::string threeAxisProgram(const std::vector<Cl>& cl, double radius) {
  std::string out =
      "PARTNO/SCULPTURED_3AXIS\nUNITS/MM\nTOOL PATH/FINISH_3AXIS,TOOL,BALL_MILL_D10\n"
      "CUTTER/10,5,0,0,0,0,40\nLOADTL/1\n"
      "SPINDL/RPM,8000,CLW\n";
  for (const Cl& c : cl) {
    const Eigen::Vector3d tip = c.tip + radius * c.axis - radius * Eigen::Vector3d::UnitZ();
    if (c.rapid) out += "RAPID\n";
    char line[120];
    std::snprintf(line, sizeof line, "GOTO/%.6f,%.6f,%.6f\n", tip.x(), tip.y(), tip.z());
    out += line;
    if (c.rapid) out += "FEDRAT/MMPM,2000\n";
  }
  return out;
}

inline std::vector<Cl> upright(std::vector<Cl> cl, double radius) {
  for (Cl& c : cl) {
    c.tip += radius * c.axis - radius * Eigen::Vector3d::UnitZ();
    c.axis = Eigen::Vector3d::UnitZ();
  }
  return cl;
}

}  // namespace indep_cut
