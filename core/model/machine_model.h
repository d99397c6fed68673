#pragma once
// The machine model: topology, nominal geometry and the layout of the error parameters
// ([AM01] chapters 3-5; Pinocchio-style: an immutable description, evaluated by free functions
// and small workspaces elsewhere).
//
// Frames:
//  F  foundation (machine bed) frame;
//  S  the frame of joint S, carried by the body that joint S moves;
//  table  the frame on the last body of the workpiece branch where parts are clamped;
//  w  the workpiece (part, program) frame: CL points are given in w;
//  spindle  the spindle gauge frame on the last body of the tool branch, z along the spindle
//           axis pointing from the tool tip towards the spindle;
//  t  the tool frame: origin at the tool tip, axes parallel to the spindle frame.
//
// Each joint contributes D_S = D1 (nominal link) * L (link errors, eq. 22) * D2(s) (nominal
// motion, eq. 23/48) * E(s) (motion errors, eq. 49/87). A joint value s displaces the joint's
// moving body by s (mm or rad) along (about) its direction in its parent's frame.
//
// Error parameters form one flat vector of named blocks (lengths in mm, angles in rad):
//  * LinkError        per axis, 6 values [ex ey ez gx gy gz] ([AM01] e_x,S ... gamma_z,S; ISO 230-1
//                      location errors XOS YOS ZOS AOS BOS COS);
//  * MotionError      per axis and component, the Chebyshev coefficients c_0..c_d of that
//                      component as a function of the normalised joint coordinate (eq. 59);
//                      ISO 230-1 motion errors EXS EYS EZS EAS EBS ECS;
//  * WorkpieceSetup   6 values, error of w in table ([AM01] e_x,w ...);
//  * ToolSetup        6 values, error of t in spindle ([AM01] e_x,t ...);
//  * Effect           the coefficients of one effect (core/model/effects.h: backlash, cyclic error,
//                      rotary harmonics, thermal drift, instrument length, a higher degree),
//                      appended by addEffect after the blocks above.
// Code that walks the vector uses the blocks.
#include <Eigen/Geometry>
#include <array>
#include <limits>
#include <map>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/model/rigid_transform.h"

