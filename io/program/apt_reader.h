#pragma once
// Reader of APT / CLDATA cutter-location files as real CAM systems write them (Siemens NX CLSF,
// SolidWorks CAM, PTC Creo, CATIA, generic APT).
//
// Recognised: GOTO (3 or 6 values; the tool axis is modal), FROM (the start position: not a
// point of the path), GOHOME (a home move: not a point either), GODLTA, MULTAX, TLAXIS,
// CUTTER (1-7 values), TLDATA, UNITS and UNIT, CYCLE (drilling cycles expanded at each GOTO
// until CYCLE/OFF), CIRCLE ... TIMES,n (n full turns), FEDRAT (unit before or after the value),
// RAPID, SPINDL, LOADTL, LOAD/TOOL, SELECT, PARTNO, PPRINT, INSERT, COOLNT, CIRCLE and MOVARC
// (expanded into points within a chordal tolerance, counter-clockwise about the circle axis), MSYS,
// CSYS and $$*CATIA0 (coordinate systems applied to the points that follow; a CSYS after
// TRNTYP/WORLD, as SolidWorks CAM writes it, only names the tool plane of points that are already
// in world coordinates, and is not applied), TOOL PATH, END-OF-PATH,
// END, FINI; `$` continuation lines; `$$` comments (Creo's `$$->` lines carry CUTTER and CSYS).
// Any case and spacing. Unknown statements are skipped and counted; NURBS blocks are refused.
//
// Points are returned in the workpiece frame w in mm: p_w = s * (R p_file + t), u_w = R u_file,
// with s the unit scale (25.4 for inches) and (R, t) the coordinate system in force.
#include <Eigen/Geometry>
#include <functional>
#include <string>
#include <vector>

#include "core/path/tool_path_prediction.h"
#include "io/common/line_source.h"
#include "io/program/source_lines.h"

