#pragma once
// Writers of a compensated program in the source's own dialect: every line, comment and word
// that is not a coordinate is kept byte for byte; coordinates change in place, with the token's
// own number of decimals or more where fewer would round the correction away (CL data: at least
// 6 decimals in mm, 8 in inches, 9 for tool-axis components; G-code: at least 4 in mm and in
// degrees, 5 in inches, the resolution of a 0.1 um control).
//
// CL data (APT, CLSF): a GOTO/FROM of one point gets the corrected point (and, in a multi-axis
// program, its tool axis: appended when the statement gave only x,y,z), in the statement's own
// coordinate system; a statement whose points were expanded (CIRCLE, MOVARC, NURBS) becomes GOTOs
// of its compensated points, with a comment naming the source line.
//
// G-code: on each G0/G1 block of one point in absolute mode, the axis words become the words that
// command the compensating joints: outside tool-centre-point mode word += nc_sign * (q - q0)
// (mm or deg, in program units); in TCP mode X Y Z += the corrected tip's change in program
// coordinates and the rotary words as outside it. A word the block did not give is added when the
// compensated value in force differs from the one the block needs. Blocks the writer cannot
// change without changing the program's structure are left as they are and listed: arcs (G2/G3),
// drilling cycles, incremental (G91) blocks, moves in machine coordinates (G53, G28) and words
// given by expressions or parameters.
#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "core/model/machine_model.h"
#include "io/program/apt_reader.h"

namespace tolver {

struct CompensatedProgramText {
  std::string text;
  std::vector<char> written;       // per program point: the text commands its compensation
  std::vector<std::string> notes;  // what was left as it was, one line each
  std::vector<int> source_line;    // per written line: the source line it comes from (0: added)
};

// corrected: per program point, the nominal machine's pose at the compensating joints (w, mm).
CompensatedProgramText formatCompensatedApt(const ClProgram& program,
                                            const std::vector<ClPoint>& corrected,
                                            const std::vector<std::string>& header);

// The same written block by block (a program read in blocks, io/program/apt_reader.h
// ProgramBlocks), into `out`: start() with the header, statements() for each block in order
// (corrected: one per block point; `written`: set to one flag per block point), notes() after
// the last. multiax: the whole program's (a block's own flag tells only what was read before
// it). source_line (optional): per written line, the source line it comes from.
class CompensatedAptWriter {
 public:
  explicit CompensatedAptWriter(bool multiax);
  void start(const std::vector<std::string>& header, std::string& out,
             std::vector<int>* source_line = nullptr);
  void statements(const ClProgram& block, const std::vector<ClPoint>& corrected, std::string& out,
                  std::vector<char>& written, std::vector<int>* source_line = nullptr);
  std::vector<std::string> notes() const;

 private:
  bool multiax_;
  std::vector<int> cycle_lines_, expanded_lines_;
};

// q0: the joints the program commands (program.joints); q: the compensating joints;
// corrected_p_w: the nominal machine's tip at q (for TCP blocks).
CompensatedProgramText formatCompensatedGcode(const ClProgram& program, const MachineModel& model,
                                              const std::vector<JointVector>& q0,
                                              const std::vector<JointVector>& q,
                                              const std::vector<Eigen::Vector3d>& corrected_p_w,
                                              const std::vector<std::string>& header);

// Which G-code blocks start an arc (the next block with a point is a G2/G3 move; its start must
// stay on the circle, so the block is written back to its programmed position): add() every
// block of a program in order (a whole program, or its blocks read one by one), then ask by
// line (1-based). One bit per line up to the last such block.
class GcodeArcStarts {
 public:
  static constexpr char kArc = 1;       // the next block with points is an arc
  static constexpr char kRelative = 2;  // ... an incremental (G91) or drilling-cycle block
  void add(const ClProgram& block);
  // 0, kArc or kRelative: what the block after line `line` (1-based) needs of its end.
  int startKind(int line) const;

 private:
  int mode_ = 0;             // the motion mode in force (G0 G1 G2 G3, G73-G89, G80)
  bool absolute_ = true;     // G90
  int last_point_line_ = 0;  // the last line with a point so far
  std::vector<char> starts_;
};

// formatCompensatedGcode block by block (a program read in blocks): start() with the first block,
// lines() for each block in order (q0, q, corrected_p_w: one per block point; written: set to
// one flag per block point), notes() after the last. units: the whole program's ("INCH" or
// "MM"); arcs: every block added (a first pass over the program).
class CompensatedGcodeWriter {
 public:
  CompensatedGcodeWriter(const MachineModel& model, const std::string& units,
                         const GcodeArcStarts& arcs);
  ~CompensatedGcodeWriter();
  CompensatedGcodeWriter(const CompensatedGcodeWriter&) = delete;
  CompensatedGcodeWriter& operator=(const CompensatedGcodeWriter&) = delete;
  void start(const ClProgram& first, const std::vector<std::string>& header, std::string& out,
             std::vector<int>* source_line = nullptr);
  void lines(const ClProgram& block, const std::vector<JointVector>& q0,
             const std::vector<JointVector>& q, const std::vector<Eigen::Vector3d>& corrected_p_w,
             std::string& out, std::vector<char>& written, std::vector<int>* source_line = nullptr);
  std::vector<std::string> notes() const;

 private:
  struct Editor;
  std::unique_ptr<Editor> editor_;
};

// Whether any block of a G-code program gives a word of a rotary axis (else it is a 3-axis
// program, compensated by the prismatic joints alone). A block of a program read in blocks: its
// own lines.
bool gcodeGivesRotaryWords(const ClProgram& program, const MachineModel& model);

}  // namespace tolver