namespace tolver {

constexpr int kMaxAxes = 9;
// Joint values in the order of MachineModel::axes (mm for prismatic, rad for rotary).
using JointVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxAxes, 1>;

enum class JointType { Prismatic, Rotary };
enum class Branch { Workpiece, Tool };

// Error components of a twist, in order. Names as in [AM01] (e, gamma) and ISO 230-1 letters.
constexpr std::array<const char*, 6> kComponentNames = {"ex", "ey", "ez", "gx", "gy", "gz"};
constexpr std::array<char, 6> kComponentIsoLetters = {'X', 'Y', 'Z', 'A', 'B', 'C'};
inline bool isAngularComponent(int component) { return component >= 3; }

struct Axis {
  std::string name;  // "X", "C", ...
  JointType type = JointType::Prismatic;
  Branch branch = Branch::Workpiece;
  Eigen::Vector3d direction = Eigen::Vector3d::UnitX();  // unit, in the joint frame at s = 0
  Eigen::Isometry3d parent_T_joint = Eigen::Isometry3d::Identity();  // nominal link D1
  double travel_min = 0.0;                                           // mm or rad
  double travel_max = 0.0;
  int nc_sign = 1;       // NC axis command = nc_sign * joint value (ISO 841)
  bool endless = false;  // rotary without stops: travel_min/max bound multi-turn words
  bool isRotary() const { return type == JointType::Rotary; }
};

enum class BlockKind { LinkError, MotionError, WorkpieceSetup, ToolSetup, Effect };

// The kinds of effect (core/model/effects.h says what each adds).
enum class EffectType { Chebyshev, Reversal, Periodic, Harmonics, Drift, Warmup, BarLength };

// One effect on a machine: its kind, where it acts and its fixed settings.
struct EffectSpec {
  EffectType type = EffectType::Chebyshev;
  int axis = -1;        // index into MachineModel::axes; -1 for the instrument (bar length)
  int component = -1;   // motion-error component it adds to, 0..5 (ex .. gz)
  int first_order = 0;  // chebyshev, harmonics: the orders it adds
  int last_order = 0;
  bool varying = false;  // reversal: also a part proportional to the axis coordinate
  double period = 0.0;   // periodic: mm
  double tau = 0.0;      // warmup: time constant, s
};

struct ParameterBlock {
  BlockKind kind = BlockKind::LinkError;
  int axis = -1;       // index into MachineModel::axes; -1 for set-up blocks
  int component = -1;  // 0..5 for MotionError, -1 for six-value blocks
  int degree = 0;      // Chebyshev degree of a MotionError block
  int offset = 0;      // first index in the flat parameter vector
  int size = 0;
  int effect = -1;  // index into MachineModel::effects for an Effect block
};

struct ParameterInfo {
  std::string thesis_name;  // e.g. "gamma_z,X", "e_y(X).c2", "e_x,w"
  std::string iso_code;     // e.g. "COX", "EYX.c2", "part.X"
  bool angular = false;     // rad if true, mm otherwise
  int block = 0;            // index into MachineModel::blocks
};

// Another name for a parameter, e.g. the names of a paper's error table ("dx_x" for EXX.c0).
struct ParameterAlias {
  std::string name;
  int parameter = 0;
  std::string description;
};

// Part and tool placement chosen by the process planner.
struct PartSetup {
  Eigen::Vector3d part_zero_table = Eigen::Vector3d::Zero();  // part zero in the table frame, mm
  double part_rotation = 0.0;  // rotation of w about the table z axis, rad
  double gauge_length = 0.0;   // tool tip to spindle gauge point along the spindle axis, mm
  // For G-code programs: work offsets (G54, G55, G54.1P1, ...: upper case, no spaces) in machine
  // coordinates, mm; a work offset not given here puts its origin at the part zero. Tool lengths
  // by H number, mm; an H not given here is the gauge length.
  std::map<std::string, Eigen::Vector3d> work_offsets;
  std::map<int, double> tool_lengths;
  // Which of the values above were given (by a set-up file or an option), for the warnings
  // that name the defaults used.
  bool part_zero_given = false, part_rotation_given = false, gauge_length_given = false;
};

// How the machine's control reads a part program (ISO 6983 G-code): the words that switch
// tool-centre-point mode on and off, the unit when a program says neither G20 nor G21.
// In TCP mode XYZ is the tool tip in the part frame and the rotary words are joint values;
// outside it every axis word is a joint (machine coordinate plus the active offsets).
struct NcControl {
  bool declared = false;         // the machine file has a <control> element
  std::string name;              // e.g. "LinuxCNC xyzac-trt-kins"
  double default_unit_mm = 1.0;  // 25.4 for a control that defaults to inches
  // Pairs of words (upper case, as written: "M428", "G43.4", "G234"): on switches TCP mode on,
  // off switches that same mode off. Several pairs may be active at once.
  std::vector<std::pair<std::string, std::string>> tcp_words;
  // Further words that end a mode on this control, by its on word (<tcp ended_by="G28">: HAAS
  // G28 cancels tool length compensation, and so G234, Mill Operator's Manual, G28). Besides
  // these, a G word of modal group 08 (G43, G44, G49, G43.4, G43.5, G234) ends a group-08 TCP
  // mode other than itself (Fanuc and HAAS group 08), and M2/M30 end every mode.
  std::map<std::string, std::vector<std::string>> tcp_ended_by;
  // How the control reads a program: "iso" (Fanuc, HAAS and other ISO 6983 controls),
  // "linuxcnc" (RS274NGC as LinuxCNC 2.9 documents it) or "sinumerik" (Siemens 840D: DEF,
  // assignments, ADDR=expression, SUPA, TRAORI, CYCLE800).
  std::string dialect = "iso";
  // The largest difference of an arc's start and end radius the control accepts (mm), when the
  // machine file gives it (Fanuc parameter 3410); 0: the dialect's documented rule
  // (LinuxCNC: 0.5 mm, or 0.005 mm and 0.1 % of the radius; RS274NGC v3: 0.002 mm).
  double arc_radius_tolerance_mm = 0.0;
  // Values of named parameters the control supplies (LinuxCNC #<_hal[pin]>), by name.
  std::map<std::string, double> parameters;
  // The rotary axes a swivel cycle calls 1 and 2, by name (Sinumerik CYCLE800: axis 1 is the
  // direction reference of _DIR); empty: the tilting axis first.
  std::vector<std::string> swivel_axes;
  // Tool axes closer than this to a rotary axis keep that axis's previous angle (rad).
  double singular_band = 1e-4;
};

class MachineModel {
 public:
  std::string name;
  std::vector<Axis> axes;            // joint-vector order
  std::vector<int> workpiece_chain;  // axis indices, foundation -> table
  std::vector<int> tool_chain;       // axis indices, foundation -> spindle
  Eigen::Isometry3d last_T_table = Eigen::Isometry3d::Identity();    // table in last wp joint
  Eigen::Isometry3d last_T_spindle = Eigen::Isometry3d::Identity();  // spindle in last tool joint
  PartSetup setup;
  NcControl control;
  // Where the error values come from: "none" (a nominal machine: predictions show no machine
  // error by construction), "measured", "identified", "simulated"; empty when the file is silent.
  std::string errors_source;