namespace tolver {

// A cutter as the file gives it, lengths converted to mm.
struct CutterSpec {
  std::string source;          // "CUTTER" or "TLDATA"
  std::string kind;            // TLDATA's first word (MILL, DRILL...), empty for CUTTER
  std::vector<double> values;  // CUTTER: d, r, e, f, alpha, beta, h (as many as given);
                               // TLDATA/MILL: d, r, length, taper, tip angle (angles in deg)
  int line = 0;
};

// One statement of the file: its physical lines and the points it produced.
struct AptStatement {
  int first_line = 0;  // 1-based, inclusive
  int last_line = 0;
  std::string major;  // upper case ("GOTO", "CIRCLE"); empty for comments and blank lines
  int first_point = -1;
  int point_count = 0;
  // Its points are the motions of a drilling cycle at a hole (a GOTO while CYCLE/ is in force):
  // read again, the same text makes them again.
  bool cycle = false;
};

// A CAM operation the program names (NX's TOOL PATH/name, an "Operation : name" comment), from
// its line on.
struct ProgramOperation {
  int line = 0;
  std::string name;
};

// The operation a line belongs to (the last named at or before it), or empty.
const std::string& operationAt(const std::vector<ProgramOperation>& operations, int line);

// The coordinate system in force for a point: p_w = scale * (T * p_file).
struct ClFrame {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  double scale = 1.0;
};

struct ClProgram {
  std::string file;
  std::string dialect = "APT";  // "APT" (CL data) or "G-code" (io/program/gcode_reader.h)
  SourceLines lines;            // the file's physical lines (the text kept: AptReadOptions)
  std::vector<AptStatement> statements;  // covering every line in order
  std::vector<ClPoint> path;             // tool positions in w, mm
  std::vector<int> point_frame;          // per point, index into frames
  // APT: the coordinate system of the file's points (p_w = scale * T p_file). G-code: the
  // control's frame in force (Sinumerik CYCLE800, TRANS, ROT...), T mapping the program's
  // coordinates into the settable frame (G54...), in mm.
  std::vector<ClFrame> frames;
  std::vector<CutterSpec> cutters;
  std::vector<ProgramOperation> operations;  // in line order
  std::string part_name;
  std::string units = "MM";  // as the file declares: MM or INCH
  bool multiax = false;      // MULTAX/ON seen, or GOTO with six values
  int arcs_expanded = 0;
  int tool_planes = 0;  // CSYS statements after TRNTYP/WORLD (not applied)
  int cycles = 0;       // drilling cycles (CL CYCLE/, G-code canned cycles)
  int cycle_holes = 0;  // holes they were expanded at
  // G-code: the first line of an O-word construct carried out (LinuxCNC sub call, loop, if), 0
  // when none: its lines ran other than once, in place (its points belong to its first line).
  int flow_line = 0;
  // G-code: the first G41/G42 carried out as cutter radius compensation (LinuxCNC), 0 when none:
  // the points are the tool centre the control computes, off the programmed contour.
  int radius_comp_line = 0;
  int unknown_count = 0;                   // statements skipped as unknown
  std::vector<std::string> unknown_names;  // their major words, each once
  bool units_declared = false;             // UNITS / G20 / G21 seen (else the default was used)
  int units_line = 0;                      // the first UNITS statement's line (CL)
  std::string units_in_file;  // CL: the unit that statement declares, when the user's differs
  // G-code only: per point, the commanded joint values (mm, rad, model axis order; in TCP mode
  // the prismatic ones are those of the nominal inverse kinematics' reference, not commands),
  // and how the point was programmed: kJointWords (work offset + tool length, no TCP),
  // kTcpWords (tool-centre-point mode) or kMachineCoordinates (G53, G28, SUPA: no offset).
  std::vector<JointVector> joints;
  std::vector<char> tcp;
  static constexpr char kJointWords = 0, kTcpWords = 1, kMachineCoordinates = 2;
  // Per point outside TCP mode, bit k (X, Y, Z) set when that coordinate stands in machine
  // coordinates (a G53/G28/SUPA move set it and no work-offset word has moved it since): a work
  // offset does not move it.
  std::vector<unsigned char> fixed_axes;
  // Per point, 1 where a swivel cycle (Sinumerik CYCLE800) set the rotary axes, not the
  // program's words: a corrected program can move its tip, not its tool axis.
  std::vector<char> cycle_orientation;
  std::vector<std::string> notes;  // what the reader assumed or ignored, one line each
  // Per point, the index of its tool in `cutters` (the last declared before its line); empty
  // when the program declares at most one.
  std::vector<int> toolOfPoints() const;
  // A program read in blocks (ProgramBlocks): the index of path[0] in the whole program.
  size_t first_point = 0;
  size_t pointsRead() const { return first_point + path.size(); }
  // After a block was passed on: its points (and their per-point arrays), statements and lines
  // dropped, the program's state kept.
  void dropBlock() {
    first_point += path.size();
    path.clear();
    point_frame.clear();
    joints.clear();
    tcp.clear();
    fixed_axes.clear();
    cycle_orientation.clear();
    statements.clear();
    lines.dropAll();
  }
};

// A program read in blocks, so that a long program's memory does not grow with its length: the
// reader calls `sink` with the program whenever it holds at least `points` points at the end of
// a statement, and once at the end (last: true) with the rest and the reader's closing notes;
// after each call it drops what it passed on (ClProgram::dropBlock). Each call's path starts at
// point ClProgram::first_point of the whole program, its statements index its own path, its
// lines keep their numbers in the file (SourceLines::first()). A checked error (InputError) may
// come after blocks were passed on: a caller writes what it makes of them to temporary files.
struct ProgramBlocks {
  size_t points = 65536;
  std::function<void(ClProgram& block, bool last)> sink;
};

struct AptReadOptions {
  double chordal_tolerance_mm = 0.001;  // for CIRCLE / MOVARC expansion
  // Keep the text of GOTO and FROM statements in ClProgram::lines: the in-place compensated
  // writer edits it; the predicted-CL writer regenerates those lines and does not need it.
  bool keep_motion_text = true;
  // NX MSYS in the CAD's absolute frame (the reading before issue 32); by default the first
  // MSYS is the part frame and later ones are relative to it.
  bool absolute_msys = false;
  // The unit of a file that declares none, mm (25.4: --cl-units inch): its points, cutters and
  // arcs read in it from the start.
  double unit_mm = 1.0;
  // The user gave the unit (--cl-units): it holds also where the file declares another (a CAM
  // that writes UNITS/INCHES over millimetres); the file's declaration is kept in
  // ClProgram::units_in_file and units_line for the notes.
  bool unit_given = false;
};

// Throws InputError naming file:line:column and the field on malformed input. The file is
// read as a stream of lines (io/common/line_source.h), not whole.
ClProgram readApt(LineSource& source, const std::string& file_name,
                  const AptReadOptions& options = {});
// In blocks: the program returned holds the state after the last block (no points).
ClProgram readApt(LineSource& source, const std::string& file_name, const AptReadOptions& options,
                  const ProgramBlocks& blocks);
ClProgram readAptFile(const std::string& path, const AptReadOptions& options = {});
ClProgram parseApt(const std::string& text, const std::string& file_name,
                   const AptReadOptions& options = {});

}  // namespace tolver
