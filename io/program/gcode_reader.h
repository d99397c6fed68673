#pragma once
// Reader of posted ISO 6983 G-code as five-axis controls run it (Fanuc, HAAS, LinuxCNC,
// Sinumerik 840D native and ISO mode), into the same program representation as the CL reader
// (ClProgram: tool tip p_w and tool axis u_w in the workpiece frame w, mm), so that predict,
// verify and setup take either.
//
// What a word means depends on the control (MachineModel::control, from the machine file):
//  * in tool-centre-point mode (the control's TCP words: Fanuc G43.4/G43.5, HAAS G234 and G254,
//    LinuxCNC M428, Siemens TRAORI; a machine file may declare others) X Y Z are the tool tip
//    in the part frame and the rotary words are joint values: u_w is the nominal forward
//    kinematics of the rotary joints;
//  * outside it every axis word is a joint: machine coordinate = word + work offset (+ tool
//    length along the spindle axis under G43), joint = nc_sign * machine coordinate, and the
//    tool tip and axis are the nominal forward kinematics with the set-up's gauge length.
// Machine coordinates m (mm) are those of the controlled point at rotary joints zero:
// p_w = g0_w + G_m m, with g0_w the spindle gauge point at joints zero and G_m the prismatic
// joints' effect on the tip (times nc_sign), both seen from w. A work offset the set-up does not
// give puts its origin at the part zero.
//
// Recognised (docs/programs.md lists each dialect's reading and refusals): a tape leader before
// the first '%' (skipped, said once); N numbers, ( ) and ; comments, % lines, O and : program
// numbers and a name at the start, a UTF-8 BOM, CRLF; G0 G1 G2 G3 with G17/G18/G19, I J K
// (incremental; G90.1 absolute) and R, helical arcs, LinuxCNC's P turns, the end point checked by
// the control's rule (NcControl::dialect, arc_radius_tolerance_mm) and never tighter than four
// steps of the program's printed resolution; G90/G91; G20/G21 (the control's default unit
// otherwise); G93/G94/G95; G53 and G28 (machine coordinates, which stay fixed until a work-offset
// word moves them); G54-G59, G54.1 Pn, G59.1-G59.3 with offsets from the set-up; G10 L2/L20; G43 H
// and G49; the control's TCP words, ended as the control ends them (modal group 08, the machine
// file's ended_by, M2/M30); canned cycles G73, G81-G86, G88, G89 (G74, G76 on ISO controls)
// expanded into straight moves; T, M6, M61 Q (the tool in force, its geometry from the post's
// tool comments); parameters and bracketed arithmetic. Sinumerik 840D (dialect "sinumerik"):
// DEF, assignments, ADDR=expression, SUPA, G500, T="name", D, MCALL CYCLE81-83, TRANS/ATRANS/
// ROT/AROT frames (whose z must be the rotary words' tool axis in TCP mode). A move made before
// every axis has a commanded position is not a point of the path. LinuxCNC (dialect
// "linuxcnc"): O-word subs, calls, loops and conditions, carried out (ClProgram::flow_line);
// ISO: M98/M97 subprograms after the main program; G92 offsets (not on a Sinumerik); Sinumerik:
// jumps, IF/WHILE/LOOP/FOR/REPEAT; LinuxCNC: cutter radius compensation (G41/G42 with the tool
// table, G41.1/G42.1), as its interpreter does it. Refused with file:line and the construct: other
// subprograms, macros and control flow (G65, Fanuc macro B, Sinumerik CASE and CALL), other
// controls' cutter radius compensation (G41/G42), coordinate rotation and scaling (G68, G51), polar
// coordinates (G16), G87, Sinumerik CYCLE800 with solid angles. Words that do not change the path
// are listed once as ignored.
#include <map>
#include <string>
#include <string_view>

#include "core/model/machine_model.h"
#include "io/program/apt_reader.h"

namespace tolver {

struct GcodeReadOptions {
  double chordal_tolerance_mm = 0.001;  // for G2/G3 expansion
  double unit_mm = 0.0;  // forced unit (mm per program unit), 0: G20/G21 or the control's default
  // G41/G42 read as wear compensation (the user's word: the file cannot say): the programmed path
  // is already the tool centre (the CAM's "wear" or "reverse wear" compensation) and the control's
  // D registers hold only the wear, taken as 0, so the path is read as written. Without it G41 and
  // G42 are refused: a program posted for the control's full radius compensation is the part's
  // contour, off the tool centre by the radius. G41.1/G42.1 (LinuxCNC: the diameter in the
  // program) are refused either way.
  bool cutter_comp_wear = false;
  // The control's tool table (LinuxCNC: --tool-table, io/program/tool_table.h): per tool number,
  // the diameter (mm) that G41/G42 compensate by on a LinuxCNC control.
  std::map<int, double> tool_diameter_mm;
  // Bounds on control flow (LinuxCNC O-words, ISO subprograms, Sinumerik loops and jumps): passes
  // of one loop, and lines carried out within constructs in all; beyond them the program is
  // refused (a loop that moves on and never ends takes seconds to reach them: the fuzz harness
  // sets smaller ones).
  long max_loop_passes = 1000000;
  long max_flow_lines = 10000000;
};

// Throws InputError naming file:line:column and the word on malformed or unsupported input.
// The file is read as a stream of lines (io/common/line_source.h); every line's text is kept.
ClProgram readGcode(LineSource& source, const std::string& file_name, const MachineModel& model,
                    const GcodeReadOptions& options = {});
// In blocks (io/program/apt_reader.h, ProgramBlocks): the program returned holds the state after
// the last block (no points).
ClProgram readGcode(LineSource& source, const std::string& file_name, const MachineModel& model,
                    const GcodeReadOptions& options, const ProgramBlocks& blocks);
ClProgram readGcodeFile(const std::string& path, const MachineModel& model,
                        const GcodeReadOptions& options = {});
ClProgram parseGcode(const std::string& text, const std::string& file_name,
                     const MachineModel& model, const GcodeReadOptions& options = {});

// True when the text reads as G-code rather than APT/CLDATA: its first statements are G, M, N,
// %, O or axis words, not APT majors.
bool looksLikeGcode(const std::string& text);

// The ')' that ends the comment opened at s[open] == '(': the one that balances it when the
// comment holds parentheses and one does ("( hole at (61.045, 67.745) )"), else the first;
// npos when none. (LinuxCNC refuses a comment inside a comment; the reader says so.)
size_t commentEnd(std::string_view s, size_t open);

// A program in a language tolver does not read, known by its first statement: HEIDENHAIN
// conversational (Klartext: "0 BEGIN PGM NAME MM") and HEIDENHAIN's own DIN/ISO (".h"/".i":
// "%NAME G71 *", blocks ending in '*') and OpenSBP (ShopBot: "MS,1,0.5", "J3,0,0,5", "'"
// comments). Throws an InputError naming the file, line, column and the construct; returns when
// the text is none of them.
void refuseUnreadLanguage(const std::string& text, const std::string& file_name);

}  // namespace tolver