  std::vector<ParameterBlock> blocks;
  std::vector<ParameterInfo> parameters;  // one per entry of the flat parameter vector
  std::vector<ParameterAlias> aliases;
  std::vector<EffectSpec> effects;  // one per Effect block, in block order
  // Parameters kept by strategy II when choosing a minimal-complete set, per model name
  // ("link", "motion"): the recognised link errors ([AM01] Tables 3.4 and 4.2).
  std::map<std::string, std::vector<int>> preferred;

  // Builds blocks and parameters: link errors for each axis, motion errors of the given
  // Chebyshev degree per axis and component, then workpiece and tool set-up errors.
  // motion_degree[a][c] < 0 means that component has no motion-error block.
  void buildParameterLayout(const std::vector<std::array<int, 6>>& motion_degree);

  // Appends an Effect block (and its named parameters) for spec; returns the block index.
  // Parameter values of a Machine must be extended with zeros to match.
  int addEffect(const EffectSpec& spec);

  int parameterCount() const { return static_cast<int>(parameters.size()); }
  int axisIndex(std::string_view axis_name) const;  // -1 if absent (case-insensitive)
  // Index of a parameter by [AM01] name, ISO code or alias (case-sensitive), -1 if absent.
  int findParameter(std::string_view name) const;
  // Index of the motion-error block of (axis, component), -1 if absent.
  int motionBlock(int axis, int component) const;

  // Nominal w in table and t in spindle, from the set-up (no errors).
  Eigen::Isometry3d table_T_w() const;
  Eigen::Isometry3d spindle_T_t() const;
};

// What a configuration carries besides its joint values, for error blocks that depend on it
// (a reversal error on the approach direction, thermal drift on time). Blocks that do not use
// it ignore it; code that evaluates the model passes it along (nullptr: unknown).
struct MotionContext {
  std::array<signed char, kMaxAxes> direction{};  // per axis: +1/-1 last motion, 0 unknown
  double time_s = std::numeric_limits<double>::quiet_NaN();  // seconds since the test began
};

// What a calibration knows of the values it identified: their covariance, and the joint ranges
// its readings covered (empty when the machine was not calibrated). A prediction's uncertainty
// is this covariance carried through the sensitivity Jacobian (core/path/prediction_uncertainty.h);
// outside the covered ranges the fitted polynomials extrapolate.
struct IdentificationUncertainty {
  std::vector<int> parameters;                   // indices into the parameter vector
  Eigen::MatrixXd covariance;                    // of those parameters, in mm and rad
  std::vector<double> covered_min, covered_max;  // per axis, mm or rad; empty: unknown
  int readings = 0;
  // What the covariance does not hold, added to a prediction's band (core/path/prediction_
  // uncertainty.h): the RMS the model misses beyond the readings' repeatability when the
  // calibration's lack-of-fit test failed (mm, per coordinate of the tip), and the prior of the
  // spindle's tilt against the machine's axes, which a ball-bar cannot see (rad, 1 sigma per
  // direction across the tool axis; 0: not stated).
  double lack_of_fit_mm = 0.0;
  double spindle_tilt_rad = 0.0;
  bool empty() const { return parameters.empty(); }
};

// A machine: its model and the values of its error parameters (mm, rad).
struct Machine {
  MachineModel model;
  Eigen::VectorXd params;  // model.parameterCount() values
  IdentificationUncertainty identification;
};

// The machine's three prismatic axes in the order of the words X, Y, Z that drive them: by name
// when they are named X, Y and Z (in any order in the file), else in the file's order;
// {-1, -1, -1} unless there are exactly three.
std::array<int, 3> prismaticWordOrder(const MachineModel& model);

}  // namespace tolver
