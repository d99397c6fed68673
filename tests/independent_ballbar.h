#pragma once
// A second, independent implementation of ball-bar readings on the Matsuura MC-760VX (ZFYXAC),
// for judging calibrate and diagnose on data their own code did not generate. It shares no code
// with tolver's model: the chains are written out from [AM01]'s description (Fig. 3.2,
// eq. 20-22), the motion errors are power polynomials (not Chebyshev series), the undeclared
// effects are closed-form functions of position, direction and time, and it writes its own CSV
// (with the approach directions the machine really had, including those of the held-out poses
// measured in between).
//
//   workpiece: F -> Y -> X -> A -> C -> w,   tool: F -> Z -> t,
//   each joint: motion (translation s d, or rotation by s about d) then its error
//   E = [Rz(gz) Ry(gy) Rx(gx), (ex, ey, ez)],  w_T_t = (F_T_w)^-1 F_T_t,
//   reading = | w_T_t b_t - b_w |.
// Only the poses come from elsewhere (any plan: they are inputs, not physics).
#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <string>
#include <vector>

namespace indep {

constexpr int kX = 0, kY = 1, kZ = 2, kA = 3, kC = 4;  // axis order of the machine file
constexpr double kTravelMin[5] = {-380, -255, -150, -120 * M_PI / 180, -M_PI};
constexpr double kTravelMax[5] = {380, 255, 360, 30 * M_PI / 180, M_PI};

// What the machine has that a cubic motion model lacks.
struct Undeclared {
  std::string type;             // "none", "reversal", "periodic", "harmonic", "straightness6",
                                // "warmup", "drift"
  int axis = 0, component = 0;  // component 0-2: ex ey ez (mm), 3-5: gx gy gz (rad)
  double amplitude = 0;         // mm or rad (reversal: the full reversal value)
  double period = 0;            // periodic: mm; harmonic: the order k; warmup: tau in s
  double phase = 0;
};

struct Pose {
  int setup = 0;      // 0-based
  double q[5] = {};   // mm, rad
  double t = 0;       // s since the test began
  int dir[5] = {};    // approach direction of each axis (+1 / -1)
  double length = 0;  // mm
  bool heldout = false;
};

struct Setup {
  int id = 1;
  Eigen::Vector3d table_ball_w, tool_ball_t;  // nominal
  Eigen::Vector3d table_error_w = Eigen::Vector3d::Zero(), tool_error_t = Eigen::Vector3d::Zero();
};

class Machine {
 public:
  // Base errors: a cubic polynomial in u = (s - mid) / half for each of the 6 components of
  // each of the 5 axes, coefficients ~ N(0, linear_um) and N(0, angular_urad).
  Machine(unsigned seed, double linear_um = 3.0, double angular_urad = 10.0) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> n(0.0, 1.0);
    for (int a = 0; a < 5; ++a)
      for (int c = 0; c < 6; ++c)
        for (int k = 0; k < 4; ++k)
          poly_[a][c][k] = n(rng) * (c < 3 ? linear_um * 1e-3 : angular_urad * 1e-6);
  }
  std::vector<Undeclared> effects;

  // The six error values of axis a at a pose.
  void errors(int a, const Pose& p, double e[6]) const {
    const double s = p.q[a];
    const double mid = 0.5 * (kTravelMin[a] + kTravelMax[a]),
                 half = 0.5 * (kTravelMax[a] - kTravelMin[a]);
    const double u = (s - mid) / half;
    for (int c = 0; c < 6; ++c)
      e[c] = poly_[a][c][0] + u * (poly_[a][c][1] + u * (poly_[a][c][2] + u * poly_[a][c][3]));
    for (const Undeclared& x : effects) {
      if (x.axis != a || x.type == "none") continue;
      double v = 0;
      if (x.type == "reversal")
        v = 0.5 * x.amplitude * p.dir[a];
      else if (x.type == "periodic")
        v = x.amplitude * std::sin(2 * M_PI * s / x.period + x.phase);
      else if (x.type == "harmonic")
        v = x.amplitude * std::cos(x.period * s + x.phase);
      else if (x.type == "straightness6")
        v = x.amplitude * std::cos(6.0 * std::acos(std::clamp(u, -1.0, 1.0)));
      else if (x.type == "warmup")
        v = x.amplitude * (1.0 - std::exp(-p.t / x.period));
      else if (x.type == "drift")
        v = x.amplitude * p.t / 3600.0;
      e[x.component] += v;
    }
  }

  // A point of the tool frame (b_t, mm) seen from the workpiece frame.
  Eigen::Vector3d point(const Pose& p, const Eigen::Vector3d& b_t) const {
    const Eigen::Matrix4d F_T_w = joint(kY, p) * joint(kX, p) * joint(kA, p) * joint(kC, p);
    const Eigen::Matrix4d F_T_t = joint(kZ, p);
    const Eigen::Matrix4d w_T_t = F_T_w.inverse() * F_T_t;
    return (w_T_t * Eigen::Vector4d(b_t.x(), b_t.y(), b_t.z(), 1.0)).head<3>();
  }

  double reading(const Pose& p, const Setup& s) const {
    return (point(p, s.tool_ball_t + s.tool_error_t) - (s.table_ball_w + s.table_error_w)).norm();
  }

 private:
  Eigen::Matrix4d joint(int a, const Pose& p) const {
    Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
    const double s = p.q[a];
    if (a == kX) M(0, 3) = s;
    if (a == kY) M(1, 3) = s;
    if (a == kZ) M(2, 3) = s;
    if (a == kA) {  // about x
      M(1, 1) = std::cos(s);
      M(1, 2) = -std::sin(s);
      M(2, 1) = std::sin(s);
      M(2, 2) = std::cos(s);
    }
    if (a == kC) {  // about z
      M(0, 0) = std::cos(s);
      M(0, 1) = -std::sin(s);
      M(1, 0) = std::sin(s);
      M(1, 1) = std::cos(s);
    }
    double e[6];
    errors(a, p, e);
    const auto rot = [](int axis, double g) {
      Eigen::Matrix4d R = Eigen::Matrix4d::Identity();
      const int i = (axis + 1) % 3, j = (axis + 2) % 3;
      R(i, i) = std::cos(g);
      R(i, j) = -std::sin(g);
      R(j, i) = std::sin(g);
      R(j, j) = std::cos(g);
      return R;
    };
    Eigen::Matrix4d E = rot(2, e[5]) * rot(1, e[4]) * rot(0, e[3]);
    E(0, 3) = e[0];
    E(1, 3) = e[1];
    E(2, 3) = e[2];
    return M * E;
  }
  double poly_[5][6][4];
};

// Times and approach directions along the sequence the machine ran (fit and held-out poses
// interleaved), then the readings with noise.
inline void measure(const Machine& m, std::vector<Pose>& poses, const std::vector<Setup>& setups,
                    double seconds_per_reading, double noise_mm, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, noise_mm);
  for (size_t i = 0; i < poses.size(); ++i) {
    Pose& p = poses[i];
    p.t = seconds_per_reading * static_cast<double>(i);
    for (int a = 0; a < 5; ++a) {
      if (i == 0) {
        p.dir[a] = 1;
        continue;
      }  // homed moving positive
      const double d = p.q[a] - poses[i - 1].q[a];
      p.dir[a] = std::abs(d) < 1e-12 ? poses[i - 1].dir[a] : (d > 0 ? 1 : -1);
    }
    p.length = m.reading(p, setups[p.setup]) + n(rng);
  }
}

// The readings of the fit (heldout = false) or the held-out poses, in tolver's CSV columns.
inline void writeCsv(const std::string& file, const std::vector<Pose>& poses,
                     const std::vector<Setup>& setups, bool heldout) {
  std::ofstream o(file);
  o << "# independent simulation (tests/independent_ballbar.h)\n"
       "setup,table_ball_x_mm,table_ball_y_mm,table_ball_z_mm,tool_ball_x_mm,tool_ball_y_mm,"
       "tool_ball_z_mm,x_mm,y_mm,z_mm,a_deg,c_deg,x_dir,y_dir,z_dir,a_dir,c_dir,time_s,length_mm\n";
  char buf[512];
  for (const Pose& p : poses) {
    if (p.heldout != heldout) continue;
    const Setup& s = setups[p.setup];
    int d[5];
    for (int a = 0; a < 5; ++a) d[a] = p.dir[a];
    std::snprintf(
        buf, sizeof buf,
        "%d,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.9f,%.9f,%.9f,%.12f,%.12f,%d,%d,%d,%d,%d,%.3f,%.9f\n",
        s.id, s.table_ball_w.x(), s.table_ball_w.y(), s.table_ball_w.z(), s.tool_ball_t.x(),
        s.tool_ball_t.y(), s.tool_ball_t.z(), p.q[0], p.q[1], p.q[2], p.q[3] * 180 / M_PI,
        p.q[4] * 180 / M_PI, d[0], d[1], d[2], d[3], d[4], p.t, p.length);
    o << buf;
  }
}

}  // namespace indep
