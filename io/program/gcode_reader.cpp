#include "io/program/gcode_reader.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <map>
#include <optional>
#include <set>
#include <unordered_set>

#include "core/kinematics/forward_kinematics.h"
#include "core/kinematics/inverse_kinematics.h"
#include "core/numerics/units.h"
#include "core/path/arc_interpolation.h"
#include "io/common/io_error.h"
#include "io/common/text_util.h"

namespace tolver {
namespace {

constexpr double kDegToRad = degToRad(1.0);

// One word of a block: its letter, value and, for G and M, the code as written ("G43.4").
struct Word {
  char letter = 0;
  double value = 0.0;
  std::string code;  // "G1", "G43.4", "M428" (no leading zeros); empty for other letters
  int column = 0;
};

// "G" + 1 -> "G1", 43.4 -> "G43.4", 54.1 -> "G54.1".
std::string codeOf(char letter, double value) {
  const long v10 = std::lround(value * 10.0);
  std::string s(1, letter);
  s += std::to_string(v10 / 10);
  if (v10 % 10 != 0) s += "." + std::to_string(std::labs(v10 % 10));
  return s;
}

// G words that change geometry and that this reader does not carry out: refused.
const std::map<std::string, const char*>& refusedG() {
  static const std::map<std::string, const char*> m = {
      {"G41",
       "cutter radius compensation is not carried out: post the program with compensation "
       "in the CAM system (tool centre path); if the path already is the tool centre (the "
       "CAM's wear or reverse-wear compensation, D registers holding only wear), read it "
       "with --cutter-comp wear"},
      {"G42",
       "cutter radius compensation is not carried out: post the program with compensation "
       "in the CAM system (tool centre path); if the path already is the tool centre (the "
       "CAM's wear or reverse-wear compensation, D registers holding only wear), read it "
       "with --cutter-comp wear"},
      {"G41.1",
       "G41.1 (LinuxCNC: cutter radius compensation with the diameter in the program; Fanuc: "
       "normal direction control, a rotary axis kept normal to the path) is not carried out"},
      {"G42.1",
       "G42.1 (LinuxCNC: cutter radius compensation with the diameter in the program; Fanuc: "
       "normal direction control, a rotary axis kept normal to the path) is not carried out"},
      // Fanuc 30i codes that move the frame or the controlled point for the moves after them
      // (Fanuc 30i-B operator's manual): with no axis words in their block they would otherwise
      // be noted as unknown and the moves after them read in the wrong frame.
      {"G68.3",
       "tilted working plane by the tool axis direction (Fanuc G68.3: the frame follows the "
       "rotary axes' position) is not carried out: post the plane with G68.2 or the moves in TCP "
       "mode"},
      {"G68.4", "incremental tilted working plane (Fanuc G68.4) is not carried out"},
      {"G54.2",
       "rotary table dynamic fixture offset (Fanuc G54.2: the work offset turns with the table) "
       "is not carried out"},
      {"G54.4", "workpiece setting error compensation (Fanuc G54.4) is not carried out"},
      {"G44",
       "tool length compensation in the negative direction (G44) is not carried out: post "
       "G43"},
      {"G43.8",
       "cutting point command (Fanuc G43.8: X Y Z are the cutting point, not the tool tip) is "
       "not carried out"},
      {"G43.9",
       "cutting point command (Fanuc G43.9: X Y Z are the cutting point, not the tool tip) is "
       "not carried out"},
      {"G41.2", "3-D cutter compensation (Fanuc G41.2-G42.6) is not carried out"},
      {"G41.3", "3-D cutter compensation (Fanuc G41.2-G42.6) is not carried out"},
      {"G41.4", "3-D cutter compensation (Fanuc G41.2-G42.6) is not carried out"},
      {"G41.5", "3-D cutter compensation (Fanuc G41.2-G42.6) is not carried out"},
      {"G41.6", "3-D cutter compensation (Fanuc G41.2-G42.6) is not carried out"},
      {"G42.2", "3-D cutter compensation (Fanuc G41.2-G42.6) is not carried out"},
      {"G42.4", "3-D cutter compensation (Fanuc G41.2-G42.6) is not carried out"},
      {"G42.5", "3-D cutter compensation (Fanuc G41.2-G42.6) is not carried out"},
      {"G42.6", "3-D cutter compensation (Fanuc G41.2-G42.6) is not carried out"},
      {"G66.1", "modal macro calls (G66.1) are not supported"},
      {"G92", "G92 is the spindle speed limit on a SINUMERIK (G92 S...), not carried out"},
      {"G52", "local coordinate systems (G52) are not supported"},
      {"G68", "coordinate rotation (G68) is not supported"},
      {"G51", "scaling (G51) is not supported"},
      {"G51.1", "mirroring (G51.1) is not supported"},
      {"G16", "polar coordinates (G16) are not supported"},
      {"G7", "lathe diameter mode (G7) is not supported"},
      {"G33", "threading (G33) is not supported"},
      {"G76", "threading cycles (G76, LinuxCNC) are not supported"},
      // G30 returns to the second reference point, a setting of the control (LinuxCNC
      // parameters #5181-#5186; Fanuc parameter 1241; HAAS settings 268-270), which a machine
      // file does not carry: the tool's position after it is unknown.
      {"G30",
       "G30 returns to the second reference point, a setting of the control (LinuxCNC #5181-"
       "#5186, Fanuc parameter 1241, HAAS settings 268-270) that the machine file does not give: "
       "post the retract as G53 or G28"},
      {"G38.2", "probing moves are not supported"},
      {"G38.3", "probing moves are not supported"},
      {"G87",
       "back boring (G87) is not expanded: the tool passes the hole off-centre with the "
       "spindle oriented; post it as motion"},
      {"G65", "macro calls (G65) are not supported"},
      {"G66", "modal macro calls (G66) are not supported"},
  };
  return m;
}

// Codes of the motion group some control gives a meaning tolver does not carry out: refused by
// name, or their axis words (spline control points, pocket sizes) would be read as moves of the
// modal G0/G1 (LinuxCNC's NURBS example, nc_files/nurbs/G5/nurbs-xy.ngc, read as five G1 points).
// Sources: the LinuxCNC G-code reference (G5 cubic spline, G5.1 quadratic spline, G5.2/G5.3
// NURBS, G33.1 rigid tapping, G70-G72 lathe cycles); Fanuc 0i-MF / 30i (G6.2 NURBS, G12.1/G13.1
// polar coordinate interpolation, G7.1 cylindrical interpolation, G2.4/G3.4 3-D circular
// interpolation); HAAS mill operator's manual 96-8000 (G12/G13 circular pocket milling, G150
// general pocket milling, G70/G71/G72 bolt-hole patterns under a drilling cycle).
const char* refusedMotion(const std::string& c, const std::string& dialect) {
  if (c == "G5.2" || c == "G5.3")
    return "NURBS (G5.2-G5.3, LinuxCNC) is not supported: post the path as G1 moves";
  if (c == "G6.2") return "NURBS (G6.2, Fanuc) is not supported: post the path as G1 moves";
  if (c == "G12.1" || c == "G13.1")
    return "polar coordinate interpolation (G12.1/G13.1) is not supported";
  if (c == "G7.1") return "cylindrical interpolation (G7.1) is not supported";
  if (c == "G2.4" || c == "G3.4") return "3-D circular interpolation (G2.4/G3.4) is not supported";
  if (dialect == "linuxcnc") {
    if (c == "G5") return "cubic spline (G5, LinuxCNC) is not supported: post the path as G1 moves";
    if (c == "G5.1")
      return "quadratic spline (G5.1, LinuxCNC) is not supported: post the path as G1 moves";
    if (c == "G33.1") return "rigid tapping (G33.1, LinuxCNC) is not expanded: post it as motion";
    if (c == "G70" || c == "G71" || c == "G72")
      return "lathe finishing and roughing cycles (G70-G72, LinuxCNC) are not expanded";
  }
  if (dialect == "iso") {
    if (c == "G12" || c == "G13")
      return "circular pocket milling (G12/G13, HAAS) is not expanded: post it as motion";
    if (c == "G150")
      return "general pocket milling (G150, HAAS) is not expanded: post it as motion";
  }
  return nullptr;
}

// HAAS's G110-G129: its additional work offsets G154 P1-P20.
bool isHaasG110(const std::string& c) {
  if (c.size() != 4 || c.compare(0, 2, "G1") != 0) return false;
  const int n = std::atoi(c.c_str() + 1);
  return n >= 110 && n <= 129;
}

// G words that do not change the tool path: accepted silently.
const std::set<std::string>& harmlessG() {
  static const std::set<std::string> s = {"G4",  "G9",   "G40",   "G61", "G61.1", "G64", "G93",
                                          "G94", "G95",  "G96",   "G97", "G15",   "G50", "G5.1",
                                          "G8",  "G187", "G50.1", "G98", "G99",   "G80"};
  return s;
}

// M words that do not change the tool path: accepted silently.
const std::set<std::string>& harmlessM() {
  static const std::set<std::string> s = {
      "M0",  "M1",  "M3",  "M4",  "M5",  "M6",  "M7",  "M8",  "M9",  "M10", "M11", "M12",
      "M13", "M19", "M48", "M49", "M50", "M51", "M52", "M53", "M61", "M62", "M63", "M64",
      "M65", "M66", "M67", "M68", "M70", "M71", "M72", "M73", "M88", "M89"};
  return s;
}

class Reader {
 public:
  Reader(LineSource& source, const std::string& file, const MachineModel& model,
         const GcodeReadOptions& opt, const ProgramBlocks* blocks)
      : model_(model),
        opt_(opt),
        nominal_(model, Eigen::VectorXd::Zero(model.parameterCount())),
        ik_(model),
        blocks_(blocks) {
    prog_.file = file;
    prog_.dialect = "G-code";
    prog_.multiax = true;
    // LinuxCNC's predefined return values (G-code reference, "O Codes": "#<_value>" and
    // "#<_value_returned>", 0 until a sub returns one).
    if (model.control.dialect == "linuxcnc") named_["_value"] = named_["_value_returned"] = 0.0;
    source_ = &source;
    if (!blocks_)  // all the text is kept
      prog_.lines.reserve(source.sizeHint(), source.sizeHint() / 30);
    prog_.frames.push_back(ClFrame{});
    unit_ = opt.unit_mm > 0 ? opt.unit_mm : model.control.default_unit_mm;
    prog_.units = unit_ == 25.4 ? "INCH" : "MM";
    for (size_t a = 0; a < model.axes.size(); ++a) {
      const std::string& n = model.axes[a].name;
      if (n.size() == 1)
        letter_axis_[static_cast<unsigned char>(std::toupper(n[0]))] = static_cast<int>(a);
    }
    for (const auto& [name, value] : model.control.parameters) named_[lowerNoSpace(name)] = value;
    prepareMachineCoordinates();
    q_ = JointVector::Zero(static_cast<int>(model.axes.size()));
  }

  ClProgram run() {
    // Lines before the first '%' are held: when a '%' follows within kMaxLeaderLines they are
    // the tape leader, which ISO 6983 controls skip (Fanuc: the leader before the first EOR is
    // ignored; NX writes its listing there); otherwise they are blocks.
    std::vector<std::string> held;
    bool leader_decided = false;
    std::string text;
    while (source_->next(text)) {
      if (leader_decided) {
        processLine(text);
        continue;
      }
      const std::string_view t = trim(text);
      if (!t.empty() && t[0] == '%') {
        // A leader holds text that is not a block (a listing, a title); lines that all read as
        // blocks before a closing '%' are the program.
        bool leader = false;
        for (const std::string& h : held) leader = leader || !looksLikeBlock(h);
        for (const std::string& h : held) {
          if (leader)
            skipLine(h);
          else
            processLine(h);
        }
        if (leader)
          prog_.notes.push_back("lines 1-" + std::to_string(held.size()) +
                                " before the first '%' are the tape leader: not read");
        held.clear();
        leader_decided = true;
        processLine(text);
        continue;
      }
      held.push_back(text);
      if (held.size() >= kMaxLeaderLines) {
        for (const std::string& h : held) processLine(h);
        held.clear();
        leader_decided = true;
      }
    }
    for (const std::string& h : held) processLine(h);
    if (tail_mode_) replayTail();
    compOff();  // the held moves of a compensation the file leaves on
    if (!held_flow_.empty()) {
      const OWord& o = held_open_;
      fail(held_flow_.front().line, o.column, "O",
           "o" + o.label + " " + o.keyword + " without its o" + o.label + " " +
               closerOf(o.keyword) + " (the file ends first)");
    }
    if (!any_) fail(0, 0, "", "empty file: no blocks");
    // What the end of the program left unread: said, and named when nothing was read before it
    // (a post that writes '%' lines as remarks ends an ISO tape there).
    const std::string after_end =
        after_end_ == 0
            ? std::string()
            : std::to_string(after_end_) + " line(s) after it, from line " +
                  std::to_string(first_after_end_) + ", are not read" +
                  (end_cause_ == "'%'" ? " (on ISO controls a second '%' ends the tape: it is not "
                                         "a comment)"
                                       : "");
    if (points_read_ == 0 && unknown_moves_ > 0 && !after_end_) {
      // Moves there were, but some axis never had a position (a lathe program's Y, a program
      // that relies on where the last one left the tool).
      std::string never;
      for (int k = 0; k < 3; ++k)
        if (coord_[k] == kUnknown) never += std::string(never.empty() ? "" : ", ") + "XYZ"[k];
      fail(first_unknown_line_, 0, "",
           std::to_string(unknown_moves_) + " move(s), lines " +
               std::to_string(first_unknown_line_) + "-" + std::to_string(last_unknown_line_) +
               ", and none where the tool's position is known: the program never commands " +
               (never.empty() ? std::string("every axis before it moves") : never) +
               (coord_[1] == kUnknown && coord_[0] != kUnknown && coord_[2] != kUnknown
                    ? " (a lathe program, X and Z only?)"
                    : ""));
    }
    if (points_read_ == 0 && subs_defined_ && prog_.flow_line == 0 && !after_end_)
      fail(0, 0, "O",
           "the file defines subroutines (o... sub) and calls none: no moves (a file of subs for "
           "another program to call: give that program)");
    if (points_read_ == 0)
      fail(after_end_ ? end_line_ : 0, 0, after_end_ ? end_cause_ : "",
           after_end_ ? "the program ends here with no moves before it; " + after_end
                      : "the program has no moves (no G0/G1/G2/G3 with axis words)");
    if (after_end_ > 0)
      prog_.notes.push_back("the program ends at line " + std::to_string(end_line_) + " (" +
                            end_cause_ + "); " + after_end);
    if (unknown_moves_ > 0)
      prog_.notes.push_back(std::to_string(unknown_moves_) +
                            " move(s) before every axis had a "
                            "commanded position (lines " +
                            std::to_string(first_unknown_line_) + "-" +
                            std::to_string(last_unknown_line_) +
                            ") are not in the path: the tool's position there is not in the "
                            "program");
    if (!units_seen_) {
      prog_.notes.push_back(std::string("no G20/G21: the control's default unit (") +
                            (unit_ == 25.4 ? "inch" : "mm") + ") was used");
    }
    if (nested_comments_ > 0)
      prog_.notes.push_back(std::to_string(nested_comments_) +
                            " comment(s) with parentheses inside (the first at line " +
                            std::to_string(first_nested_comment_) +
                            ") read as one comment each, up to the parenthesis that balances it: "
                            "the control must do the same (LinuxCNC refuses nested comments)");
    if (!ignored_.empty()) {
      std::string names;
      for (const auto& n : ignored_) names += (names.empty() ? "" : ", ") + n;
      prog_.notes.push_back("ignored (no effect on the tool path): " + names);
    }
    if (stored_cycles_ > 0)
      prog_.notes.push_back(std::to_string(stored_cycles_) +
                            " drilling-cycle block(s) with L0/K0: the cycle stored, no hole made "
                            "there");
    if (g92_line_ > 0)
      prog_.notes.push_back("G92 offsets (first at line " + std::to_string(g92_line_) +
                            ") carried out: the points after them are where the offset puts "
                            "them, in the work offset in force");
    if (model_.control.dialect == "iso" && bare_point_ && first_integer_line_ > 0)
      prog_.notes.push_back(
          "numbers without a decimal point beside numbers written as '10.' (the first, " +
          first_integer_ + ", at line " + std::to_string(first_integer_line_) + ") read in " +
          std::string(unit_ == 25.4 ? "inches" : "mm") +
          ": a Fanuc control with parameter 3401#0 DPI = 0 reads them in least input "
          "increments (" +
          first_integer_ + " as " + first_integer_.substr(1) +
          (unit_ == 25.4 ? " ten-thousandths of an inch)" : " um)") +
          "; check the control's setting");
    if (huge_feed_line_ > 0)
      prog_.notes.push_back("feeds beyond any machine's (first at line " +
                            std::to_string(huge_feed_line_) +
                            ") read as the control's fastest, not known: the control clamps them "
                            "to its velocity limits");
    if (block_deletes_ > 0)
      prog_.notes.push_back(std::to_string(block_deletes_) +
                            " block(s) marked '/' (block delete, the first at line " +
                            std::to_string(first_block_delete_) +
                            ") read as run: with the control's block-delete switch on they are "
                            "skipped");
    if (radius_comp_blocks_ > 0)
      prog_.notes.push_back(
          "cutter radius compensation carried out as LinuxCNC's interpreter does (" +
          std::to_string(radius_comp_blocks_) + " G41/G42 block(s), the first at line " +
          std::to_string(prog_.radius_comp_line) +
          "): the path is the tool centre offset from the programmed contour");
    if (wear_comp_line_ > 0)
      prog_.notes.push_back("G41/G42 (first at line " + std::to_string(wear_comp_line_) +
                            ") read as wear compensation (--cutter-comp wear): the path is the "
                            "tool centre as written, the D registers' wear taken as 0");
    if (g75_line_ > 0)
      prog_.notes.push_back("G75 (first at line " + std::to_string(g75_line_) +
                            ") takes the axes it names to a fixed point of the control's machine "
                            "data: not a point of the path; those axes are unknown until "
                            "commanded again");
    if (bare_g28_line_ > 0)
      prog_.notes.push_back(
          "G28 without axis words (first at line " + std::to_string(bare_g28_line_) +
          ") read as every axis to machine zero, as HAAS and LinuxCNC do; a Fanuc control moves "
          "only the axes a G28 names (none)");
    if (!unknown_.empty()) {
      std::string names;
      for (const auto& [code, first] : unknown_)
        names += (names.empty() ? "" : ", ") + code + " (line " + std::to_string(first) + ")";
      prog_.notes.push_back(
          "codes tolver does not know, read as not moving the tool (check "
          "what they do on the control): " +
          names);
    }
    // A program that selects no tool at all (no T word: Fusion's personal-use posts for hobby
    // machines) and lists exactly one in its comments: that tool cuts, and the note says so.
    if (prog_.cutters.empty() && active_tool_.empty() && selected_tool_.empty() &&
        tool_table_.size() == 1) {
      const auto& [key, geometry] = *tool_table_.begin();
      CutterSpec spec;
      spec.source = "TLDATA";
      spec.kind = key;
      spec.line = tool_line_.count(key) ? tool_line_.at(key) : 0;
      spec.values = {geometry.first * unit_, geometry.second * unit_};
      prog_.cutters.push_back(spec);
      prog_.notes.push_back(key + " (listed in a comment at line " + std::to_string(spec.line) +
                            ") is the only tool the program names and it selects none (no T "
                            "word): taken as the tool that cuts");
    }
    if (tcp_without_tlc_)
      prog_.notes.push_back(
          "TCP mode without G43: LinuxCNC then drives the spindle gauge point; XYZ was taken as "
          "the tool tip with the set-up's gauge length");
    for (const auto& [word, first] : missing_offsets_)
      prog_.notes.push_back(
          word +
          (commanded_offsets_.count(word)
               ? " (first used at line " + std::to_string(first) + ")"
               : " (the control's default work offset: the program never selects one; in force "
                 "from line " +
                     std::to_string(first) + ")") +
          " is not in the set-up: its origin was put at the part zero");
    if (blocks_) {
      blocks_->sink(prog_, true);
      prog_.dropBlock();
    }
    return std::move(prog_);
  }

  // One physical line: a block, a '%' or nothing; its statement and text kept.
  void processLine(const std::string& text) {
    if (tail_mode_) {
      tail_.push_back(text);
      return;
    }
    if (model_.control.dialect == "linuxcnc" && (!held_flow_.empty() || opensFlow(text))) {
      flowLine(text);
      return;
    }
    if (model_.control.dialect == "sinumerik" && !ended_ && !replaying_ && mayFlow(text)) {
      const SinFlowLine f = sinFlow(text);
      if (!f.label.empty() || !f.keyword.empty()) {  // jumps may come: the rest is held
        tail_mode_ = true;
        tail_.push_back(text);
        return;
      }
    }
    if (isoSubprograms() && !ended_) {
      if (const auto call = parseIsoCall(text)) {
        isoCallLine(text, *call);
        return;
      }
    }
    const int first_point = static_cast<int>(prog_.path.size());
    const std::string major = runLine(static_cast<int>(prog_.lines.size()) + 1, text);
    pushStatement(text, first_point + compLateToTheirLines(first_point), major);
    sinkBlock();
  }

  // Cutter radius compensation holds a move until the next (compMoveEndpointAndFlush): its points
  // come while a later line is read. They go to their own line's statement (the written CL's
  // "$$ line" is the line that made them), when it directly precedes them; returns how many of
  // the points from `first` on were given away so.
  int compLateToTheirLines(int first) {
    int given = 0;
    for (const CompLate& late : comp_late_) {
      if (late.first != first + given) break;
      AptStatement* st = nullptr;
      for (auto it = prog_.statements.rbegin(); it != prog_.statements.rend(); ++it)
        if (it->first_line == late.line) {
          st = &*it;
          break;
        }
      if (st == nullptr) break;
      if (st->point_count <= 0) {
        st->first_point = late.first;
        st->point_count = late.count;
      } else if (st->first_point + st->point_count == late.first) {
        st->point_count += late.count;
      } else {
        break;
      }
      given += late.count;
    }
    comp_late_.clear();
    return given;
  }

  // One line carried out as its own line number: the block, a '%', or a line after the end.
  // Returns the block's major word.
  std::string runLine(int line, const std::string& text) {
    line_ = line;
    const std::string_view t = trim(text);
    any_ = any_ || !t.empty();
    if (!ended_ && !t.empty() && t[0] == '%') {
      if (++percent_ >= 2 && seen_block_) endAt("'%'");
    } else if (!ended_ && !t.empty()) {
      return block(text);
    } else if (ended_ && !t.empty() && t[0] != '%' && t[0] != '(' && t[0] != ';' &&
               !sub_lines_.count(line)) {
      if (after_end_++ == 0) first_after_end_ = line;
    }
    return "";
  }

  // The next line's statement (one per line, in order), holding the points from first_point on.
  void pushStatement(const std::string& text, int first_point, const std::string& major) {
    AptStatement st;
    st.first_line = st.last_line = static_cast<int>(prog_.lines.size()) + 1;
    st.first_point = first_point;
    st.major = major;
    st.point_count = static_cast<int>(prog_.path.size()) - first_point;
    if (st.point_count <= 0) {
      st.point_count = 0;
      st.first_point = -1;
    }
    prog_.statements.push_back(st);
    prog_.lines.push(text, true);
  }

  void sinkBlock() {
    // (not while compensation holds a move: its points still go to a statement of this block)
    if (blocks_ && prog_.path.size() >= blocks_->points && comp_side_ == 0) {
      blocks_->sink(prog_, false);
      prog_.dropBlock();
    }
  }

  // ---------------------------------------------------------------- LinuxCNC O-words
  // LinuxCNC's subprograms and control flow (LinuxCNC G-code reference, "O Codes"): o<name> sub
  // ... endsub [value], o<name> call [arg] ..., oN while [c] ... endwhile, oN do ... while [c],
  // oN if [c] ... elseif [c] ... else ... endif, oN repeat [n] ... endrepeat, break, continue,
  // return [value]. A construct met at the top level is held whole up to its end, then carried
  // out; its points belong to its first line's statement (statements stay one per line) and each
  // point keeps the line that made it (ClProgram::flow_line says a construct ran). A sub is kept
  // where it is defined and run by its calls: #1-#30 take the call's arguments (0 beyond them)
  // and, with the named parameters that do not begin with '_', belong to the call (restored
  // after it); a
  // value returned is #<_value>. Refused by name: a call of a sub not defined above it in the
  // file (LinuxCNC would also search its subroutine path, which no machine file gives), a
  // construct without its end or a word out of place, a loop that runs more than
  // opt_.max_loop_passes times, calls nested deeper than kMaxCallDepth.
  struct OWord {
    std::string label;    // "100" or "<name>" (lower case, no spaces)
    std::string keyword;  // lower case: sub, endsub, call, while, ...
    std::string rest;     // upper case, comments removed: "[#1 LT 3]"
    int column = 1;
  };
  struct SourceLine {
    int line = 0;
    std::string text;
  };
  struct Sub {
    std::vector<SourceLine> body;  // between sub and endsub
    SourceLine end;                // the endsub line (its value)
    std::string refuse;            // ISO: why it cannot be carried out (its M99 block)
  };
  enum class FlowExit { Next, Break, Continue, Return };
  struct FlowResult {
    FlowExit exit = FlowExit::Next;
    std::string label;
  };
  // (the bounds: GcodeReadOptions::max_loop_passes, max_flow_lines)
  static constexpr int kMaxCallDepth = 50;
  static constexpr int kMaxFlowDepth = 100;  // constructs within constructs

  // A line as LinuxCNC reads it: comments out ('(...)' and after ';'), every space out, upper
  // case; col (when given) the 1-based column of each character kept.
  static std::string compactLine(const std::string& raw, std::vector<int>* col = nullptr) {
    std::string c;
    for (size_t k = 0; k < raw.size(); ++k) {
      if (raw[k] == ';') break;
      if (raw[k] == '(') {
        const size_t close = commentEnd(raw, k);
        if (close == std::string::npos) break;
        k = close;
        continue;
      }
      if (std::isspace(static_cast<unsigned char>(raw[k]))) continue;
      c += static_cast<char>(std::toupper(static_cast<unsigned char>(raw[k])));
      if (col) col->push_back(static_cast<int>(k) + 1);
    }
    return c;
  }

  // An O-word line, read as LinuxCNC reads a line: comments out, and every space ignored ("o
  // <name> call", "o100 end sub" and "o100 endsub" are the same). nullopt when the line is not
  // an O-word of subs or control flow (a program number O1234, any other block).
  static std::optional<OWord> parseOWord(const std::string& raw) {
    static const std::set<std::string> words = {
        "sub",      "endsub", "call",   "if",        "elseif", "else",  "endif",   "while",
        "endwhile", "do",     "repeat", "endrepeat", "return", "break", "continue"};
    std::vector<int> col;
    const std::string c = compactLine(raw, &col);
    size_t i = 0;
    if (i + 1 < c.size() && c[i] == 'N' && std::isdigit(static_cast<unsigned char>(c[i + 1]))) {
      ++i;
      while (i < c.size() && std::isdigit(static_cast<unsigned char>(c[i]))) ++i;
    }
    if (i >= c.size() || c[i] != 'O') return std::nullopt;
    OWord o;
    o.column = col[i];
    ++i;
    if (i < c.size() && c[i] == '<') {
      const size_t close = c.find('>', i);
      if (close == std::string::npos) return std::nullopt;
      o.label = "<" + toLower(c.substr(i + 1, close - i - 1)) + ">";
      i = close + 1;
    } else {
      const size_t from = i;
      while (i < c.size() && std::isdigit(static_cast<unsigned char>(c[i]))) ++i;
      if (i == from) return std::nullopt;
      o.label = std::to_string(std::stol(c.substr(from, std::min<size_t>(i - from, 9))));
    }
    size_t e = i;
    while (e < c.size() && std::isalpha(static_cast<unsigned char>(c[e]))) ++e;
    o.keyword = toLower(c.substr(i, e - i));
    if (!words.count(o.keyword)) return std::nullopt;
    o.rest = c.substr(e);
    return o;
  }

  static bool opensFlow(const std::string& text) {
    // Most lines are no O-word: their first letter (after a block number) is not O.
    size_t i = 0;
    while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
    if (i < text.size() && (text[i] == 'N' || text[i] == 'n'))
      while (++i < text.size() &&
             (std::isdigit(static_cast<unsigned char>(text[i])) || text[i] == ' '))
        ;
    if (i >= text.size() || (text[i] != 'O' && text[i] != 'o')) return false;
    return parseOWord(text).has_value();
  }

  static const char* closerOf(const std::string& keyword) {
    if (keyword == "sub") return "endsub";
    if (keyword == "while") return "endwhile";
    if (keyword == "do") return "while";
    if (keyword == "if") return "endif";
    if (keyword == "repeat") return "endrepeat";
    return nullptr;
  }

  // A line at the top level that opens a construct, or one inside a construct being held.
  void flowLine(const std::string& text) {
    const int line = static_cast<int>(prog_.lines.size() + held_flow_.size()) + 1;
    const std::optional<OWord> o = parseOWord(text);
    any_ = true;
    if (held_flow_.empty()) {
      line_ = line;
      // After the end only sub definitions are read (LinuxCNC: subs may follow the main
      // program's M2/M30); after a closing '%' nothing is.
      if (ended_ && (o->keyword != "sub" || end_cause_ == "'%'")) {
        pushStatement(text, static_cast<int>(prog_.path.size()), runLine(line, text));
        return;
      }
      if (o->keyword == "call") {
        held_flow_.push_back({line, text});
        finishFlow();
        return;
      }
      if (o->keyword == "sub") subs_defined_ = true;
      if (!closerOf(o->keyword))
        fail(line, o->column, "O",
             "o" + o->label + " " + o->keyword + " outside the construct it belongs to (no o" +
                 o->label + " sub, while, do, if or repeat open before it)");
      held_open_ = *o;
    }
    held_flow_.push_back({line, text});
    if (held_flow_.size() > 1 && o && o->label == held_open_.label &&
        o->keyword == closerOf(held_open_.keyword))
      finishFlow();
  }

  // The construct held is complete: defined (sub) or carried out; its lines become statements.
  // When it calls a sub not yet defined, it and the rest of the file are held (tail_) and read
  // again once the file's subs are known (LinuxCNC: subs may follow the main program).
  void finishFlow() {
    std::vector<SourceLine> lines;
    lines.swap(held_flow_);
    if (!replaying_ && callsUndefined(lines)) {
      tail_mode_ = true;
      for (const SourceLine& l : lines) tail_.push_back(l.text);
      return;
    }
    const int first_point = static_cast<int>(prog_.path.size());
    const std::optional<OWord> o = parseOWord(lines.front().text);
    if (o->keyword == "sub") {
      line_ = lines.front().line;
      defineSub(*o, lines, 0, lines.size() - 1);
    } else {
      if (prog_.flow_line == 0) prog_.flow_line = lines.front().line;
      const FlowResult r = runLines(lines, 0, lines.size());
      if (r.exit != FlowExit::Next)
        fail(lines.front().line, o->column, "O",
             "o" + r.label + " " + (r.exit == FlowExit::Return ? "return" : "break/continue") +
                 " outside the sub or loop it belongs to");
    }
    for (size_t k = 0; k < lines.size(); ++k)
      pushStatement(lines[k].text, k == 0 ? first_point : static_cast<int>(prog_.path.size()), "");
    sinkBlock();
  }

  // The line of lines[from..] that closes the construct opened at lines[at] (same label, the
  // closing keyword); a construct without one is refused naming it.
  size_t closing(const std::vector<SourceLine>& lines, size_t at, const OWord& open,
                 const std::string& keyword) {
    for (size_t k = at + 1; k < lines.size(); ++k) {
      const auto o = parseOWord(lines[k].text);
      if (o && o->label == open.label && o->keyword == keyword) return k;
    }
    fail(lines[at].line, open.column, "O",
         "o" + open.label + " " + open.keyword + " without its o" + open.label + " " + keyword);
  }

  // ---------------------------------------------------------------- Sinumerik control flow
  // SINUMERIK 840D sl Programming Manual, Job Planning, "Program jumps and branches" and
  // "Control structures": jump labels (NAME:), GOTOF/GOTOB/GOTO/GOTOC to a label or a block
  // number, IF cond GOTO.. (a conditional jump), IF ... ELSE ... ENDIF, WHILE ... ENDWHILE,
  // LOOP ... ENDLOOP, FOR var = a TO b ... ENDFOR, REPEAT ... UNTIL cond; conditions with == <>
  // < > <= >=, AND OR XOR NOT. From the first label or control word on, the file is held and
  // then carried out from there with a program counter (jumps go anywhere in it); its points
  // belong to the first held line's statement, each keeping its own line (flow_line). Refused by
  // name: CASE and subprogram calls, a jump to a label or block the held part does not hold
  // (GOTOC goes on), a structure without its end, loops beyond opt_.max_loop_passes and
  // opt_.max_flow_lines lines in all.
  struct SinFlowLine {
    std::string label;    // NAME when the line defines NAME: (else empty)
    long number = -1;     // its block number N..., -1 none
    std::string keyword;  // IF ELSE ENDIF WHILE ENDWHILE LOOP ENDLOOP FOR ENDFOR REPEAT UNTIL
                          // GOTOF GOTOB GOTO GOTOC CASE CALL ..., or empty
    std::string rest;     // after the keyword, upper case, comment out
    int column = 1;
  };

  // True when a line may hold a label or a control word (a cheap test before sinFlow).
  static bool mayFlow(const std::string& raw) {
    if (raw.find(':') != std::string::npos) return true;
    std::string u;
    for (char c : raw) {
      if (c == ';') break;
      u += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    }
    for (const char* w : {"IF", "GOTO", "WHILE", "LOOP", "FOR", "REPEAT", "UNTIL", "ELSE", "CASE",
                          "CALL", "RET", "M17", "PROC", "SAVE", "EXTERN"})
      if (u.find(w) != std::string::npos) return true;
    return false;
  }

  static SinFlowLine sinFlow(const std::string& raw) {
    static const std::set<std::string> words = {
        "IF",     "ELSE",   "ENDIF", "WHILE", "ENDWHILE", "LOOP", "ENDLOOP", "FOR",
        "ENDFOR", "REPEAT", "UNTIL", "GOTOF", "GOTOB",    "GOTO", "GOTOC",   "CASE",
        "CALL",   "PCALL",  "RET",   "M17",   "PROC",     "SAVE", "EXTERN"};
    SinFlowLine f;
    std::string u;
    bool str = false;
    for (char c : raw) {
      if (c == '"') str = !str;
      if (c == ';' && !str) break;
      u += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    }
    size_t i = 0;
    auto skip = [&] {
      while (i < u.size() && (u[i] == ' ' || u[i] == '\t')) ++i;
    };
    auto word = [&] {
      const size_t from = i;
      while (i < u.size() && (std::isalnum(static_cast<unsigned char>(u[i])) || u[i] == '_')) ++i;
      return u.substr(from, i - from);
    };
    auto digits = [](const std::string& w) {
      return w.size() > 1 && std::all_of(w.begin() + 1, w.end(), [](char c) {
               return std::isdigit(static_cast<unsigned char>(c)) != 0;
             });
    };
    skip();
    if (i < u.size() && u[i] == '/') {  // block delete: runs unless the switch is on
      ++i;
      skip();
    }
    size_t at = i;
    std::string w = word();
    if (w[0] == 'N' && digits(w)) {
      f.number = std::strtol(w.c_str() + 1, nullptr, 10);
      skip();
      at = i;
      w = word();
    }
    if (!w.empty() && i < u.size() && u[i] == ':' &&
        std::isalpha(static_cast<unsigned char>(w[0]))) {
      f.label = w;
      ++i;
      skip();
      at = i;
      w = word();
    }
    if (words.count(w) && (i >= u.size() || !std::isalnum(static_cast<unsigned char>(u[i])))) {
      f.keyword = w;
      f.rest = std::string(trim(std::string_view(u).substr(i)));
      f.column = static_cast<int>(at) + 1;
    }
    return f;
  }

  // A Sinumerik condition (or a value): its operators in the reader's bracket syntax.
  double sinCondition(const std::string& text, int line, int column) {
    const std::string e = sinOperators(text, line, column);
    line_ = line;
    const std::string b = sinBrackets("[" + e + "]");
    size_t i = 0;
    const double v = primary(b, i, column - 1);
    if (!trim(std::string_view(b).substr(i)).empty())
      fail(line, column, text.substr(0, 20), "unexpected text in the condition");
    return v;
  }

  // Sinumerik's comparisons (== <> < > <= >=) as the reader's EQ NE LT GT LE GE; its bit
  // operators (B_AND ...) are refused by name.
  std::string sinOperators(const std::string& text, int line, int column) {
    for (const char* w : {"B_AND", "B_OR", "B_XOR", "B_NOT"})
      if (text.find(w) != std::string::npos)
        fail(line, column, w, std::string("the bit operator ") + w + " is not evaluated");
    if (text.find_first_of("<>=") == std::string::npos) return text;
    std::string e;
    for (size_t k = 0; k < text.size(); ++k) {
      const char c = text[k], d = k + 1 < text.size() ? text[k + 1] : ' ';
      if (c == '"') fail(line, column, "\"", "a comparison of texts (STRING) is not evaluated");
      if (c == '=' && d == '=') {
        e += " EQ ";
        ++k;
      } else if (c == '<' && d == '>') {
        e += " NE ";
        ++k;
      } else if (c == '<' && d == '=') {
        e += " LE ";
        ++k;
      } else if (c == '>' && d == '=') {
        e += " GE ";
        ++k;
      } else if (c == '<') {
        e += " LT ";
      } else if (c == '>') {
        e += " GT ";
      } else {
        e += c;
      }
    }
    return e;
  }

  void runSinumerikTail() {
    std::vector<SourceLine> lines;
    const int first = static_cast<int>(prog_.lines.size()) + 1;
    bool flow = false;
    for (size_t k = 0; k < tail_.size(); ++k) {
      lines.push_back({first + static_cast<int>(k), tail_[k]});
      flow = flow || !sinFlow(tail_[k]).keyword.empty();
    }
    std::vector<std::string> tail;
    tail.swap(tail_);
    if (!flow) {  // labels alone: the lines as any others
      for (const std::string& t : tail) processLine(t);
      return;
    }
    const int first_point = static_cast<int>(prog_.path.size());
    prog_.flow_line = lines.front().line;
    runSinumerikFlow(lines);
    for (size_t k = 0; k < lines.size(); ++k)
      pushStatement(lines[k].text, k == 0 ? first_point : static_cast<int>(prog_.path.size()), "");
    sinkBlock();
  }

  // The structures of the held lines: each opening's partner and each IF's ELSE.
  struct SinStructure {
    std::vector<size_t> partner, else_of;
  };

  SinStructure sinStructure(const std::vector<SourceLine>& L, const std::vector<SinFlowLine>& f) {
    const size_t n = L.size();
    SinStructure st{std::vector<size_t>(n, n), std::vector<size_t>(n, n)};
    std::vector<size_t> open;
    for (size_t k = 0; k < n; ++k) {
      const std::string& kw = f[k].keyword;
      const bool jump_if = kw == "IF" && f[k].rest.find("GOTO") != std::string::npos;
      if (kw == "CASE" || kw == "CALL" || kw == "PCALL" || kw == "RET" || kw == "M17" ||
          kw == "PROC" || kw == "SAVE" || kw == "EXTERN")
        fail(L[k].line, f[k].column, kw,
             "Sinumerik " + kw +
                 " is not carried out (subprograms and CASE): post the program without it");
      if ((kw == "IF" && !jump_if) || kw == "WHILE" || kw == "LOOP" || kw == "FOR" ||
          kw == "REPEAT") {
        open.push_back(k);
        if (open.size() > static_cast<size_t>(kMaxFlowDepth))
          fail(L[k].line, f[k].column, kw, "control structures nested deeper than 100");
        continue;
      }
      const char* want = kw == "ELSE" || kw == "ENDIF" ? "IF"
                         : kw == "ENDWHILE"            ? "WHILE"
                         : kw == "ENDLOOP"             ? "LOOP"
                         : kw == "ENDFOR"              ? "FOR"
                         : kw == "UNTIL"               ? "REPEAT"
                                                       : nullptr;
      if (!want) continue;
      if (open.empty() || f[open.back()].keyword != want)
        fail(L[k].line, f[k].column, kw, kw + " without its " + want + " (or structures crossed)");
      if (kw == "ELSE") {
        st.else_of[open.back()] = k;
        continue;
      }
      const size_t head = open.back();
      open.pop_back();
      st.partner[head] = k;
      st.partner[k] = head;
      if (st.else_of[head] < n) st.partner[st.else_of[head]] = k;
    }
    if (!open.empty())
      fail(L[open.back()].line, f[open.back()].column, f[open.back()].keyword,
           f[open.back()].keyword + " without its end (the file ends first)");
    return st;
  }

  void runSinumerikFlow(const std::vector<SourceLine>& L) {
    const size_t n = L.size();
    std::vector<SinFlowLine> f(n);
    std::map<std::string, std::vector<size_t>> labels;
    std::map<long, std::vector<size_t>> numbers;
    for (size_t k = 0; k < n; ++k) {
      f[k] = sinFlow(L[k].text);
      if (!f[k].label.empty()) labels[f[k].label].push_back(k);
      if (f[k].number >= 0) numbers[f[k].number].push_back(k);
    }
    const SinStructure st = sinStructure(L, f);
    // A jump's target: a label or a block number, forward (GOTOF), backward (GOTOB) or either
    // (GOTO, GOTOC: forward first); n when none (GOTOC goes on).
    auto target = [&](size_t from, const std::string& how, const std::string& to) -> size_t {
      const std::string name(trim(std::string_view(to)));
      std::vector<size_t> at;
      const size_t d = !name.empty() && name[0] == 'N' ? 1 : 0;  // N90 or 90: a block number
      const bool block = name.size() > d &&
                         std::all_of(name.begin() + static_cast<long>(d), name.end(), [](char c) {
                           return std::isdigit(static_cast<unsigned char>(c)) != 0;
                         });
      if (block) {
        const auto it = numbers.find(std::strtol(name.c_str() + d, nullptr, 10));
        if (it != numbers.end()) at = it->second;
      } else {
        const auto it = labels.find(name);
        if (it != labels.end()) at = it->second;
      }
      size_t fwd = n, back = n;
      for (size_t a : at) {
        if (a > from && fwd == n) fwd = a;
        if (a < from) back = a;
      }
      const size_t t = how == "GOTOF" ? fwd : how == "GOTOB" ? back : fwd < n ? fwd : back;
      if (t == n && how != "GOTOC")
        fail(L[from].line, f[from].column, how,
             how + " " + name + ": no such label or block " +
                 (how == "GOTOF"   ? "after"
                  : how == "GOTOB" ? "before"
                                   : "in") +
                 " this line (in the program from its first label or control word on)");
      return t;
    };
    std::map<size_t, std::pair<std::string, double>> for_end;  // FOR line -> variable, end
    std::map<size_t, long> iterations;
    std::map<size_t, std::unordered_set<uint64_t>> passes;  // the variables at each pass
    auto iterate = [&](size_t at) {
      checkLoopProgress(passes[at], L[at].line, f[at].column, f[at].keyword);
      if (++iterations[at] > opt_.max_loop_passes)
        fail(L[at].line, f[at].column, f[at].keyword,
             f[at].keyword + " ran " + std::to_string(opt_.max_loop_passes) +
                 " times: a loop that does not end (or one too long to predict)");
    };
    auto jump = [&](size_t pc, const std::string& how, const std::string& to) {
      const size_t t = target(pc, how, to);
      if (t < n && t <= pc) iterate(pc);  // a backward jump: a loop
      return t < n ? t : pc + 1;
    };
    size_t pc = 0;
    while (pc < n && !ended_) {
      if (++flow_lines_ > opt_.max_flow_lines)
        fail(L[pc].line, 0, "O",
             "the program's loops and jumps carried out " + std::to_string(opt_.max_flow_lines) +
                 " lines: too long to predict (or a loop that does not end)");
      const SinFlowLine& x = f[pc];
      const std::string& kw = x.keyword;
      const int line = L[pc].line;
      line_ = line;
      if (kw.empty()) {
        runLine(line, L[pc].text);
        ++pc;
      } else if (kw == "GOTOF" || kw == "GOTOB" || kw == "GOTO" || kw == "GOTOC") {
        pc = jump(pc, kw, x.rest);
      } else if (kw == "IF" && st.partner[pc] == n) {  // IF condition GOTO.. label
        const size_t g = x.rest.find("GOTO");
        size_t e = g + 4;
        while (e < x.rest.size() && std::isalpha(static_cast<unsigned char>(x.rest[e]))) ++e;
        const std::string how = x.rest.substr(g, e - g);
        if (how != "GOTOF" && how != "GOTOB" && how != "GOTO" && how != "GOTOC")
          fail(line, x.column, how, "IF ... " + how + ": not a jump");
        pc = sinCondition(x.rest.substr(0, g), line, x.column) != 0.0
                 ? jump(pc, how, x.rest.substr(e))
                 : pc + 1;
      } else if (kw == "IF") {
        pc = sinCondition(x.rest, line, x.column) != 0.0 ? pc + 1
             : st.else_of[pc] < n                        ? st.else_of[pc] + 1
                                                         : st.partner[pc] + 1;
      } else if (kw == "ELSE") {
        pc = st.partner[pc] + 1;  // the true branch ran: past its ENDIF
      } else if (kw == "WHILE") {
        if (sinCondition(x.rest, line, x.column) != 0.0) {
          iterate(pc);
          ++pc;
        } else {
          pc = st.partner[pc] + 1;
        }
      } else if (kw == "ENDWHILE") {
        pc = st.partner[pc];
      } else if (kw == "ENDLOOP") {
        iterate(st.partner[pc]);
        pc = st.partner[pc] + 1;
      } else if (kw == "LOOP" || kw == "REPEAT" || kw == "ENDIF") {
        ++pc;
      } else if (kw == "UNTIL") {
        if (sinCondition(x.rest, line, x.column) != 0.0) {
          ++pc;
        } else {
          iterate(st.partner[pc]);
          pc = st.partner[pc] + 1;
        }
      } else if (kw == "FOR") {
        // FOR variable = start TO end: the variable runs start, start + 1, ... up to end.
        const size_t eq = x.rest.find('='), to = x.rest.find(" TO ");
        if (eq == std::string::npos || to == std::string::npos || to < eq)
          fail(line, x.column, "FOR", "expected FOR variable = start TO end");
        const std::string var(trim(std::string_view(x.rest).substr(0, eq)));
        bool r_parameter = var.size() > 1 && var[0] == 'R';
        for (size_t c = 1; c < var.size() && r_parameter; ++c)
          r_parameter = std::isdigit(static_cast<unsigned char>(var[c])) != 0;
        if (!sin_vars_.count(var) && !r_parameter)
          fail(line, x.column, var,
               "FOR: " + var + " is neither a declared variable (DEF) nor an R parameter");
        const double start = sinCondition(x.rest.substr(eq + 1, to - eq - 1), line, x.column);
        const double end = sinCondition(x.rest.substr(to + 4), line, x.column);
        sin_vars_[var] = start;
        for_end[pc] = {var, end};
        pc = start <= end ? pc + 1 : st.partner[pc] + 1;
      } else if (kw == "ENDFOR") {
        const size_t head = st.partner[pc];
        const auto& [var, end] = for_end[head];
        sin_vars_[var] += 1.0;
        iterate(head);
        pc = sin_vars_[var] <= end ? head + 1 : pc + 1;
      } else {
        fail(line, x.column, kw, "Sinumerik " + kw + " is not carried out");
      }
    }
  }

  // ---------------------------------------------------------------- ISO subprograms
  // Fanuc M98 P<program> [L<times>] calls program O<program> of the same file (Fanuc 0i-MF,
  // "Subprogram": the subprogram ends with M99, the call returns to the block after it); HAAS
  // M97 P<n> [L<times>] calls the local subroutine that starts at block N<n> and ends with M99
  // (HAAS Mill Operator's Manual, "M97 Local Sub-Program Call"). The subprograms follow the main
  // program's M30 in the file: a call holds the rest of the file (tail_), which is read again
  // once they are known. Each point keeps its line; a call's points belong to its line's
  // statement (ClProgram::flow_line). Refused by name: a call with axis words or other M codes
  // in its block, P given as repeats and number together (Fanuc's 8-digit P), a subprogram the
  // file does not hold, M99 anywhere but at a subprogram's end (in the main program it restarts
  // it: an endless program), M99 P (a return to a block number).
  struct IsoCall {
    std::string code;  // M98 or M97
    long number = 0;   // the program (M98) or block number (M97)
    long times = 1;    // L
    int column = 1;
  };

  // The M98/M97 call on a line, when it has one (comments out, upper case).
  std::optional<IsoCall> parseIsoCall(const std::string& raw) const {
    if (raw.find("98") == std::string::npos && raw.find("97") == std::string::npos)
      return std::nullopt;  // most lines: no M98/M97 (M098 holds 98 too)
    std::vector<int> col;
    const std::string c = compactLine(raw, &col);
    std::optional<IsoCall> call;
    std::map<char, std::string> words;
    for (size_t i = 0; i < c.size();) {
      const char l = c[i];
      size_t j = i + 1;
      while (j < c.size() && (std::isdigit(static_cast<unsigned char>(c[j])) || c[j] == '.' ||
                              c[j] == '-' || c[j] == '+'))
        ++j;
      const std::string v = c.substr(i + 1, j - i - 1);
      if (l == 'M' && (v == "98" || v == "97" || v == "098" || v == "097")) {
        call = IsoCall{v.back() == '8' ? "M98" : "M97", 0, 1, col[i]};
      } else if (std::isalpha(static_cast<unsigned char>(l))) {
        words[l] += (words.count(l) ? "," : "") + v;
      }
      if (j == i + 1) ++j;  // not a word: step on
      i = j;
    }
    if (!call) return std::nullopt;
    for (const auto& [l, v] : words) {
      if (l == 'P' || l == 'L' || l == 'N' || l == 'O') continue;
      call->number = -1;  // words beside the call: refused where it is carried out
      call->code += " with " + std::string(1, l) + v;
      return call;
    }
    if (!words.count('P')) {
      call->number = -2;
      return call;
    }
    call->number = std::strtol(words['P'].c_str(), nullptr, 10);
    if (words.count('L')) call->times = std::strtol(words['L'].c_str(), nullptr, 10);
    return call;
  }

  // A call at the top level: held with the rest of the file until the subprograms are read.
  void isoCallLine(const std::string& text, const IsoCall& call) {
    const int line = static_cast<int>(prog_.lines.size()) + 1;
    if (!replaying_) {
      tail_mode_ = true;
      tail_.push_back(text);
      return;
    }
    const int first_point = static_cast<int>(prog_.path.size());
    if (prog_.flow_line == 0) prog_.flow_line = line;
    line_ = line;
    any_ = true;
    runIsoCall(call, line);
    pushStatement(text, first_point, call.code);
    sinkBlock();
  }

  // LinuxCNC reads Fanuc's M98/M99 too (LinuxCNC M-code reference, "M98, M99"; its
  // tests/interp/m98m99), its #1-#30 global in them as Fanuc's; not HAAS's M97.
  bool isoSubprograms() const {
    return model_.control.dialect == "iso" || model_.control.dialect == "linuxcnc";
  }

  void runIsoCall(const IsoCall& call, int line) {
    if (call.code.rfind("M97", 0) == 0 && model_.control.dialect == "linuxcnc")
      fail(line, call.column, "M97",
           "M97 (HAAS's local subprogram call) is not a LinuxCNC code: LinuxCNC calls "
           "subprograms with M98 or o-word call");
    if (call.number == -1)
      fail(line, call.column, call.code.substr(0, 3),
           call.code +
               ": a subprogram call with other words in its block is not carried out: "
               "post the move and the call in separate blocks");
    if (call.number == -2)
      fail(line, call.column, call.code, call.code + " without P (the subprogram to call)");
    if (call.code == "M98" && call.number > 9999)
      fail(line, call.column, "P",
           "M98 P" + std::to_string(call.number) +
               ": a program number above 9999 (Fanuc's repeat count in P's upper digits?) is not "
               "read: write the repeats as L");
    if (!(call.times >= 0 && call.times <= 9999))
      fail(line, call.column, "L", "the repeat count L must be 0 to 9999");
    const std::string key = (call.code == "M98" ? "O" : "N") + std::to_string(call.number);
    const auto it = subs_.find(key);
    if (it == subs_.end())
      fail(line, call.column, call.code,
           call.code + " P" + std::to_string(call.number) + ": no " +
               (call.code == "M98" ? "program O" : "block N") + std::to_string(call.number) +
               " ending in M99 after the main program in this file (a program in the control's "
               "memory is not read): put the subprogram in the file or expand it in the post");
    if (call_depth_ >= kMaxCallDepth)
      fail(line, call.column, call.code,
           "calls nested deeper than " + std::to_string(kMaxCallDepth));
    if (!it->second.refuse.empty()) fail(line, call.column, call.code, it->second.refuse);
    ++call_depth_;
    const Sub sub = it->second;
    for (long n = 0; n < call.times && !ended_; ++n) {
      const FlowResult r = runLines(sub.body, 0, sub.body.size());
      if (r.exit != FlowExit::Next)
        fail(line, call.column, call.code, "an O-word return or loop exit in a subprogram");
    }
    --call_depth_;
    line_ = line;
  }

  // The subprograms of the file's tail: O<n> ... M99 and (for M97) N<n> ... M99 after the main
  // program's end (M2/M30).
  // True when a compact line (compactLine) holds the word M<code>: M2 and not M20 or M2 inside
  // another word.
  static bool hasMWord(const std::string& c, const char* code) {
    const std::string w = std::string("M") + code;
    for (size_t at = c.find(w); at != std::string::npos; at = c.find(w, at + 1)) {
      const size_t e = at + w.size();
      if ((at == 0 || !std::isalpha(static_cast<unsigned char>(c[at - 1]))) &&
          (e == c.size() || !std::isdigit(static_cast<unsigned char>(c[e]))))
        return true;
    }
    return false;
  }

  void defineIsoSubs(const std::vector<SourceLine>& lines) {
    std::vector<std::string> c(lines.size());
    for (size_t k = 0; k < lines.size(); ++k) c[k] = compactLine(lines[k].text);
    bool after_end = false;
    for (size_t k = 0; k < lines.size(); ++k) {
      const std::string& u = c[k];
      if (!after_end) {
        after_end = hasMWord(u, "30") || hasMWord(u, "2") || hasMWord(u, "02");
        continue;
      }
      if (u.empty() || (u[0] != 'O' && u[0] != 'N' && u[0] != ':')) continue;
      size_t j = 1;
      while (j < u.size() && std::isdigit(static_cast<unsigned char>(u[j]))) ++j;
      if (j == 1 || j > 10) continue;  // no number, or more digits than any control's
      const std::string key =
          std::string(1, u[0] == 'N' ? 'N' : 'O') + std::to_string(std::stol(u.substr(1, j - 1)));
      Sub sub;
      // An O line is the program's header; an N line is the subroutine's first block.
      size_t first = u[0] == 'N' ? k : k + 1;
      size_t e = first;
      while (e < lines.size() && !hasMWord(c[e], "99")) ++e;
      if (e == lines.size()) continue;  // no M99: not a subprogram
      sub.body.assign(lines.begin() + static_cast<long>(first),
                      lines.begin() + static_cast<long>(e));
      sub.end = lines[e];
      // The M99 block: M99 alone (and a block number). Another word there would be dropped with
      // it; a P returns elsewhere than to the call.
      std::string rest = c[e];
      for (const char* w : {"M99", "M099"})
        for (size_t at = rest.find(w); at != std::string::npos; at = rest.find(w))
          rest.erase(at, std::strlen(w));
      if (!rest.empty() && rest[0] == 'N') {
        size_t d = 1;
        while (d < rest.size() && std::isdigit(static_cast<unsigned char>(rest[d]))) ++d;
        rest.erase(0, d);
      }
      if (!rest.empty())
        sub.refuse = "the subprogram's M99 block at line " + std::to_string(lines[e].line) +
                     " holds other words (" + rest.substr(0, 20) + ")" +
                     (rest[0] == 'P' ? ": M99 P returns to a block number, not to the call"
                                     : ": post them in a block of their own");
      for (size_t b = k; b <= e; ++b) sub_lines_.insert(lines[b].line);
      if (!subs_.count(key)) subs_[key] = std::move(sub);
    }
  }

  // True when lines call a sub that is neither defined nor defined among them.
  bool callsUndefined(const std::vector<SourceLine>& lines) const {
    std::set<std::string> defined;
    std::vector<std::string> called;
    for (const SourceLine& l : lines) {
      const auto o = parseOWord(l.text);
      if (o && o->keyword == "sub") defined.insert(o->label);
      if (o && o->keyword == "call") called.push_back(o->label);
    }
    for (const std::string& c : called)
      if (!subs_.count(c) && !defined.count(c)) return true;
    return false;
  }

  // The file's tail held after a call of a sub not yet defined: its subs defined first (up to a
  // closing '%'), then its lines read in order as any others.
  void replayTail() {
    tail_mode_ = false;
    replaying_ = true;
    if (model_.control.dialect == "sinumerik") {
      runSinumerikTail();
      return;
    }
    std::vector<SourceLine> lines, all;
    int percents = percent_;
    const int first = static_cast<int>(prog_.lines.size()) + 1;
    for (size_t k = 0; k < tail_.size(); ++k) {
      all.push_back({first + static_cast<int>(k), tail_[k]});
      const std::string_view t = trim(tail_[k]);
      if (!t.empty() && t[0] == '%' && ++percents >= 2) continue;
      if (percents < 2) lines.push_back(all.back());
    }
    // ISO: a file may hold the subprograms as programs of their own after the main one's tape
    // ("%" ... "%" "%" O1001 ... M99 "%"): a control loads them all.
    if (isoSubprograms()) defineIsoSubs(all);
    for (size_t k = 0; k < lines.size(); ++k) {
      const auto o = parseOWord(lines[k].text);
      if (!o || o->keyword != "sub") continue;
      bool closed = false;
      for (size_t e = k + 1; e < lines.size() && !closed; ++e) {
        const auto c = parseOWord(lines[e].text);
        if (c && c->label == o->label && c->keyword == "endsub") {
          defineSub(*o, lines, k, e);
          k = e;
          closed = true;
        }
      }
    }
    std::vector<std::string> tail;
    tail.swap(tail_);
    for (const std::string& t : tail) processLine(t);
  }

  void defineSub(const OWord& o, const std::vector<SourceLine>& lines, size_t at, size_t end) {
    Sub s;
    s.body.assign(lines.begin() + static_cast<long>(at) + 1,
                  lines.begin() + static_cast<long>(end));
    s.end = lines[end];
    subs_[o.label] = std::move(s);
  }

  // The value of an O-word's expression (a condition, a count): its bracketed expression.
  double flowValue(const OWord& o, int line) {
    line_ = line;
    if (o.rest.empty() || o.rest[0] != '[')
      fail(line, o.column, "O", "o" + o.label + " " + o.keyword + " needs [expression]");
    size_t i = 0;
    const double v = primary(o.rest, i, o.column);
    if (!trim(std::string_view(o.rest).substr(i)).empty())
      fail(line, o.column, "O", "unexpected text after o" + o.label + " " + o.keyword + "'s [...]");
    return v;
  }

  void countIteration(long& n, const OWord& o, int line) {
    if (++n > opt_.max_loop_passes)
      fail(line, o.column, "O",
           "o" + o.label + " " + o.keyword + " ran " + std::to_string(opt_.max_loop_passes) +
               " times: a loop that does not end (or one too long to predict)");
  }

  // The program's variables (LinuxCNC's parameters, Sinumerik's DEF variables and R
  // parameters), hashed: a loop's conditions read nothing else (the controls' system variables of
  // position and state are refused), so a loop head reached twice in one run of the loop with
  // the same variables repeats forever. Said at once instead of after a million iterations
  // (seconds; a fuzzed Sinumerik WHILE whose step was 0 took 11 s).
  uint64_t variablesHash() const {
    uint64_t h = 14695981039346656037ull;
    auto mix = [&h](const void* p, size_t n) {
      const auto* b = static_cast<const unsigned char*>(p);
      for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
    };
    for (const auto& [k, v] : sin_vars_) mix(k.data(), k.size()), mix(&v, sizeof v);
    for (const auto& [k, v] : named_) mix(k.data(), k.size()), mix(&v, sizeof v);
    for (const auto& [k, v] : numbered_) mix(&k, sizeof k), mix(&v, sizeof v);
    return h;
  }

  // A loop's passes: refused when one starts with the variables of an earlier one.
  void checkLoopProgress(std::unordered_set<uint64_t>& seen, int line, int column,
                         const std::string& what) {
    if (!seen.insert(variablesHash()).second)
      fail(line, column, what,
           what +
               ": a loop that does not end (its variables come back to the values of an "
               "earlier pass)");
  }

  // Carries out lines[from, to); returns how control left them (a break, continue or return
  // goes to the construct it names).
  FlowResult runLines(const std::vector<SourceLine>& lines, size_t from, size_t to) {
    const ScopedDepth depth(flow_depth_);
    if (flow_depth_ > kMaxFlowDepth)
      fail(from < lines.size() ? lines[from].line : line_, 0, "O",
           "subs and control flow nested deeper than " + std::to_string(kMaxFlowDepth));
    for (size_t k = from; k < to; ++k) {
      if (ended_) return {};
      if (++flow_lines_ > opt_.max_flow_lines)
        fail(lines[k].line, 0, "O",
             "the program's subs and loops carried out " + std::to_string(opt_.max_flow_lines) +
                 " lines: too long to predict (or a loop that does not end)");
      if (isoSubprograms()) {
        if (const auto call = parseIsoCall(lines[k].text)) {
          line_ = lines[k].line;
          runIsoCall(*call, lines[k].line);
          continue;
        }
      }
      const std::optional<OWord> o = parseOWord(lines[k].text);
      if (!o) {
        runLine(lines[k].line, lines[k].text);
        continue;
      }
      const int line = lines[k].line;
      line_ = line;
      const std::string& kw = o->keyword;
      if (kw == "sub") {
        const size_t e = closing(lines, k, *o, "endsub");
        defineSub(*o, lines, k, e);
        k = e;
      } else if (kw == "call") {
        callSub(*o, line);
      } else if (kw == "while" || kw == "do" || kw == "repeat") {
        const size_t e = closing(lines, k, *o, closerOf(kw));
        const std::optional<OWord> end = parseOWord(lines[e].text);
        long n = 0;
        std::unordered_set<uint64_t> passes;  // while/do: the variables at each pass
        const double count = kw == "repeat" ? flowValue(*o, line) : 0.0;
        if (kw == "repeat" && !(count >= 0 && count <= opt_.max_loop_passes))
          fail(line, o->column, "O", "o" + o->label + " repeat count " + formatNumber(count));
        for (;;) {
          if (kw == "while" && flowValue(*o, line) == 0.0) break;
          if (kw == "repeat" && n >= std::lround(count)) break;
          countIteration(n, *o, line);
          if (kw != "repeat") checkLoopProgress(passes, line, o->column, "o" + o->label + " " + kw);
          const FlowResult r = runLines(lines, k + 1, e);
          if (ended_) return {};
          if (r.exit == FlowExit::Return || (r.exit != FlowExit::Next && r.label != o->label))
            return r;
          if (r.exit == FlowExit::Break) break;
          if (kw == "do" && flowValue(*end, lines[e].line) == 0.0) break;
        }
        k = e;
      } else if (kw == "if") {
        const size_t e = closing(lines, k, *o, "endif");
        // The branches: the if, each elseif, the else; the first whose condition holds runs.
        std::vector<size_t> at = {k};
        for (size_t j = k + 1; j < e; ++j) {
          const auto b = parseOWord(lines[j].text);
          if (b && b->label == o->label && (b->keyword == "elseif" || b->keyword == "else"))
            at.push_back(j);
        }
        at.push_back(e);
        for (size_t b = 0; b + 1 < at.size(); ++b) {
          const OWord head = *parseOWord(lines[at[b]].text);
          if (head.keyword != "else" && flowValue(head, lines[at[b]].line) == 0.0) continue;
          const FlowResult r = runLines(lines, at[b] + 1, at[b + 1]);
          if (r.exit != FlowExit::Next) return r;
          break;
        }
        k = e;
      } else if (kw == "break" || kw == "continue") {
        return {kw == "break" ? FlowExit::Break : FlowExit::Continue, o->label};
      } else if (kw == "return") {
        if (!o->rest.empty()) setReturnValue(flowValue(*o, line));
        return {FlowExit::Return, o->label};
      } else {
        fail(line, o->column, "O",
             "o" + o->label + " " + kw + " out of place (no construct of that label open here)");
      }
    }
    return {};
  }

  void setReturnValue(double v) {
    named_["_value"] = v;
    named_["_value_returned"] = 1.0;
  }

  // o<name> call [a1] [a2] ...: the sub's body with #1.. set to the arguments, in its own scope.
  void callSub(const OWord& o, int line) {
    const auto it = subs_.find(o.label);
    if (it == subs_.end())
      fail(line, o.column, "O",
           "o" + o.label + " call: no o" + o.label +
               " sub defined above it in this file (LinuxCNC would also look for it in the "
               "subroutine path, which tolver does not read): define it before the call");
    if (call_depth_ >= kMaxCallDepth)
      fail(line, o.column, "O", "calls nested deeper than " + std::to_string(kMaxCallDepth));
    std::vector<double> args;
    size_t i = 0;
    while (true) {
      while (i < o.rest.size() && o.rest[i] == ' ') ++i;
      if (i >= o.rest.size()) break;
      if (o.rest[i] != '[')
        fail(line, o.column, "O", "o" + o.label + " call: arguments are [expressions]");
      args.push_back(primary(o.rest, i, o.column));
      if (args.size() > 30) fail(line, o.column, "O", "more than 30 arguments");
    }
    // The call's scope: #1-#30 and the named parameters without a leading '_'.
    std::map<int, double> saved_numbered;
    for (int n = 1; n <= 30; ++n) {
      const auto s = numbered_.find(n);
      if (s != numbered_.end()) saved_numbered[n] = s->second;
      numbered_.erase(n);
    }
    std::map<std::string, double> saved_named;
    for (auto s = named_.begin(); s != named_.end();) {
      if (!s->first.empty() && s->first[0] != '_') {
        saved_named.insert(*s);
        s = named_.erase(s);
      } else {
        ++s;
      }
    }
    // #1-#30 take the arguments and 0 beyond them (LinuxCNC's interp_read.cc: "zero the
    // remaining params").
    for (int a = 0; a < 30; ++a)
      numbered_[a + 1] = a < static_cast<int>(args.size()) ? args[static_cast<size_t>(a)] : 0.0;
    named_["_value_returned"] = 0.0;
    ++call_depth_;
    autorestore_.resize(static_cast<size_t>(call_depth_));
    autorestore_.back().reset();
    const Sub sub = it->second;  // a copy: the body may define subs again
    const FlowResult r = runLines(sub.body, 0, sub.body.size());
    if (r.exit == FlowExit::Break || r.exit == FlowExit::Continue)
      fail(line, o.column, "O", "o" + r.label + " break/continue outside its loop in a sub");
    if (r.exit == FlowExit::Next && !ended_) {
      const auto end = parseOWord(sub.end.text);
      if (end && !end->rest.empty()) setReturnValue(flowValue(*end, sub.end.line));
    }
    // M73 in the sub: its modal state back on the return (not when the program ended in it).
    const std::optional<ModalState> restore = autorestore_.back();
    autorestore_.pop_back();
    --call_depth_;
    line_ = line;
    if (restore && !ended_) restoreModal(*restore);
    for (int n = 1; n <= 30; ++n) numbered_.erase(n);
    for (const auto& [n, v] : saved_numbered) numbered_[n] = v;
    for (auto s = named_.begin(); s != named_.end();)
      s = !s->first.empty() && s->first[0] != '_' ? named_.erase(s) : std::next(s);
    for (const auto& [n, v] : saved_named) named_[n] = v;
  }

  // True when a line can start a block: empty, a comment, '/', '#', ':' or 'O' or a word (a
  // letter then a number, a sign, '[', '#' or '='), or (Sinumerik) a name followed by '=', '(' or
  // an end of statement. An NX listing line ("Information listing created by") is not.
  bool looksLikeBlock(std::string_view line) const {
    line = trim(line);
    if (line.rfind("\xEF\xBB\xBF", 0) == 0) line = trim(line.substr(3));
    if (line.empty()) return true;
    const char c = line[0];
    if (c == '(' || c == ';' || c == '/' || c == '#' || c == ':' || c == '%') return true;
    if (!std::isalpha(static_cast<unsigned char>(c))) return false;
    if (line.size() == 1) return true;
    const char d = line[1];
    if (std::isdigit(static_cast<unsigned char>(d)) || d == '-' || d == '+' || d == '.' ||
        d == '[' || d == '#' || d == '=' || d == ' ' || d == '<')
      return c != 'I' || d != ' ';  // "I ..." is prose
    if (model_.control.dialect == "sinumerik") {
      size_t k = 0;
      while (k < line.size() &&
             (std::isalnum(static_cast<unsigned char>(line[k])) || line[k] == '_'))
        ++k;
      return k == line.size() || line[k] == '=' || line[k] == '(' || line[k] == ' ' ||
             line[k] == ';';
    }
    return (c == 'O' || c == 'o');  // a program name: "OFinal ToolPath"
  }

  // A line of the tape leader: kept as text, not read.
  void skipLine(const std::string& text) {
    AptStatement st;
    st.first_line = st.last_line = static_cast<int>(prog_.lines.size()) + 1;
    prog_.statements.push_back(st);
    prog_.lines.push(text, true);
  }

 private:
  [[noreturn]] void fail(int line, int column, const std::string& field, const std::string& msg) {
    throw InputError(prog_.file, line, column, field, msg);
  }

  static std::string lowerNoSpace(std::string_view s) {
    std::string o;
    for (char c : s)
      if (!std::isspace(static_cast<unsigned char>(c)))
        o += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return o;
  }

  // ---------------------------------------------------------------- machine coordinates
  // p_w of the tip for machine coordinates m at rotary joints zero: g0 + Gm m (see header).
  void prepareMachineCoordinates() {
    const int n = static_cast<int>(model_.axes.size());
    JointVector q0 = JointVector::Zero(n);
    Eigen::Vector3d tip0, axis0;
    nominal_.tipAndAxis(q0, &tip0, &axis0);
    g0_ = tip0 + model_.setup.gauge_length * axis0;
    const std::array<int, 3> order = prismaticWordOrder(model_);
    if (order[0] < 0) fail(0, 0, "machine", "G-code needs exactly three linear axes");
    for (int col = 0; col < 3; ++col) {
      const int a = order[col];
      JointVector q = q0;
      q[a] = 1.0;
      Eigen::Vector3d tip, axis;
      nominal_.tipAndAxis(q, &tip, &axis);
      Gm_.col(col) = (tip - tip0) * model_.axes[a].nc_sign;
      prismatic_[col] = a;
    }
    if (std::abs(Gm_.determinant()) < 1e-9)
      fail(0, 0, "machine", "the linear axes of this machine are not independent");
    Gm_inv_ = Gm_.inverse();
    spindle_m_ = Gm_inv_ * axis0;  // the spindle axis in machine coordinates
    // Work offsets: given ones as they are; others put their origin at the part zero.
    default_offset_ = -Gm_inv_ * g0_;
  }

  // A work offset selected: the axes stay where they are (a control moves only the axes a later
  // block names: Fanuc 0i-MF "Workpiece coordinate system", LinuxCNC "G54-G59.3"), so the
  // current position's program coordinates are those of the new offset.
  void selectWorkOffset(const std::string& name) {
    if (name != "G500") commanded_offsets_.insert(name);
    if (name == work_) return;
    const bool turned = rotationOf(work_) != rotationOf(name);
    work_ = name;
    last_offset_ = workOffset(work_);
    if (turned) applyG92Frame();  // LinuxCNC: each system keeps its own rotation
    cur_xyz_ = currentProgramXyz();
  }

  Eigen::Vector3d workOffset(const std::string& name) {
    if (name == "G500") return Eigen::Vector3d::Zero();  // Sinumerik: no settable offset
    auto set = set_offsets_.find(name);
    if (set != set_offsets_.end()) return set->second;
    auto it = model_.setup.work_offsets.find(name);
    if (it != model_.setup.work_offsets.end()) return it->second;
    if (!missing_offsets_.count(name)) missing_offsets_[name] = line_;
    return default_offset_;
  }

  // The length of tool offset h (default: the H in force).
  double toolLength() const { return toolLength(h_); }
  double toolLength(int h) const {
    const auto set = set_tool_lengths_.find(h);  // the program's own G10 L1 / L10
    if (set != set_tool_lengths_.end()) return set->second;
    auto it = model_.setup.tool_lengths.find(h);
    return it != model_.setup.tool_lengths.end() ? it->second : model_.setup.gauge_length;
  }

  // Joint vector from machine coordinates of the controlled point (prismatic) and the rotary
  // words (deg, program values), in joint mode.
  JointVector jointsFromMachine(const Eigen::Vector3d& m_controlled) const {
    JointVector q = q_;
    const Eigen::Vector3d m_gauge = m_controlled + (tlc_ ? toolLength() : 0.0) * spindle_m_;
    for (int k = 0; k < 3; ++k) q[prismatic_[k]] = model_.axes[prismatic_[k]].nc_sign * m_gauge[k];
    setRotaries(q);
    return q;
  }

  void setRotaries(JointVector& q) const {
    for (size_t a = 0; a < model_.axes.size(); ++a)
      if (model_.axes[a].isRotary()) q[a] = model_.axes[a].nc_sign * rot_word_[a] * kDegToRad;
  }

  // The machine coordinates of the controlled point that joint values q put there.
  Eigen::Vector3d machineOfJoints(const JointVector& q) const {
    Eigen::Vector3d m;
    for (int k = 0; k < 3; ++k) m[k] = model_.axes[prismatic_[k]].nc_sign * q[prismatic_[k]];
    return m - (tlc_ ? toolLength() : 0.0) * spindle_m_;
  }

  // ---------------------------------------------------------------- Sinumerik 840D
  // A Sinumerik block (Siemens SINUMERIK 840D sl Programming Manual, Fundamentals and Job
  // Planning) rewritten into ISO words that the rest of the reader carries out: DEF REAL/INT
  // declarations and NAME=expression assignments of constants (kept as variables; arithmetic
  // functions, DIV and MOD: sinFunction, term), ADDR=expression words (X=_X_HOME ->
  // X[_X_HOME]; X=IC(...) and the other dimensions: sinDimension), SUPA (non-modal machine
  // coordinates, as G53), G500 (no settable offset), TRANS/ATRANS (programmable translation),
  // T="name" and D (tool and its length offset; D0 switches it off), MCALL CYCLE81/82/83 (modal
  // drilling, RTP, RFP, SDIS, DP, DPR), CYCLE800() (swivel reset); MSG, CYCLE832 and the
  // path-control words listed as ignored. Jumps and control structures are carried out by
  // runSinumerikFlow (the lines never reach here); CASE, CALL and other constructs are refused
  // naming them.
  std::string sinumerikBlock(const std::string& upper, const std::vector<int>& col) {
    SinBlock b = sinTokens(upper, col);
    size_t t = 0;
    if (t < b.tok.size() && b.tok[t][0] == 'N' && b.tok[t].size() > 1 &&
        std::isdigit(static_cast<unsigned char>(b.tok[t][1])))
      ++t;  // the block number
    sin_turns_ = -1;
    sin_dim_.clear();
    if (t < b.tok.size() && b.tok[t] == "DEF") {
      sinDeclare(b, t);
      return "";
    }
    for (; t < b.tok.size(); ++t) t = sinWord(b, t);
    if (b.orient_given) b.out += orientationWords(b.orient, b.orient_column);
    sin_turns_ = b.turns;
    return b.out;
  }

  // One Sinumerik block being rewritten: its tokens with their columns, the ISO words written so
  // far, and the tool orientation (A3= B3= C3=, 0 where not given) gathered over the block.
  struct SinBlock {
    std::vector<std::string> tok;
    std::vector<int> col;
    std::string out;
    Eigen::Vector3d orient = Eigen::Vector3d::Zero();
    bool orient_given = false;
    int orient_column = 0;
    int turns = -1;  // TURN=: full circles added to the block's arc; -1 none
  };

  [[noreturn]] void sinRefuse(const SinBlock& b, size_t t, const std::string& why) {
    fail(line_, b.col[t], b.tok[t].substr(0, b.tok[t].find_first_of("(=")), why);
  }

  // Tokens separated by spaces outside parentheses and strings; an expression written with
  // spaces ("NAME = expr", "X=7 DIV 2", "R1 = R2 * 4") joined into one token: a token that ends
  // in '=' or an operator, or one that starts with '=' or an operator or is DIV or MOD, goes on
  // the one before it.
  static bool sinWordOperator(const std::string& w) {
    return w == "DIV" || w == "MOD" || w == "AND" || w == "OR" || w == "XOR" || w == "NOT" ||
           w == "B_AND" || w == "B_OR" || w == "B_XOR" || w == "B_NOT";
  }

  static bool sinJoins(const std::string& prev, const std::string& cur) {
    static const std::string ops = "=+-*/<>";
    if (prev.find('=') == std::string::npos && cur[0] != '=') return false;
    const size_t sp = prev.rfind(' ');
    return ops.find(prev.back()) != std::string::npos || ops.find(cur[0]) != std::string::npos ||
           sinWordOperator(cur) ||
           (sp != std::string::npos && sinWordOperator(prev.substr(sp + 1)));
  }

  static SinBlock sinTokens(const std::string& upper, const std::vector<int>& col) {
    SinBlock b;
    std::string cur;
    int depth = 0, start = 0;
    bool str = false;
    for (size_t k = 0; k <= upper.size(); ++k) {
      const char c = k < upper.size() ? upper[k] : ' ';
      if (c == '"') str = !str;
      if (!str && c == '(') ++depth;
      if (!str && c == ')') --depth;
      if (c == ' ' && depth <= 0 && !str) {
        if (!cur.empty()) {
          if (!b.tok.empty() && sinJoins(b.tok.back(), cur)) {
            const std::string& prev = b.tok.back();
            const size_t sp = prev.rfind(' ');
            const bool keep_space = sinWordOperator(cur) || (sp != std::string::npos &&
                                                             sinWordOperator(prev.substr(sp + 1)));
            b.tok.back() += (keep_space ? " " : "") + cur;
          } else {
            b.tok.push_back(cur);
            b.col.push_back(start);
          }
        }
        cur.clear();
        continue;
      }
      if (cur.empty()) start = k < col.size() ? col[k] : (col.empty() ? 1 : col.back());
      cur += c;
    }
    return b;
  }

  // DEF type name[=value], name2...: declared variables, 0 unless given.
  void sinDeclare(const SinBlock& b, size_t t) {
    if (t + 1 >= b.tok.size()) sinRefuse(b, t, "DEF without a type");
    const std::string type = b.tok[t + 1];
    static const std::set<std::string> types = {"REAL",   "INT",  "BOOL", "CHAR",
                                                "STRING", "AXIS", "FRAME"};
    const std::string base = type.substr(0, type.find('['));
    if (!types.count(base)) sinRefuse(b, t + 1, "unknown type in DEF");
    std::string rest;
    for (size_t k = t + 2; k < b.tok.size(); ++k) rest += b.tok[k];
    size_t p = 0;
    while (p < rest.size()) {
      size_t e = rest.find(',', p);
      if (e == std::string::npos) e = rest.size();
      const std::string item = rest.substr(p, e - p);
      const size_t eq = item.find('=');
      const std::string name = item.substr(0, eq);
      double v = 0.0;
      const bool text = base == "STRING" || base == "CHAR";
      if (eq != std::string::npos && !text) v = sinExpression(item.substr(eq + 1), b.col[t]);
      if (text) sin_texts_.insert(name);
      if (!name.empty()) sin_vars_[name] = v;
      p = e + 1;
    }
  }

  // Token t of a block: rewritten into ISO words, carried out (frames, tools, cycles), ignored
  // or refused. Returns the last token it used.
  size_t sinWord(SinBlock& b, size_t t) {
    static const std::set<std::string> flow = {
        "GOTO",     "GOTOF", "GOTOB",   "GOTOC", "IF",     "ELSE",   "ENDIF", "WHILE",
        "ENDWHILE", "LOOP",  "ENDLOOP", "FOR",   "ENDFOR", "REPEAT", "UNTIL", "CASE",
        "CALL",     "PCALL", "RET",     "M17",   "PROC",   "SAVE",   "EXTERN"};
    static const std::set<std::string> ignored = {
        "FNORM",   "COMPOF", "COMPON",  "COMPCURV", "COMPCAD", "SOFT",     "BRISK",    "SOFTA",
        "BRISKA",  "FFWON",  "FFWOF",   "CFC",      "CFTCP",   "CFIN",     "G60",      "G601",
        "G602",    "G603",   "G64",     "G641",     "G642",    "G643",     "G644",     "G645",
        "UPATH",   "SPATH",  "ORIAXES", "ORIVECT",  "STOPRE",  "G40",      "DIAMOF",   "CUT2D",
        "CUT2DF",  "CUT3DC", "G450",    "G451",     "WAITM",   "ORIAXPOS", "ORIEULER", "ORIRPY",
        "ORIPATH", "TOFFOF", "G93",     "G94",      "G95",     "M27",      "M29",      "M50",
        "M51",     "M65",    "M7",      "M8",       "M9",      "CYCLE832"};
    static const std::set<std::string> carried = {"MSG",      "G710",  "G700", "SETMS", "WORKPIECE",
                                                  "CYCLE800", "MCALL", "SUPA", "G500",  "TRANS",
                                                  "ATRANS",   "ROT",   "AROT", "T",     "D"};
    const std::string& k = b.tok[t];
    const size_t paren = k.find('(');
    const size_t eq = k.find('=');
    const std::string head = k.substr(0, std::min(paren, eq));
    if (k.back() == ':' && k.size() > 1) {
      // A jump label (NAME:) marks the block and does nothing; a jump to it (GOTOF, GOTOB...)
      // is refused where it is written. Posts write them as restart marks.
      ignored_.insert("jump labels");
      return t;
    }
    if (flow.count(head))
      sinRefuse(b, t,
                "Sinumerik " + head +
                    ": loops, jumps and subprograms are not supported: post the program "
                    "without them (expanded)");
    if (!carried.count(head) && ignored.count(head)) {
      ignored_.insert(head);
      return t;
    }
    if (head == "G110" || head == "G111" || head == "G112")
      sinRefuse(b, t,
                "Sinumerik " + head +
                    " sets the pole of polar coordinates (AP=, RP=), which are not supported");
    if (head == "ORIWKS" || head == "ORIMKS") {
      orimks_ = head == "ORIMKS";
    } else if (head == "MSG" || head == "SETMS" || head == "WORKPIECE") {
      ignored_.insert(head);
    } else if (head == "G710" || head == "G700") {
      b.out += (head == "G710" ? " G21" : " G20");
    } else if (head == "SUPA" || head == "G153") {
      // SUPA and G153 suppress the frames (G153 with the base frame, SUPA also the handwheel
      // and external offsets, which a machine file does not carry): machine coordinates, as G53
      // (SINUMERIK 840D sl Programming Manual, Fundamentals, "Frame suppression"). G153 was
      // ignored, and its block read in the work offset.
      b.out += " G53";
    } else if (head == "G500") {
      selectWorkOffset("G500");
    } else if (head == "T") {
      sinTool(eq == std::string::npos ? k.substr(1) : k.substr(eq + 1));
    } else if (head == "CYCLE800") {
      cycle800(k, b.col[t]);
    } else if (head == "MCALL") {
      if (t + 1 >= b.tok.size()) {
        sin_mcall_ = false;  // MCALL alone ends the modal call
        cycle_ = false;
        return t;
      }
      sinCycle(b.tok[t + 1], b.col[t + 1], /*modal=*/true);
      return t + 1;
    } else if (head.rfind("CYCLE", 0) == 0 && paren != std::string::npos) {
      sinCycle(k, b.col[t], /*modal=*/false);  // once, where the block ends
      sin_cycle_here_ = true;
    } else if (head == "TRANS" || head == "ATRANS" || head == "ROT" || head == "AROT") {
      return sinFrame(b, t, head);
    } else if (head == "D") {
      b.out += " " + k;
    } else if (eq != std::string::npos && (paren == std::string::npos || eq < paren)) {
      sinAssign(b, t, k.substr(0, eq), k.substr(eq + 1));
    } else if (paren != std::string::npos && (head == "FGROUP" || head == "GROUP_BEGIN" ||
                                              head == "GROUP_END" || head == "SETPIECE")) {
      // The feed's reference axes, the program's grouping for the control's editor (Operate's
      // program structure) and the piece counter: no effect on the path.
      ignored_.insert(head);
    } else if (paren != std::string::npos) {
      sinRefuse(b, t,
                "Sinumerik " + head +
                    "(...) is not supported: a cycle or function tolver does "
                    "not know (post it as motion)");
    } else if (std::isalpha(static_cast<unsigned char>(k[0])) && k.size() > 1 &&
               std::isalpha(static_cast<unsigned char>(k[1])) && !tcpWordName(k)) {
      // A TCP name the machine file does not declare goes on for the ISO path to name it.
      if (k != "TRAORI" && k != "TRAFOOF")
        sinRefuse(b, t, "Sinumerik instruction " + k + " is not supported");
      b.out += " " + k;
    } else {
      b.out += " " + k;
    }
    return t;
  }

  // T="name", T=number or T5: the tool selected.
  void sinTool(const std::string& v) {
    tool_name_ = v.size() >= 2 && v.front() == '"' ? v.substr(1, v.size() - 2) : v;
    bool digits = !tool_name_.empty() && tool_name_.size() < 8;
    for (char ch : tool_name_) digits = digits && std::isdigit(static_cast<unsigned char>(ch));
    selected_tool_ = digits ? "T" + std::to_string(std::stoi(tool_name_)) : tool_name_;
  }

  // The programmable frame (SINUMERIK Fundamentals, "Frames"): TRANS and ROT replace it, ATRANS
  // and AROT add to it; several angles in one ROT/AROT turn about Z, then Y, then X (RPY, the
  // control's default); an angle turns the coordinate system counter-clockwise seen from the
  // positive axis. Program coordinates x map into the settable frame as frame_ * x. Returns the
  // last token of the instruction.
  size_t sinFrame(const SinBlock& b, size_t t, const std::string& head) {
    Eigen::Vector3d v = Eigen::Vector3d::Zero();
    size_t u = t + 1;
    for (; u < b.tok.size(); ++u) {
      const std::string& a = b.tok[u];
      const char l = a[0];
      if (a.rfind("RPL=", 0) == 0 && head.find("ROT") != std::string::npos) {
        // RPL: a rotation in the working plane, about its normal (G17: Z, G18: Y, G19: X).
        v[plane_] += sinExpression(a.substr(4), b.col[u]);
        continue;
      }
      if (a.size() < 2 || (l != 'X' && l != 'Y' && l != 'Z')) {
        if (a.size() >= 2 && std::isalpha(static_cast<unsigned char>(l)) &&
            (std::isdigit(static_cast<unsigned char>(a[1])) || a[1] == '=' || a[1] == '-'))
          sinRefuse(b, u,
                    head + " with " + std::string(1, l) + " (not X, Y or Z) is not supported");
        break;
      }
      const std::string e = a[1] == '=' ? a.substr(2) : a.substr(1);
      v[l - 'X'] = sinExpression(e, b.col[u]);
    }
    Eigen::Isometry3d change = Eigen::Isometry3d::Identity();
    if (head == "TRANS" || head == "ATRANS") {
      change.translation() = v * unit_;
    } else {
      change.linear() = (Eigen::AngleAxisd(v.z() * kDegToRad, Eigen::Vector3d::UnitZ()) *
                         Eigen::AngleAxisd(v.y() * kDegToRad, Eigen::Vector3d::UnitY()) *
                         Eigen::AngleAxisd(v.x() * kDegToRad, Eigen::Vector3d::UnitX()))
                            .toRotationMatrix();
    }
    pframe_ = head[0] == 'A' ? Eigen::Isometry3d(pframe_ * change) : change;
    setFrame(swivel_ * pframe_);
    return u - 1;
  }

  // NAME=expression: the tool orientation (A3= B3= C3=), a circle radius (CR=), an address with
  // an expression (X=...), or a variable's value; words that change the path are refused.
  void sinAssign(SinBlock& b, size_t t, const std::string& name, const std::string& expr) {
    if (name == "A3" || name == "B3" || name == "C3") {
      b.orient[name[0] - 'A'] = sinExpression(expr, b.col[t]);
      b.orient_given = true;
      if (b.orient_column == 0) b.orient_column = b.col[t];
      return;
    }
    if (name == "TURN") {
      // Helical interpolation's additional full circles, 0 to 999 (SINUMERIK 840D sl
      // Programming Manual, Fundamentals, 6FC5398-1BP40-0BA0, "Helical interpolation (G2/G3,
      // TURN)": the full circles first, then the arc to the end point; the infeed axis moves
      // over the whole helix). Carried out by the arc as LinuxCNC's P (turns = TURN + 1).
      const double n = sinExpression(expr, b.col[t]);
      if (!(n >= 0 && n <= 999 && n == std::round(n)))
        sinRefuse(b, t, "TURN= must be a whole number of full circles from 0 to 999");
      b.turns = static_cast<int>(n);
      return;
    }
    if (name == "FP") {
      // G75's fixed point number (1 to 4): which one does not matter, none being known.
      ignored_.insert("FP=");
      return;
    }
    // Spindle words of a multi-spindle control: S<n>= spindle n's speed, SPOS=/SPOSA= its
    // positioning (stopped, oriented), M<n>= its M function (3, 4, 5 turning and stopped, 19
    // oriented, 40-45 gear ranges, 70 axis mode): no effect on the tool's path.
    const bool spindle_number = !sin_vars_.count(name) && name.size() > 1 && name.size() < 4 &&
                                std::all_of(name.begin() + 1, name.end(), [](char c) {
                                  return std::isdigit(static_cast<unsigned char>(c)) != 0;
                                });
    if (name == "SPOS" || name == "SPOSA" || (spindle_number && name[0] == 'S') ||
        name.rfind("SPOS[", 0) == 0) {
      ignored_.insert(name[0] == 'S' && spindle_number ? "S<n>= (spindle speed)" : name + "=");
      return;
    }
    if (spindle_number && name[0] == 'M') {
      const double v = sinExpression(expr, b.col[t]);
      static const std::set<double> harmless = {3, 4, 5, 19, 40, 41, 42, 43, 44, 45, 70};
      if (!harmless.count(v))
        sinRefuse(b, t,
                  "Sinumerik " + name + "=" + formatNumber(v) + ": an M function of spindle " +
                      name.substr(1) +
                      " that tolver does not know (M3, M4, M5, M19, M40-M45, M70 are read)");
      ignored_.insert("M<n>= (spindle functions)");
      return;
    }
    if (name == "ADIS" || name == "ADISPOS") {
      // G641's rounding distance for path (ADIS) and rapid (ADISPOS) blocks: how far from a
      // corner the control may blend, as G64's tolerance; the programmed path is read.
      ignored_.insert(name + "=");
      return;
    }
    if (name == "CR") {
      // Circle radius (G2/G3 ... CR=, negative beyond 180 deg): the ISO R form.
      b.out += " R[" + sinBrackets(expr) + "]";
      return;
    }
    static const std::set<std::string> motion_names = {
        "A2",  "B2",  "C2", "A4",  "B4",   "C4",   "A5",   "B5",    "C5",  "A6",
        "B6",  "C6",  "A7", "B7",  "C7",   "LEAD", "TILT", "THETA", "PO",  "PSI",
        "XH",  "YH",  "ZH", "RND", "RNDM", "CHR",  "CHF",  "AP",    "RP",  "AR",
        "ANG", "CIP", "I1", "J1",  "K1",   "SF",   "OFFN", "DISC",  "DISR"};
    if (motion_names.count(name))
      sinRefuse(b, t,
                "Sinumerik " + name +
                    "= (orientation angles, normals, rounding, chamfers, contour offsets, "
                    "polar or circle-angle programming) changes the path and is not supported");
    if (name.size() == 1 && std::isalpha(static_cast<unsigned char>(name[0]))) {
      b.out += " " + name + "[" + sinBrackets(sinDimension(b, t, name[0], expr)) + "]";
      return;
    }
    if (name.empty()) sinRefuse(b, t, "an assignment without a name");
    // A name the program did not declare (DEF) and not an R parameter is an address with a
    // meaning on the control (an orientation, path or spindle word): not a variable.
    bool r_parameter = name.size() > 1 && name[0] == 'R';
    for (size_t c = 1; c < name.size() && r_parameter; ++c)
      r_parameter = std::isdigit(static_cast<unsigned char>(name[c])) != 0;
    if (!sin_vars_.count(name) && !r_parameter)
      sinRefuse(b, t,
                "Sinumerik " + name +
                    "= is neither a variable the program declares (DEF) nor an "
                    "R parameter: an address tolver does not carry out");
    // A STRING or CHAR variable takes text, which moves nothing.
    if (sin_texts_.count(name)) {
      if (expr.size() < 2 || expr.front() != '"' || expr.back() != '"')
        sinRefuse(b, t, name + " is a STRING variable: only a quoted text is carried (\"...\")");
      ignored_.insert("STRING assignment");
      return;
    }
    // An assignment: constant expressions only (a value computed from motion is refused by the
    // expression's own check).
    sin_vars_[name] = sinExpression(expr, b.col[t]);
  }

  // An axis word's dimension (SINUMERIK 840D sl Programming Manual, Fundamentals,
  // "Absolute dimensions (G90, AC)", "Incremental dimensions (G91, IC)", "Absolute dimensions
  // for rotary axes (DC, ACP, ACN)"): X=IC(v) is incremental and X=AC(v) absolute in this block
  // whatever G90/G91 says; I=AC(v) puts an arc centre absolute; C=DC(v) turns a modulo rotary
  // axis to v by the shortest way, ACP in the positive and ACN in the negative sense. Returns
  // the value's expression; the mode is kept in sin_dim_ for target() and the rotary words.
  std::string sinDimension(const SinBlock& b, size_t t, char letter, const std::string& expr) {
    const size_t open = expr.find('(');
    if (open == std::string::npos || expr.back() != ')') return expr;
    const std::string mode = expr.substr(0, open);
    if (mode != "IC" && mode != "AC" && mode != "DC" && mode != "ACP" && mode != "ACN") return expr;
    // The parenthesis that opens must close at the end: IC(1)+IC(2) is not one dimension.
    int depth = 0;
    for (size_t k = open; k < expr.size(); ++k) {
      depth += expr[k] == '(' ? 1 : expr[k] == ')' ? -1 : 0;
      if (depth == 0 && k + 1 != expr.size()) return expr;
    }
    const bool linear = letter == 'X' || letter == 'Y' || letter == 'Z';
    const bool centre = letter == 'I' || letter == 'J' || letter == 'K';
    const auto axis = letter_axis_.find(letter);
    const bool rotary = axis != letter_axis_.end() && model_.axes[axis->second].isRotary();
    if (!linear && !centre && !rotary)
      sinRefuse(b, t,
                std::string(1, letter) + "=" + mode +
                    "(...): a dimension on a word that is not "
                    "an axis of this machine or an arc centre");
    if (centre && mode != "AC" && mode != "IC")
      sinRefuse(b, t, std::string(1, letter) + "=" + mode + "(...): an arc centre takes AC or IC");
    if (mode.size() >= 2 && mode != "AC" && mode != "IC") {
      if (!rotary)
        sinRefuse(b, t,
                  mode + " (absolute with a direction) is for a rotary axis, not " +
                      std::string(1, letter));
      if (!model_.axes[axis->second].endless)
        sinRefuse(b, t,
                  mode + " on " + std::string(1, letter) +
                      " is for a modulo rotary axis, and the machine file gives " +
                      model_.axes[axis->second].name +
                      " stops (mark it endless=\"true\" if it turns without them)");
    }
    sin_dim_[letter] = mode;
    return expr.substr(open + 1, expr.size() - open - 2);
  }

  // The rotary word's value (deg) after a block: absolute or incremental as the block says, and
  // a modulo target (DC, ACP, ACN) taken the way the control turns from the current angle.
  double rotaryWordValue(char letter, double current, double v) const {
    const auto it = sin_dim_.find(letter);
    const std::string mode = it == sin_dim_.end() ? std::string() : it->second;
    if (mode == "IC" || (mode.empty() && !absolute_)) return current + v;
    if (mode.empty() || mode == "AC") return v;
    const double m = std::fmod(v, 360.0);
    const double target = m < 0.0 ? m + 360.0 : m;  // 0 <= target < 360
    double d = std::fmod(target - current, 360.0);  // (-360, 360)
    if (mode == "DC") {
      if (d > 180.0) d -= 360.0;
      if (d < -180.0) d += 360.0;
    } else if (mode == "ACP") {
      if (d < 0.0) d += 360.0;
    } else if (d > 0.0) {  // ACN
      d -= 360.0;
    }
    return current + d;
  }

  bool tcpWordName(const std::string& k) const {
    for (const auto& [on, off] : model_.control.tcp_words)
      if (k == on || k == off) return true;
    return false;
  }

  // A new frame (swivel and programmable frames composed): the current position kept, in the
  // new frame's coordinates. The points after it carry it (ClProgram::frames).
  void setFrame(const Eigen::Isometry3d& f) {
    frame_line_ = line_;
    frame_moved_.fill(true);
    const Eigen::Vector3d settable = frame_ * cur_xyz_;
    frame_ = f;
    cur_xyz_ = frame_.inverse() * settable;
    frame_checked_ = false;
    ClFrame c;
    c.T = frame_;
    prog_.frames.push_back(c);
    frame_index_ = static_cast<int>(prog_.frames.size()) - 1;
  }

  // CYCLE800, swivel plane (SINUMERIK 840D sl Programming Manual, Job Planning / Cycles,
  // "Swivel plane - CYCLE800"):
  //   CYCLE800(_FR, _TC, _ST, _MODE, _X0, _Y0, _Z0, _A, _B, _C, _X1, _Y1, _Z1, _DIR, _FR_I, _DMODE)
  // CYCLE800() and _TC="0" deselect the swivel frame. Otherwise the swivel frame becomes
  //   TRANS X0 Y0 Z0 (reference point of the rotation) : rotation : TRANS X1 Y1 Z1 (zero point
  //   of the swivelled plane),
  // new (_ST units digit 0) or added to the one in force (1). _MODE bits 7-6 give the swivel
  // mode: 00 axis by axis, the angles _A, _B, _C about the axes bits 1-0, 3-2, 5-4 name
  // (01 X, 10 Y, 11 Z), each about the axis already turned (57: X, Y, Z; 27: Z, Y, X);
  // 11 rotary axes direct, _A and _B the positions of rotary axes 1 and 2 (<control
  // swivel_axes>, by default the tilting axis first), the frame the one they turn the tool
  // frame by. Solid and projection angles are refused by name. The rotaries turn the tool
  // along the new z: of the two solutions, _DIR -1 takes the lower value of rotary axis 1
  // (the direction reference), +1 the higher, unless only one lies inside travel (as the
  // control does); _DIR 0 leaves them where the program puts them. From here the machine
  // holds the tool tip at the program's points in the swivelled frame (as in TCP mode), until
  // CYCLE800() or a deselection. The retraction (_FR, _FR_I) and the swivel motion itself are
  // not points of the path; the other digits of _ST (tool follow-up) do not change the points.
  void cycle800(const std::string& k, int column) {
    const size_t paren = k.find('(');
    if (paren == std::string::npos || k.back() != ')')
      fail(line_, column, "CYCLE800", "expected CYCLE800(...)");
    const std::string args = k.substr(paren + 1, k.size() - paren - 2);
    std::vector<std::string> a;
    {
      std::string cur;
      bool str = false;
      for (char c : args) {
        if (c == '"') str = !str;
        if (c == ',' && !str) {
          a.push_back(std::string(trim(cur)));
          cur.clear();
        } else {
          cur += c;
        }
      }
      a.push_back(std::string(trim(cur)));
    }
    auto num = [&](size_t n, const char* field) -> double {
      if (n >= a.size() || a[n].empty()) return 0.0;
      try {
        return sinExpression(a[n], column);
      } catch (const InputError&) {
        fail(line_, column, std::string("CYCLE800 ") + field,
             "expected a number, found '" + a[n] + "'");
      }
      return 0.0;
    };
    bool any = false;
    for (const std::string& v : a) any = any || !v.empty();
    const std::string tc = a.size() > 1 ? a[1] : "";
    if (!any || tc == "\"0\"" || tc == "0") {
      swivel_ = Eigen::Isometry3d::Identity();
      swivel_on_ = false;
      setFrame(swivel_ * pframe_);
      cur_xyz_ = currentProgramXyz();
      prog_.notes.push_back("line " + std::to_string(line_) +
                            ": CYCLE800 deselects the swivel frame");
      return;
    }
    const double st = num(2, "_ST"), mode_v = num(3, "_MODE"), dir_v = num(13, "_DIR");
    if (!(st >= 0 && st < 1e9) || std::floor(st) != st)
      fail(line_, column, "CYCLE800 _ST", "expected a whole number");
    if (!(mode_v >= 0 && mode_v <= 255) || std::floor(mode_v) != mode_v)
      fail(line_, column, "CYCLE800 _MODE", "expected a whole number from 0 to 255");
    if (!(dir_v == -1 || dir_v == 0 || dir_v == 1))
      fail(line_, column, "CYCLE800 _DIR", "expected -1, 0 or +1");
    const int mode = static_cast<int>(mode_v), dir = static_cast<int>(dir_v);
    const int st_units = static_cast<int>(std::fmod(st, 10.0));
    if (st_units > 1)
      fail(line_, column, "CYCLE800 _ST",
           "swivel type " + std::to_string(st_units) +
               " (units digit) is not known: 0 new, 1 additive");
    const std::vector<int> rot = swivelAxes();
    if (rot.size() != 2)
      fail(line_, column, "CYCLE800", "swivelling needs a machine with two rotary axes");
    const Eigen::Vector3d p0(num(4, "_X0"), num(5, "_Y0"), num(6, "_Z0"));
    const Eigen::Vector3d p1(num(10, "_X1"), num(11, "_Y1"), num(12, "_Z1"));
    const double A = num(7, "_A"), B = num(8, "_B"), C = num(9, "_C");
    const int swivel_mode = (mode >> 6) & 3;
    Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
    JointVector q = q_;
    setRotaries(q);
    bool positioned = false;
    if (swivel_mode == 0) {
      const double ang[3] = {A, B, C};
      for (int r = 0; r < 3; ++r) {
        const int code = (mode >> (2 * r)) & 3;
        if (code == 0 && ang[r] != 0.0)
          fail(line_, column, "CYCLE800 _MODE",
               "_MODE " + std::to_string(mode) + " names no axis for angle " + "ABC"[r] + "");
        if (code == 0) continue;
        R = R * Eigen::AngleAxisd(ang[r] * kDegToRad, Eigen::Vector3d::Unit(code - 1))
                    .toRotationMatrix();
      }
    } else if (swivel_mode == 3) {
      // Rotary axes direct: the frame is the turn they give the tool frame.
      const double words[2] = {A, B};
      JointVector q0 = q;
      for (int r = 0; r < 2; ++r) {
        const Axis& ax = model_.axes[rot[r]];
        q[rot[r]] = ax.nc_sign * words[r] * kDegToRad;
        q0[rot[r]] = 0.0;
        if (!ax.endless && (q[rot[r]] < ax.travel_min - 1e-9 || q[rot[r]] > ax.travel_max + 1e-9))
          fail(line_, column, "CYCLE800",
               "rotary axis " + ax.name + " " + formatNumber(words[r]) +
                   " deg (direct mode) is outside its travel");
      }
      const Eigen::Matrix3d w_R_t = nominal_.w_T_t(q).linear(),
                            w_R_t0 = nominal_.w_T_t(q0).linear();
      R = Gm_inv_ * w_R_t * w_R_t0.transpose() * Gm_;
      positioned = true;
    } else {
      fail(line_, column, "CYCLE800 _MODE",
           std::string(swivel_mode == 1 ? "solid angles" : "projection angles") + " (_MODE " +
               std::to_string(mode) +
               ") are not supported: post the swivel axis by "
               "axis (_MODE 57 or 27) or with the rotary axes direct (_MODE 192)");
    }
    Eigen::Isometry3d S = Eigen::Isometry3d::Identity();
    S.translation() = p0 * unit_;
    S.linear() = R;
    Eigen::Isometry3d T1 = Eigen::Isometry3d::Identity();
    T1.translation() = p1 * unit_;
    S = S * T1;
    swivel_ = st_units == 1 && swivel_on_ ? Eigen::Isometry3d(swivel_ * S) : S;
    swivel_on_ = true;
    setFrame(swivel_ * pframe_);
    if (!positioned && dir != 0) {
      // The tool along the new z: the rotary solution the direction picks.
      const Eigen::Vector3d u_w = Gm_ * frame_.linear() * Eigen::Vector3d::UnitZ();
      const std::vector<JointVector> ok =
          rotarySolutions(u_w, q, column, "CYCLE800", "the swivelled plane");
      size_t pick = 0;
      if (ok.size() == 2) {
        const Axis& ref = model_.axes[rot[0]];
        const double w0 = ref.nc_sign * ok[0][rot[0]], w1 = ref.nc_sign * ok[1][rot[0]];
        if (std::abs(w0 - w1) > 1e-9) pick = (dir > 0) == (w1 > w0) ? 1 : 0;
      }
      q = ok[pick];
      positioned = true;
    }
    if (positioned) {
      for (int r : rot) rot_word_[r] = model_.axes[r].nc_sign * q[r] / kDegToRad;
      setRotaries(q_);
    }
    cur_xyz_ = currentProgramXyz();
    std::string words;
    for (int r : rot) words += " " + model_.axes[r].name + formatWith("%.3f", rot_word_[r] + 0.0);
    prog_.notes.push_back(
        "line " + std::to_string(line_) + ": CYCLE800 swivels the working plane" +
        (positioned ? " (rotaries to" + words + ")" : " (rotaries as the program puts them)") +
        "; the points after it are held in the swivelled frame until CYCLE800()");
  }

  // G68.2, tilted working plane (Fanuc 30i-B Operator's Manual, "Tilted working plane indexing";
  // HAAS NGC mill manual, G68.2): G68.2 X Y Z I J K, the feature coordinate system's origin in
  // the workpiece coordinates and its Euler angles (P0, the default: I about Z, J about the new
  // X, K about the new Z; P1: roll I about X, pitch J about Y, yaw K about Z, fixed axes). Other
  // P forms are refused. G53.1 turns the rotaries so that the tool lies along the plane's +Z:
  // of the two solutions, the one nearer the axes' positions (said in a note: the control's
  // parameters may pick the other; the points are the same, the joints not). While the plane is
  // active the machine holds the tool tip at the program's points in it (as in TCP mode); G69
  // cancels it.
  std::string tiltedPlane(const std::map<char, const Word*>& aw, const Word* g682,
                          const Word* g531) {
    auto value = [&](char l) { return aw.count(l) ? aw.at(l)->value : 0.0; };
    if (g682) {
      const double form_v = value('P');
      const int form = form_v == 0.0 ? 0 : form_v == 1.0 ? 1 : -1;
      if (form < 0)
        fail(line_, g682->column, "G68.2",
             "G68.2 P" + formatNumber(form_v) +
                 " (three points, two vectors or "
                 "projection angles) is not supported: post Euler angles (P0) or "
                 "roll-pitch-yaw (P1)");
      if (rotaryCount() != 2)
        fail(line_, g682->column, "G68.2",
             "a tilted working plane needs a machine with two rotary axes");
      const double I = value('I') * kDegToRad, J = value('J') * kDegToRad,
                   K = value('K') * kDegToRad;
      Eigen::Matrix3d R;
      if (form == 0)
        R = (Eigen::AngleAxisd(I, Eigen::Vector3d::UnitZ()) *
             Eigen::AngleAxisd(J, Eigen::Vector3d::UnitX()) *
             Eigen::AngleAxisd(K, Eigen::Vector3d::UnitZ()))
                .toRotationMatrix();
      else
        R = (Eigen::AngleAxisd(K, Eigen::Vector3d::UnitZ()) *
             Eigen::AngleAxisd(J, Eigen::Vector3d::UnitY()) *
             Eigen::AngleAxisd(I, Eigen::Vector3d::UnitX()))
                .toRotationMatrix();
      Eigen::Isometry3d S = Eigen::Isometry3d::Identity();
      S.translation() = Eigen::Vector3d(value('X'), value('Y'), value('Z')) * unit_;
      S.linear() = R;
      swivel_ = S;
      swivel_on_ = true;
      setFrame(swivel_ * pframe_);
      cur_xyz_ = currentProgramXyz();
    }
    if (g531) {
      if (!swivel_on_)
        fail(line_, g531->column, "G53.1", "G53.1 without a tilted working plane (G68.2)");
      const Eigen::Vector3d u_w = Gm_ * frame_.linear() * Eigen::Vector3d::UnitZ();
      JointVector q = q_;
      setRotaries(q);
      const std::vector<JointVector> ok =
          rotarySolutions(u_w, q, g531->column, "G53.1", "the tilted plane");
      const size_t pick = nearestSolution(ok, q);
      std::string words;
      for (int a : ik_.rotaryAxes()) {
        rot_word_[a] = model_.axes[a].nc_sign * ok[pick][a] / kDegToRad;
        words += " " + model_.axes[a].name + formatWith("%.3f", rot_word_[a] + 0.0);
      }
      setRotaries(q_);
      cur_xyz_ = currentProgramXyz();
      prog_.notes.push_back(
          "line " + std::to_string(line_) + ": G53.1 turns the rotaries to" + words +
          (ok.size() > 1 ? ", the solution nearer their positions (the control's parameters "
                           "may pick the other: the points are the same, the joints not)"
                         : ""));
    }
    return g682 ? "G68.2" : "G53.1";
  }

  int rotaryCount() const {
    int n = 0;
    for (const Axis& a : model_.axes) n += a.isRotary() ? 1 : 0;
    return n;
  }

  // Of rotary solutions, the one nearest q (the sum of the rotary axes' moves).
  size_t nearestSolution(const std::vector<JointVector>& ok, const JointVector& q) const {
    size_t pick = 0;
    double best = INFINITY;
    for (size_t k = 0; k < ok.size(); ++k) {
      double d = 0;
      for (int a : ik_.rotaryAxes()) d += std::abs(ok[k][a] - q[a]);
      if (d < best) best = d, pick = k;
    }
    return pick;
  }

  // The rotary solutions (at most two) that turn the tool along u_w, each inside travel, from
  // joint values q (each angle unwrapped to the turn nearest q's); none is an error naming what
  // (e.g. "the swivelled plane") needs which angles.
  std::vector<JointVector> rotarySolutions(const Eigen::Vector3d& u_w, const JointVector& q,
                                           int column, const std::string& field,
                                           const std::string& what) {
    InverseKinematics::RotaryCandidate cand[2];
    bool singular = false;
    const int n = ik_.rotaryCandidates(u_w, cand, &singular);
    const std::vector<int>& order = ik_.rotaryAxes();
    std::vector<JointVector> ok;
    std::string outside;
    for (int c = 0; c < n; ++c) {
      JointVector qc = q;
      bool inside = true;
      for (size_t r = 0; r < order.size(); ++r) {
        const int ax_i = order[r];
        const Axis& ax = model_.axes[ax_i];
        double v = cand[c].free[r] ? q[ax_i] : cand[c].angleOf(static_cast<int>(r));
        if (ax.endless) {
          v += 2 * kPi * std::round((q[ax_i] - v) / (2 * kPi));
        } else {
          double best = v;
          bool found = false;
          for (int turn = -2; turn <= 2; ++turn) {
            const double w = v + 2 * kPi * turn;
            if (w >= ax.travel_min - 1e-9 && w <= ax.travel_max + 1e-9 &&
                (!found || std::abs(w - q[ax_i]) < std::abs(best - q[ax_i]))) {
              best = w;
              found = true;
            }
          }
          if (!found) {
            inside = false;
            outside += (outside.empty() ? "" : ", ") + ax.name + " " +
                       formatWith("%.3f", ax.nc_sign * radToDeg(v)) + " deg";
          }
          v = best;
        }
        qc[ax_i] = v;
      }
      if (inside) ok.push_back(qc);
    }
    if (ok.empty())
      fail(line_, column, field,
           n == 0 ? "no rotary position of this machine turns the tool as " + what + " asks"
                  : what + " needs " + outside + ", outside travel");
    return ok;
  }

  // Sinumerik orientation vector A3= B3= C3= (SINUMERIK 840D sl Programming Manual, Job
  // Planning, "Orientation programming with direction vectors"): under TRAORI the tool's
  // direction in the workpiece coordinates (ORIWKS, the default), turned by the frame in force.
  // Written back as the rotary words of the solution nearest the axes' positions (the control's
  // choice of the shorter path), absolute.
  std::string orientationWords(const Eigen::Vector3d& v, int column) {
    if (!tcpMode())
      fail(line_, column, "A3",
           "an orientation vector (A3= B3= C3=) outside TRAORI: the control "
           "has no tool orientation to program");
    if (orimks_)
      fail(line_, column, "A3",
           "orientation vectors under ORIMKS (machine coordinates) are not "
           "supported: post them in ORIWKS");
    if (!absolute_) fail(line_, column, "A3", "orientation vectors in G91 are not supported");
    if (!(v.norm() > 1e-12)) fail(line_, column, "A3", "the orientation vector is zero");
    const Eigen::Vector3d u_w = Gm_ * frame_.linear() * v.normalized();
    JointVector q = q_;
    setRotaries(q);
    const std::vector<JointVector> ok =
        rotarySolutions(u_w, q, column, "A3", "the orientation vector");
    const size_t pick = nearestSolution(ok, q);
    std::string out;
    char buf[64];
    for (int a : ik_.rotaryAxes()) {
      const Axis& ax = model_.axes[a];
      if (ax.name.size() != 1)
        fail(line_, column, "A3", "rotary axis " + ax.name + " has no one-letter word");
      std::snprintf(buf, sizeof buf, " %s%.12g", ax.name.c_str(),
                    ax.nc_sign * radToDeg(ok[pick][a]) + 0.0);
      out += buf;
    }
    return out;
  }

  // The rotary axes CYCLE800 calls 1 and 2: <control swivel_axes="B C">, else the tilting axis
  // (the one that turns the tool axis at zero) first.
  std::vector<int> swivelAxes() const {
    std::vector<int> rot;
    for (const std::string& name : model_.control.swivel_axes)
      for (size_t a = 0; a < model_.axes.size(); ++a)
        if (toUpper(model_.axes[a].name) == name) rot.push_back(static_cast<int>(a));
    if (!rot.empty()) return rot;
    JointVector z = JointVector::Zero(static_cast<int>(model_.axes.size()));
    Eigen::Vector3d p, u0;
    nominal_.tipAndAxis(z, &p, &u0);
    for (size_t a = 0; a < model_.axes.size(); ++a) {
      if (!model_.axes[a].isRotary()) continue;
      JointVector t = z;
      t[a] = 0.5;
      Eigen::Vector3d u;
      nominal_.tipAndAxis(t, &p, &u);
      const bool tilts = (u - u0).norm() > 1e-6;
      rot.insert(tilts ? rot.begin() : rot.end(), static_cast<int>(a));
    }
    return rot;
  }

  // A Sinumerik expression in the reader's bracket syntax: ( ) become [ ].
  static std::string sinBrackets(std::string e) {
    for (char& c : e) {
      if (c == '(')
        c = '[';
      else if (c == ')')
        c = ']';
    }
    return e;
  }

  double sinExpression(const std::string& e, int column) {
    const std::string b = sinBrackets(sinOperators(e, line_, column));
    size_t i = 0;
    const double v = logical(b, i, column - 1);  // comparisons and logic give 1 or 0
    while (i < b.size() && b[i] == ' ') ++i;
    if (i != b.size()) fail(line_, column, e.substr(0, 20), "unexpected text in the expression");
    if (!std::isfinite(v) || std::abs(v) > 1e9)
      fail(line_, column, e.substr(0, 20),
           "value " + clip(formatNumber(v)) + " is beyond any plausible number");
    return v;
  }

  // CYCLE81/82/83(RTP, RFP, SDIS, DP, DPR, ...): the drilling motion at each position (modal
  // under MCALL) or at the current one; RTP retract plane, RFP reference plane, SDIS safety
  // distance, DP final depth (absolute) or DPR (relative to RFP).
  void sinCycle(const std::string& k, int column, bool modal) {
    const size_t paren = k.find('(');
    const std::string name = k.substr(0, paren);
    if (name != "CYCLE81" && name != "CYCLE82" && name != "CYCLE83")
      fail(line_, column, name,
           "the Sinumerik cycle " + name +
               " is not expanded (drilling "
               "cycles CYCLE81, CYCLE82 and CYCLE83 are)");
    if (paren == std::string::npos || k.back() != ')')
      fail(line_, column, name, "expected " + name + "(...)");
    const std::string args = k.substr(paren + 1, k.size() - paren - 2);
    std::vector<std::string> a;
    size_t p = 0;
    while (true) {
      const size_t e = args.find(',', p);
      a.push_back(
          std::string(trim(args.substr(p, e == std::string::npos ? std::string::npos : e - p))));
      if (e == std::string::npos) break;
      p = e + 1;
    }
    auto arg = [&](size_t n) -> std::optional<double> {
      if (n >= a.size() || a[n].empty()) return std::nullopt;
      return sinExpression(a[n], column);
    };
    const auto rtp = arg(0), rfp = arg(1), sdis = arg(2), dp = arg(3), dpr = arg(4);
    if (!rtp || !rfp) fail(line_, column, name, name + " needs RTP and RFP (its first two values)");
    if (!dp && !dpr)
      fail(line_, column, name, name + " needs DP or DPR (its fourth or fifth value)");
    cycle_ = true;
    ++prog_.cycles;
    sin_mcall_ = modal;
    cycle_code_ = name;
    cycle_return_initial_ = true;
    cycle_initial_z_ = *rtp * unit_;
    cycle_r_ = (*rfp + sdis.value_or(0.0)) * unit_;
    cycle_z_ = (dp ? *dp : *rfp - std::abs(*dpr)) * unit_;
    cycle_r_incremental_ = cycle_z_incremental_ = false;  // the cycle's planes are absolute
  }

  // A recursion's depth counted for as long as a call lasts (bounded by the caller's check).
  struct ScopedDepth {
    int& d;
    explicit ScopedDepth(int& depth) : d(++depth) {}
    ~ScopedDepth() { --d; }
    ScopedDepth(const ScopedDepth&) = delete;
    ScopedDepth& operator=(const ScopedDepth&) = delete;
  };

  // ---------------------------------------------------------------- expressions
  double parameter(const std::string& text, size_t& i, int col_base) {
    // text[i] == '#'
    ++i;
    while (i < text.size() && text[i] == ' ') ++i;
    if (i < text.size() && text[i] == '<') {
      const size_t close = text.find('>', i);
      if (close == std::string::npos) fail(line_, col_base + i, "#<", "unclosed parameter name");
      const std::string name = lowerNoSpace(text.substr(i + 1, close - i - 1));
      i = close + 1;
      auto it = named_.find(name);
      if (it == named_.end())
        fail(line_, col_base + i, "#<" + name + ">",
             name.rfind("_hal[", 0) == 0
                 ? "HAL pin with no value: declare it in the machine file's <control> as "
                   "<parameter name=\"" +
                       name + "\" value=\"...\"/>"
                 : "parameter has no value");
      return it->second;
    }
    const size_t at = i;
    const int n = parameterNumber(primary(text, i, col_base), col_base + static_cast<int>(at));
    auto it = numbered_.find(n);
    if (it == numbered_.end())
      fail(line_, col_base + i, "#" + std::to_string(n), "parameter has no value");
    return it->second;
  }

  // A numbered parameter's number, as LinuxCNC takes it: an integer (to 1e-4) from 1 to 5601.
  int parameterNumber(double n, int col) {
    const double r = std::round(n);
    if (!(r >= 1 && r <= kMaxParameter))
      fail(line_, col, "#",
           "parameter number " + formatWith("%g", n) + " out of range (1 to " +
               std::to_string(kMaxParameter) + ")");
    if (std::abs(n - r) > 1e-4)
      fail(line_, col, "#", "parameter number " + formatWith("%g", n) + " is not an integer");
    return static_cast<int>(r);
  }

  double primary(const std::string& text, size_t& i, int col_base) {
    // Signs, brackets and parameter references nest by recursion: bounded, so that a block of
    // thousands of '+' or '[' is an error, not a stack overflow.
    const ScopedDepth depth(nesting_);
    if (nesting_ > kMaxNesting)
      fail(line_, col_base + i, "",
           "expression nested deeper than " + std::to_string(kMaxNesting) + " levels");
    while (i < text.size() && text[i] == ' ') ++i;
    if (i >= text.size()) fail(line_, col_base + i, "", "a number is missing");
    const char c = text[i];
    if (c == '[') {
      ++i;
      ++brackets_;
      const double v = logical(text, i, col_base);
      --brackets_;
      while (i < text.size() && text[i] == ' ') ++i;
      if (i >= text.size() || text[i] != ']') fail(line_, col_base + i, "[", "missing ']'");
      ++i;
      return v;
    }
    if (c == '-' || c == '+') {
      ++i;
      const double v = primary(text, i, col_base);
      return c == '-' ? -v : v;
    }
    if (c == '#') return parameter(text, i, col_base);
    if (model_.control.dialect == "sinumerik" && c == '$') {
      size_t j = i + 1;
      while (j < text.size() &&
             (std::isalnum(static_cast<unsigned char>(text[j])) || text[j] == '_'))
        ++j;
      fail(line_, col_base + i, text.substr(i, j - i),
           "the system variable " + text.substr(i, j - i) +
               " (the control's state or machine data) is not known here");
    }
    if (model_.control.dialect == "sinumerik" &&
        (std::isalpha(static_cast<unsigned char>(c)) || c == '_')) {
      size_t j = i;
      while (j < text.size() &&
             (std::isalnum(static_cast<unsigned char>(text[j])) || text[j] == '_'))
        ++j;
      const std::string name = text.substr(i, j - i);
      if (j < text.size() && text[j] == '[') {
        const double v = sinFunction(name, text, j, col_base, col_base + static_cast<int>(i));
        i = j;
        return v;
      }
      if (sin_texts_.count(name))
        fail(line_, col_base + i, name, name + " is a STRING variable: it has no number");
      if (name == "TRUE" || name == "FALSE") {  // BOOL constants
        i = j;
        return name == "TRUE" ? 1.0 : 0.0;
      }
      auto it = sin_vars_.find(name);
      if (it == sin_vars_.end())
        fail(line_, col_base + i, name,
             "the variable " + name + " has no value (not assigned in the program)");
      i = j;
      return it->second;
    }
    if (std::isalpha(static_cast<unsigned char>(c))) return function(text, i, col_base);
    size_t j = i;
    while (j < text.size() && (std::isdigit(static_cast<unsigned char>(text[j])) || text[j] == '.'))
      ++j;
    const auto v = parseNumber(std::string_view(text).substr(i, j - i));
    if (!v)
      fail(line_, col_base + i, "", "malformed number '" + clip(text.substr(i, j - i + 1)) + "'");
    i = j;
    return *v;
  }

  // SINUMERIK's arithmetic functions (840D sl Programming Manual, Job Planning, "Arithmetic
  // functions"; angles in degrees): SIN COS TAN ASIN ACOS, ATAN2(y, x) (the angle of (x, y)
  // from x), SQRT, POT (square), ABS, TRUNC, ROUND, ROUNDUP, LN, EXP, MINVAL(a, b),
  // MAXVAL(a, b), BOUND(min, max, value). text[i] is the '[' (sinBrackets) after the name;
  // returns with i past the ']'. Any other name is refused naming it.
  double sinFunction(const std::string& name, const std::string& text, size_t& i, int col_base,
                     int col) {
    static const std::map<std::string, int> arity = {
        {"SIN", 1},  {"COS", 1}, {"TAN", 1},    {"ASIN", 1},   {"ACOS", 1},  {"ATAN2", 2},
        {"SQRT", 1}, {"POT", 1}, {"ABS", 1},    {"TRUNC", 1},  {"ROUND", 1}, {"ROUNDUP", 1},
        {"LN", 1},   {"EXP", 1}, {"MINVAL", 2}, {"MAXVAL", 2}, {"BOUND", 3}};
    const auto known = arity.find(name);
    if (known == arity.end()) {
      const bool dimension =
          name == "IC" || name == "AC" || name == "DC" || name == "ACP" || name == "ACN";
      fail(line_, col + 1, name,
           dimension ? name + "(...) is a dimension of a whole axis word (X=" + name +
                           "(...)), not part of an expression"
                     : name +
                           "(...) is not a SINUMERIK arithmetic function tolver evaluates "
                           "(SIN COS TAN ASIN ACOS ATAN2 SQRT POT ABS TRUNC ROUND ROUNDUP "
                           "LN EXP MINVAL MAXVAL BOUND)");
    }
    ++i;  // '['
    ++brackets_;
    std::vector<double> a;
    for (;;) {
      a.push_back(expression(text, i, col_base));
      while (i < text.size() && text[i] == ' ') ++i;
      if (i < text.size() && text[i] == ',') {
        ++i;
        continue;
      }
      break;
    }
    --brackets_;
    if (i >= text.size() || text[i] != ']') fail(line_, col + 1, name, "missing ')' after " + name);
    ++i;
    if (static_cast<int>(a.size()) != known->second)
      fail(line_, col + 1, name,
           name + " takes " + std::to_string(known->second) + " value(s), given " +
               std::to_string(a.size()));
    const double x = a[0];
    auto domain = [&](bool ok) {
      if (!ok) fail(line_, col + 1, name, name + " of " + formatNumber(x) + ": no value");
    };
    constexpr double d = M_PI / 180.0;
    if (name == "SIN") return std::sin(x * d);
    if (name == "COS") return std::cos(x * d);
    if (name == "TAN") return std::tan(x * d);
    if (name == "ASIN") return domain(std::abs(x) <= 1.0), std::asin(x) / d;
    if (name == "ACOS") return domain(std::abs(x) <= 1.0), std::acos(x) / d;
    if (name == "ATAN2") return std::atan2(x, a[1]) / d;
    if (name == "SQRT") return domain(x >= 0.0), std::sqrt(x);
    if (name == "POT") return x * x;
    if (name == "ABS") return std::abs(x);
    if (name == "TRUNC") return std::trunc(x);
    if (name == "ROUND") return std::round(x);
    if (name == "ROUNDUP") return std::ceil(x);
    if (name == "LN") return domain(x > 0.0), std::log(x);
    if (name == "EXP") return std::exp(x);
    if (name == "MINVAL") return std::min(x, a[1]);
    if (name == "MAXVAL") return std::max(x, a[1]);
    if (x > a[1]) fail(line_, col + 1, name, "BOUND(min, max, value) with min above max");
    return std::clamp(a[2], x, a[1]);  // BOUND
  }

  // LinuxCNC's unary functions (G-code reference, "Unary Operation Value"; angles in degrees):
  // NAME[expr], ATAN[y]/[x], EXISTS[#<name>]. Any other name is refused naming it.
  double function(const std::string& text, size_t& i, int col_base) {
    const size_t at = i;
    size_t j = i;
    while (j < text.size() && std::isalpha(static_cast<unsigned char>(text[j]))) ++j;
    const std::string name = toUpper(text.substr(i, j - i));
    while (j < text.size() && text[j] == ' ') ++j;  // LinuxCNC ignores spaces: "TAN [29]"
    static const std::set<std::string> known = {"ABS", "ACOS", "ASIN", "ATAN",  "COS",
                                                "EXP", "FIX",  "FUP",  "LN",    "ROUND",
                                                "SIN", "SQRT", "TAN",  "EXISTS"};
    if (!known.count(name) || j >= text.size() || text[j] != '[')
      fail(line_, col_base + at + 1, name,
           "'" + clip(text.substr(at, 12)) +
               "': not a function of LinuxCNC expressions (ABS, ACOS, ASIN, ATAN, COS, EXP, "
               "FIX, FUP, LN, ROUND, SIN, SQRT, TAN, EXISTS)");
    i = j;
    if (name == "EXISTS") {
      const size_t close = text.find(']', j);
      if (close == std::string::npos) fail(line_, col_base + j, "[", "missing ']'");
      const std::string inner = lowerNoSpace(text.substr(j + 1, close - j - 1));
      i = close + 1;
      if (inner.size() < 3 || inner.rfind("#<", 0) != 0 || inner.back() != '>')
        fail(line_, col_base + j, name, "EXISTS takes a named parameter, #<name>");
      return named_.count(inner.substr(2, inner.size() - 3)) ? 1.0 : 0.0;
    }
    const double a = primary(text, i, col_base);
    auto domain = [&](bool ok) {
      if (!ok) fail(line_, col_base + at + 1, name, name + " of " + formatNumber(a) + ": no value");
    };
    constexpr double d = M_PI / 180.0;
    if (name == "ATAN") {
      while (i < text.size() && text[i] == ' ') ++i;
      if (i >= text.size() || text[i] != '/')
        fail(line_, col_base + i, name, "ATAN is written ATAN[y]/[x]");
      ++i;
      const double x = primary(text, i, col_base);
      return std::atan2(a, x) / d;
    }
    if (name == "ABS") return std::abs(a);
    if (name == "ACOS") return domain(std::abs(a) <= 1.0), std::acos(a) / d;
    if (name == "ASIN") return domain(std::abs(a) <= 1.0), std::asin(a) / d;
    if (name == "COS") return std::cos(a * d);
    if (name == "SIN") return std::sin(a * d);
    if (name == "TAN") return std::tan(a * d);
    if (name == "EXP") return std::exp(a);
    if (name == "FIX") return std::floor(a);
    if (name == "FUP") return std::ceil(a);
    if (name == "ROUND") return std::round(a);
    if (name == "LN") return domain(a > 0.0), std::log(a);
    return domain(a >= 0.0), std::sqrt(a);  // SQRT
  }

  // Inside brackets, '**' (power) binds tightest, then * / MOD, then + - (LinuxCNC's binary
  // operators; comparisons and logic belong to O-word conditions, which are refused).
  double power(const std::string& text, size_t& i, int col_base) {
    double v = primary(text, i, col_base);
    for (;;) {
      size_t k = i;
      while (k < text.size() && text[k] == ' ') ++k;
      if (brackets_ > 0 && k + 1 < text.size() && text[k] == '*' && text[k + 1] == '*') {
        i = k + 2;
        const double e = primary(text, i, col_base);
        v = std::pow(v, e);
        if (!std::isfinite(v)) fail(line_, col_base + k, "**", "the power has no finite value");
      } else {
        return v;
      }
    }
  }

  double term(const std::string& text, size_t& i, int col_base) {
    double v = power(text, i, col_base);
    for (;;) {
      while (i < text.size() && text[i] == ' ') ++i;
      const bool sin = model_.control.dialect == "sinumerik";
      const bool mod =
          (brackets_ > 0 || sin) && i + 2 < text.size() && toUpper(text.substr(i, 3)) == "MOD";
      const bool div = sin && i + 2 < text.size() && text.compare(i, 3, "DIV") == 0;
      if (mod && sin) {
        // SINUMERIK MOD: the remainder of the division, as fmod (7 MOD 4.1 = 2.9). Its sign
        // with a negative operand is not carried: refused rather than guessed.
        i += 3;
        const double r = power(text, i, col_base);
        if (r == 0.0) fail(line_, col_base + i, "MOD", "MOD by zero");
        if (v < 0.0 || r < 0.0)
          fail(line_, col_base + i, "MOD", "MOD of a negative number: its sign is not carried");
        v = std::fmod(v, r);
      } else if (div) {
        // SINUMERIK DIV: division whose result is the whole part (7 DIV 0.4 = 17).
        i += 3;
        const double r = power(text, i, col_base);
        if (r == 0.0) fail(line_, col_base + i, "DIV", "DIV by zero");
        v = std::trunc(v / r);
      } else if (mod) {
        i += 3;
        const double r = power(text, i, col_base);
        if (r == 0.0) fail(line_, col_base + i, "MOD", "MOD by zero");
        v = std::fmod(v, r);  // LinuxCNC's interp_execute.cc: "always a positive answer"
        if (v < 0.0) v += std::abs(r);
      } else if (i < text.size() && (text[i] == '*' || text[i] == '/') &&
                 !(i + 1 < text.size() && text[i + 1] == '*')) {
        const char op = text[i++];
        const double r = power(text, i, col_base);
        if (op == '/' && r == 0.0) fail(line_, col_base + i, "/", "division by zero");
        v = op == '*' ? v * r : v / r;
      } else {
        return v;
      }
    }
  }

  // Inside brackets, below + and -: the comparisons EQ NE GT GE LT LE (1 or 0), then AND, OR,
  // XOR (LinuxCNC's binary operators, "Binary Operators": equal precedence left to right within
  // each group). The O-words' conditions use them.
  static bool operatorAt(const std::string& text, size_t i, const char* op) {
    const size_t n = std::strlen(op);
    if (i + n > text.size()) return false;
    for (size_t k = 0; k < n; ++k)
      if (std::toupper(static_cast<unsigned char>(text[i + k])) != op[k]) return false;
    return true;
  }

  double relation(const std::string& text, size_t& i, int col_base) {
    double v = expression(text, i, col_base);
    static const char* const ops[] = {"EQ", "NE", "GT", "GE", "LT", "LE"};
    for (;;) {
      while (i < text.size() && text[i] == ' ') ++i;
      int op = -1;
      for (int k = 0; k < 6 && op < 0; ++k)
        if (operatorAt(text, i, ops[k])) op = k;
      if (op < 0) return v;
      i += 2;
      const double r = expression(text, i, col_base);
      const bool t = op == 0   ? v == r
                     : op == 1 ? v != r
                     : op == 2 ? v > r
                     : op == 3 ? v >= r
                     : op == 4 ? v < r
                               : v <= r;
      v = t ? 1.0 : 0.0;
    }
  }

  // NOT (Sinumerik) before a relation negates it.
  double negatable(const std::string& text, size_t& i, int col_base) {
    while (i < text.size() && text[i] == ' ') ++i;
    if (operatorAt(text, i, "NOT") && i + 3 < text.size() &&
        !std::isalnum(static_cast<unsigned char>(text[i + 3])) && text[i + 3] != '_') {
      i += 3;
      return negatable(text, i, col_base) == 0.0 ? 1.0 : 0.0;
    }
    return relation(text, i, col_base);
  }

  double logical(const std::string& text, size_t& i, int col_base) {
    double v = negatable(text, i, col_base);
    for (;;) {
      while (i < text.size() && text[i] == ' ') ++i;
      const int op = operatorAt(text, i, "AND")   ? 0
                     : operatorAt(text, i, "XOR") ? 2
                     : operatorAt(text, i, "OR")  ? 1
                                                  : -1;
      if (op < 0) return v;
      i += op == 1 ? 2 : 3;
      const bool a = v != 0.0, b = negatable(text, i, col_base) != 0.0;
      v = (op == 0 ? a && b : op == 1 ? a || b : a != b) ? 1.0 : 0.0;
    }
  }

  double expression(const std::string& text, size_t& i, int col_base) {
    double v = term(text, i, col_base);
    for (;;) {
      while (i < text.size() && text[i] == ' ') ++i;
      if (i < text.size() && (text[i] == '+' || text[i] == '-')) {
        const char op = text[i++];
        const double r = term(text, i, col_base);
        v = op == '+' ? v + r : v - r;
      } else {
        return v;
      }
    }
  }

  // The finest printed resolution of the program's coordinates: the most digits after the
  // decimal point in a plain number of X Y Z I J K R (arc checks are never tighter than it).
  void noteResolution(std::string_view v, char letter) {
    if (std::string_view("XYZIJKR").find(letter) == std::string_view::npos) return;
    const size_t dot = v.find('.');
    if (dot == std::string_view::npos) return;
    int digits = 0;
    for (size_t k = dot + 1; k < v.size() && std::isdigit(static_cast<unsigned char>(v[k])); ++k)
      ++digits;
    max_decimals_ = std::max(max_decimals_, std::min(digits, 9));
  }

  // Numbers with and without a decimal point (Fanuc 0i-MF, "Decimal point programming": with
  // parameter 3401#0 DPI = 0 a dimension without a point is in least input increments, X10 =
  // 0.010 mm; HAAS, LinuxCNC and posts for them read X10 as 10): a post that writes "10." (a
  // point and no digits after it) writes for a control that needs the point, and a non-zero
  // whole number without one in the same program is said, on an ISO control.
  void noteDecimalPoint(std::string_view v, char letter) {
    if (std::string_view("XYZIJKRABCUVW").find(letter) == std::string_view::npos) return;
    while (!v.empty() && v.back() == ' ') v.remove_suffix(1);
    if (v.empty() || v.find_first_not_of("+-0123456789.") != std::string_view::npos) return;
    const size_t dot = v.find('.');
    if (dot != std::string_view::npos) {
      if (dot + 1 == v.size()) bare_point_ = true;  // "10.": the point written for its own sake
      return;
    }
    if (v.find_first_not_of("+-0") == std::string_view::npos) return;  // zero reads the same
    if (first_integer_line_ == 0) {
      first_integer_line_ = line_;
      first_integer_ = std::string(1, letter) + std::string(v);
    }
  }

  // The largest difference of an arc's start and end radius (mm) the control accepts, never
  // tighter than four steps of the program's printed resolution (the rounding of start, end and
  // centre adds up to 2.9 steps): LinuxCNC as its interpreter checks it (src/emc/rs274ngc/
  // interp_arc.cc, arc_data_ijk: an error when the radii differ by more than 100 t, or by more
  // than t and 0.1 % of the radius, t = CENTER_ARC_RADIUS_TOLERANCE_MM = 0.02 sqrt 2 mm, 0.002
  // sqrt 2 inch in an inch program, interp_internal.hh; its own tests/interp/good and bad arcs
  // sit on either side; the G-code reference's older figures, 0.5 mm or 0.005 mm and 0.1 %,
  // reject arcs LinuxCNC runs); a given arc_radius_tolerance_mm (Fanuc parameter 3410); else
  // RS274NGC v3's 0.002 mm (0.0002 inch).
  double arcRadiusTolerance(double radius_mm) const {
    const bool inch = unit_ == 25.4;
    double rule;
    if (model_.control.arc_radius_tolerance_mm > 0) {
      rule = model_.control.arc_radius_tolerance_mm;
    } else if (model_.control.dialect == "linuxcnc") {
      const double t = (inch ? 25.4 * 0.002 : 0.02) * std::sqrt(2.0);
      // 0.1 % of the larger radius, which for an end radius beyond the start is r / 0.999.
      rule = std::max(t, std::min(100.0 * t, 1e-3 * radius_mm / 0.999));
    } else {
      rule = inch ? 0.00508 : 0.002;
    }
    const double step = unit_ * std::pow(10.0, -max_decimals_);
    return std::max(rule, 4.0 * step);
  }

  static std::string clip(std::string s) {
    if (s.size() > 60) s = s.substr(0, 57) + "...";
    return s;
  }

  // ---------------------------------------------------------------- one block
  // Tool geometry in the posts' comments: Fusion "(T1  D=2.8 CR=0 - ZMIN=... - flat end mill)",
  // LinuxCNC posts "( TOOL: T1 = 10.0 dia. ... )", Mastercam's Fanuc and HAAS posts
  // "( 1/2 FLAT ENDMILL TOOL - 1 DIA. OFF. - 1 LEN. - 1 DIA. - .5 )" (a BALL in the name: the
  // corner radius is half the diameter). In the program's unit, converted where the tool is used.
  void toolComment(const std::string& raw) {
    const std::string u = toUpper(raw);
    for (size_t open = u.find('('); open != std::string::npos; open = u.find('(', open + 1)) {
      const size_t close = u.find(')', open);
      if (close == std::string::npos) return;
      std::string c(trim(std::string_view(u).substr(open + 1, close - open - 1)));
      if (mastercamToolComment(c)) continue;
      if (c.rfind("TOOL:", 0) == 0) c = std::string(trim(std::string_view(c).substr(5)));
      if (c.rfind("D =", 0) == 0 || c.rfind("D=", 0) == 0) {
        fabexToolComment(c);
        continue;
      }
      if (c.size() < 2 || c[0] != 'T' || !std::isdigit(static_cast<unsigned char>(c[1]))) continue;
      size_t k = 1;
      while (k < c.size() && std::isdigit(static_cast<unsigned char>(c[k]))) ++k;
      if (k > 7) continue;  // not a tool number
      const int number = std::atoi(c.substr(1, k - 1).c_str());
      auto numberAfter = [&](const std::string& key) -> std::optional<double> {
        const size_t at = c.find(key, k);
        if (at == std::string::npos) return std::nullopt;
        size_t b = at + key.size();
        while (b < c.size() && c[b] == ' ') ++b;
        size_t e = b;
        while (e < c.size() &&
               (std::isdigit(static_cast<unsigned char>(c[e])) || c[e] == '.' || c[e] == '-'))
          ++e;
        // A number that runs on into letters ("1E999", "6MM") is not one the posts write: no
        // geometry rather than its leading digits.
        if (e < c.size() && std::isalpha(static_cast<unsigned char>(c[e]))) return std::nullopt;
        return parseNumber(std::string_view(c).substr(b, e - b));
      };
      // CamBam's tool list "( T0 : 3.175 )": the number and the diameter alone (its posts'
      // ToolTableItem, "T{$tool.index} : {$tool.diameter}"); the shape is not given.
      size_t colon = k;
      while (colon < c.size() && c[colon] == ' ') ++colon;
      if (colon < c.size() && c[colon] == ':') {
        const std::optional<double> d = numberAfter(":");
        if (!d || !(*d > 0)) continue;
        tool_table_["T" + std::to_string(number)] = {*d, 0.0};
        tool_line_.emplace("T" + std::to_string(number), line_);
        diameter_only_.insert("T" + std::to_string(number));
        continue;
      }
      std::optional<double> d = numberAfter(" D=");
      if (!d) d = numberAfter("=");  // "T1 = 10.0 dia."
      if (!d || !(*d > 0)) continue;
      const double r =
          numberAfter(" CR=").value_or(c.find("BALL") != std::string::npos ? *d / 2 : 0.0);
      tool_table_["T" + std::to_string(number)] = {*d, std::clamp(r, 0.0, *d / 2)};
      tool_line_.emplace("T" + std::to_string(number), line_);
    }
  }

  // Fabex (BlenderCAM): "(Tool: D = 6.0 mm  type BALLNOSE flutes 2)" after its "T2M06", or alone
  // (its grbl post writes no T): the tool that cuts from here on, its diameter in the unit the
  // comment names (fabex/gcode/gcode_export.py: "Tool: D = %s type %s flutes %s", the diameter
  // by unit_value_to_string: "mm" or '' for inches). END is a flat end, BALLNOSE a ball; another
  // type (BULLNOSE, VCARVE, BALLCONE, ...) is named in a note and gives no geometry.
  void fabexToolComment(const std::string& c) {
    size_t b = c.find('=') + 1;
    while (b < c.size() && c[b] == ' ') ++b;
    size_t e = b;
    while (e < c.size() && (std::isdigit(static_cast<unsigned char>(c[e])) || c[e] == '.')) ++e;
    const std::optional<double> value = parseNumber(std::string_view(c).substr(b, e - b));
    if (!value || !(*value > 0)) return;
    const std::string rest(trim(std::string_view(c).substr(e)));
    double mm_per_unit = 0;
    if (rest.rfind("MM", 0) == 0) mm_per_unit = 1.0;
    if (rest.rfind("''", 0) == 0 || rest.rfind("\"", 0) == 0) mm_per_unit = 25.4;
    const size_t t = rest.find("TYPE ");
    if (mm_per_unit == 0 || t == std::string::npos) return;
    size_t te = t + 5;
    while (te < rest.size() && rest[te] != ' ') ++te;
    const std::string type = rest.substr(t + 5, te - t - 5);
    const double d = *value * mm_per_unit;
    std::vector<double> values;
    if (type == "END") values = {d, 0.0};
    if (type == "BALLNOSE") values = {d, d / 2};
    if (values.empty())
      prog_.notes.push_back("line " + std::to_string(line_) + ": Fabex's tool comment names a " +
                            type +
                            " cutter, whose shape the comment does not give: give --cutter "
                            "d,r (or a --tools file)");
    // The tool a T/M6 just loaded, still without geometry, gets it; else this is the tool from
    // here on (a repeat of the last one changes nothing).
    if (!prog_.cutters.empty() && !active_tool_.empty() &&
        prog_.cutters.back().kind == active_tool_ && prog_.cutters.back().values.empty()) {
      prog_.cutters.back().values = values;
      return;
    }
    if (!prog_.cutters.empty() && prog_.cutters.back().values == values && !values.empty()) return;
    CutterSpec spec;
    spec.source = "TLDATA";
    spec.kind = "Fabex " + type;
    spec.line = line_;
    spec.values = values;
    prog_.cutters.push_back(spec);
  }

  // "TOOL - n ... DIA. - d" (Mastercam): true when read.
  bool mastercamToolComment(const std::string& c) {
    const size_t t = c.find("TOOL -");
    if (t == std::string::npos) return false;
    auto numberAt = [&](size_t b, bool integer) -> std::optional<double> {
      while (b < c.size() && c[b] == ' ') ++b;
      size_t e = b;
      while (e < c.size() &&
             (std::isdigit(static_cast<unsigned char>(c[e])) || (!integer && c[e] == '.')))
        ++e;
      if (e == b || e - b > 12) return std::nullopt;
      return parseNumber(std::string_view(c).substr(b, e - b));
    };
    const auto number = numberAt(t + 6, true);
    if (!number) return false;
    // The diameter: "DIA." then '-' (the offset numbers read "DIA. OFF. - n").
    std::optional<double> d;
    for (size_t at = c.find("DIA.", t); at != std::string::npos; at = c.find("DIA.", at + 4)) {
      size_t b = at + 4;
      while (b < c.size() && c[b] == ' ') ++b;
      if (b < c.size() && c[b] == '-') d = numberAt(b + 1, false);
    }
    if (!d || !(*d > 0)) return false;
    const double r = c.find("BALL") != std::string::npos ? *d / 2 : 0.0;
    tool_table_["T" + std::to_string(static_cast<long>(*number))] = {*d, r};
    tool_line_.emplace("T" + std::to_string(static_cast<long>(*number)), line_);
    return true;
  }

  // The tool that cuts from here on: the program's cutters list gets its geometry (from the
  // comments), or an empty entry naming the tool when the program does not give it.
  void toolChange(const std::string& key) {
    if (key == active_tool_) return;
    active_tool_ = key;
    if (key.size() > 1 && key[0] == 'T' && std::isdigit(static_cast<unsigned char>(key[1])))
      loaded_tool_ = std::atoi(key.c_str() + 1);
    // T0 empties the spindle (LinuxCNC), unless the program's own tool list names a T0 (CamBam
    // numbers its tools from 0 and writes "T0 M6" for the tool that cuts).
    if (key.empty() || (key == "T0" && !tool_table_.count(key))) return;
    CutterSpec spec;
    spec.source = "TLDATA";
    spec.kind = key;
    spec.line = line_;
    auto it = tool_table_.find(key);
    if (it != tool_table_.end())
      spec.values = {it->second.first * unit_, it->second.second * unit_};
    if (diameter_only_.erase(key))
      prog_.notes.push_back(key + " (line " + std::to_string(line_) +
                            "): the program's tool list gives its diameter only (CamBam's \"( " +
                            key +
                            " : d )\"): a flat end is assumed; give --cutter d,r for "
                            "another shape");
    prog_.cutters.push_back(spec);
  }

  // A CAM operation named in a comment ("(begin operation: Profile)", ";Operation : DRILLING").
  void operationComment(const std::string& raw) {
    if (raw.find_first_of("(;") == std::string::npos) return;
    std::string name;
    const size_t semi = raw.find(';');
    if (semi != std::string::npos) name = operationName(std::string_view(raw).substr(semi + 1));
    for (size_t open = raw.find('('); name.empty() && open != std::string::npos && open < semi;
         open = raw.find('(', open + 1))
      name = operationName(std::string_view(raw).substr(open + 1));
    if (name.empty()) return;
    if (!prog_.operations.empty() && prog_.operations.back().name == name) return;
    prog_.operations.push_back({line_, std::move(name)});
  }

  std::string block(const std::string& raw) {
    toolComment(raw);
    operationComment(raw);
    // Strip comments, keep positions (1-based columns of the raw line).
    std::string text;
    std::vector<int> col;
    const bool sinumerik = model_.control.dialect == "sinumerik";
    for (size_t i = 0; i < raw.size(); ++i) {
      const char c = raw[i];
      if (c == ';') break;
      if (sinumerik && c == '"') {  // a string: MSG("..."), T="name"
        const size_t close = raw.find('"', i + 1);
        if (close == std::string::npos)
          fail(line_, static_cast<int>(i) + 1, "\"", "unclosed string");
        for (size_t k = i; k <= close; ++k) {
          text += raw[k];
          col.push_back(static_cast<int>(k) + 1);
        }
        i = close;
        continue;
      }
      if (c == '(' && !sinumerik) {
        const size_t first_close = raw.find(')', i);
        if (first_close == std::string::npos)
          fail(line_, static_cast<int>(i) + 1, "(", "unclosed comment");
        // A '(' inside the comment ("( Drilling hole at (61.045, 67.745) )"): LinuxCNC
        // refuses it ("Nested comment found"); on other controls the comment is read up to the
        // parenthesis that balances it, when one does (commentEnd), and a note says so.
        const size_t inner = raw.find('(', i + 1);
        if (inner != std::string::npos && inner < first_close &&
            model_.control.dialect == "linuxcnc")
          fail(line_, static_cast<int>(inner) + 1, "(",
               "a comment inside a comment: LinuxCNC refuses nested comments");
        const size_t close = commentEnd(raw, i);
        if (close != first_close && nested_comments_++ == 0) first_nested_comment_ = line_;
        i = close;
        continue;
      }
      if (c == '\r' || c == '\t') continue;
      text += c;
      col.push_back(static_cast<int>(i) + 1);
    }
    std::string_view tv = trim(text);
    if (tv.empty()) return "";
    const size_t lead = tv.data() - text.data();
    text = std::string(tv);
    col.erase(col.begin(), col.begin() + lead);
    seen_block_ = true;
    if (text[0] == '/') {  // block delete: the control runs it unless the switch is on
      text[0] = ' ';
      if (block_deletes_++ == 0) first_block_delete_ = line_;
    }
    std::string upper = toUpper(text);
    // TCP words that are names, not letter-number words (Siemens TRAORI / TRAFOOF): taken out
    // of the block and carried out first.
    for (const auto& [on, off] : model_.control.tcp_words)
      for (const std::string* w : {&on, &off}) {
        if (w->size() < 3 || !std::isalpha(static_cast<unsigned char>((*w)[1]))) continue;
        const size_t at = upper.find(*w);
        if (at == std::string::npos) continue;
        const size_t end = at + w->size();
        const bool alone =
            (at == 0 || !std::isalnum(static_cast<unsigned char>(upper[at - 1]))) &&
            (end == upper.size() || !std::isalnum(static_cast<unsigned char>(upper[end])));
        if (!alone) continue;
        // Siemens's TRAORI(n): the n-th transformation data set; the machine file describes one,
        // TRAORI(1) (or TRAORI()).
        size_t stop = end;
        if (end < upper.size() && upper[end] == '(') {
          const size_t close = upper.find(')', end);
          if (close == std::string::npos)
            fail(line_, col.empty() ? 0 : col[at], *w, *w + "(: the ')' is missing");
          const std::string n(trim(std::string_view(upper).substr(end + 1, close - end - 1)));
          if (!n.empty() && n != "1")
            fail(line_, col.empty() ? 0 : col[at], *w,
                 *w + "(" + n + "): the control's transformation data set " + n +
                     "; the machine file describes one kinematics (TRAORI, TRAORI(1))");
          stop = close + 1;
        }
        tcpWord(*w);
        for (size_t k = at; k < stop; ++k) upper[k] = ' ';
      }
    if (sinumerik) {
      upper = sinumerikBlock(upper, col);
      if (trim(upper).empty()) return "";
      col.assign(upper.size(), col.empty() ? 1 : col[0]);
      if (upper[0] == ' ') {
        const std::string_view u = trim(upper);
        upper = std::string(u);
        col.resize(upper.size());
      }
      text = upper;
    }
    // The program's number or name: O1234, O<name>, :1234 (ISO 6983's alternative), and at the
    // program start OName ... (NX writes "OFinal ToolPath"). O-word subprograms and control flow
    // (LinuxCNC "O100 sub", "O<x> if [...]") are refused naming the construct.
    if (upper[0] == 'O' || upper[0] == ':') {
      size_t j = 1;
      while (j < upper.size() && std::isdigit(static_cast<unsigned char>(upper[j]))) ++j;
      if (j == 1 && j < upper.size() && upper[j] == '<')
        j = upper.find('>', j) == std::string::npos ? upper.size() : upper.find('>', j) + 1;
      const std::string rest(trim(std::string_view(upper).substr(j)));
      const bool numbered = j > 1;
      if (rest.empty() && (numbered || upper[0] == 'O')) {
        if (prog_.part_name.empty()) prog_.part_name = std::string(trim(text.substr(1)));
        return "";
      }
      static const std::set<std::string> flow = {
          "SUB",      "ENDSUB", "CALL",   "IF",        "ELSE",   "ELSEIF", "ENDIF",   "WHILE",
          "ENDWHILE", "DO",     "REPEAT", "ENDREPEAT", "RETURN", "BREAK",  "CONTINUE"};
      const std::string keyword = rest.substr(0, rest.find_first_of(" [#"));
      if (numbered && flow.count(keyword))
        fail(line_, col[0], "O",
             "O-word " + toLower(keyword) + " ('" + clip(rest) + "'): " +
                 (model_.control.dialect == "linuxcnc"
                      ? std::string("not carried out here: expand it in the post-processor")
                      : "LinuxCNC's subprograms and control flow, carried out on a machine "
                        "whose file declares dialect=\"linuxcnc\" in its <control>; this one's "
                        "control is " +
                            model_.control.dialect + ": expand them in the post-processor"));
      if (!numbered && upper[0] == 'O' && !executed_block_) {
        prog_.part_name = std::string(trim(text.substr(1)));  // a name at the program start
        return "";
      }
      fail(line_, col[0], "O",
           "'" + clip(text) +
               "' is neither a program number nor a name at "
               "the program start: O-word subprograms and control flow are not "
               "supported");
    }
    // Words, and parameter settings (#n = expr, #<name> = expr): LinuxCNC takes them anywhere in
    // a line, after a line number or beside words, and sets them once the whole line is read
    // (its G-code reference, "Parameters"), so every value on the line, theirs included, is
    // read with the values before it. A setting that is not the line's first item used to end
    // the line there, its words unread ("#1=-2 G0 X-1" lost the move).
    std::vector<Word> words;
    std::vector<std::pair<std::string, double>> named_set;
    std::vector<std::pair<int, double>> numbered_set;
    size_t i = 0;
    while (i < upper.size()) {
      const char c = upper[i];
      if (c == ' ') {
        ++i;
        continue;
      }
      if (c == '#') {
        const int at = col[i];
        size_t k = i + 1;
        while (k < upper.size() && upper[k] == ' ') ++k;
        std::string name;
        std::optional<double> number;
        if (k < upper.size() && upper[k] == '<') {
          const size_t close = upper.find('>', k);
          if (close == std::string::npos) fail(line_, at, "#<", "unclosed parameter name");
          name = lowerNoSpace(upper.substr(k + 1, close - k - 1));
          k = close + 1;
        } else {
          const size_t from = k;
          while (k < upper.size() &&
                 (std::isdigit(static_cast<unsigned char>(upper[k])) || upper[k] == '.'))
            ++k;
          number = parseNumber(upper.substr(from, k - from));
          if (!number) fail(line_, at, "#", "malformed parameter number");
        }
        while (k < upper.size() && upper[k] == ' ') ++k;
        if (k == upper.size() || upper[k] != '=')
          fail(line_, at, "#", "expected '#parameter = value'");
        ++k;
        const double v = expression(upper, k, 0);
        if (number)
          numbered_set.emplace_back(parameterNumber(*number, at), v);
        else
          named_set.emplace_back(name, v);
        i = k;
        continue;
      }
      // Grbl's own commands ('$H' homes, '$J=' jogs, '$$' lists settings, '?' asks the status:
      // Grbl v1.1 "Grbl Interface", "Grbl Commands"): lines a sender writes to Grbl, not blocks;
      // some move the machine, so they are named, not skipped.
      if (i == 0 && (c == '$' || c == '?')) {
        // Grbl's: $ alone, $$, $#, $n=, $H, $J=, $I, $X, $C, $G, $N, $RST, $SLP, ?. Another $
        // line is some control's own command (HAAS NGC writes "$AddRegPart"): named as such.
        const std::string u = toUpper(text.substr(i, 6));
        const char d = u.size() > 1 ? u[1] : ' ';
        const bool grbl =
            c == '?' || u.size() == 1 || d == '$' || d == '#' || d == ' ' ||
            std::isdigit(static_cast<unsigned char>(d)) ||
            ((d == 'H' || d == 'J' || d == 'I' || d == 'X' || d == 'C' || d == 'G' || d == 'N') &&
             (u.size() == 2 || !std::isalpha(static_cast<unsigned char>(u[2])))) ||
            u.rfind("$RST", 0) == 0 || u.rfind("$SLP", 0) == 0;
        fail(line_, col[i], std::string(1, c),
             "'" + clip(text.substr(i, 12)) +
                 (grbl ? "' is a Grbl system command, not a G-code block (some move the machine: "
                         "$H homes, $J= jogs): remove it from the program"
                       : "' is a control's own command line, not a G-code block: what it does "
                         "is not known here; remove it from the program"));
      }
      // LinuxCNC's polar coordinates (@ distance, ^ angle in the XY plane; G-code reference,
      // "Polar Coordinates"): words on a LinuxCNC control (polarTarget), named on others.
      const bool polar = c == '@' || c == '^';
      if (polar && model_.control.dialect != "linuxcnc")
        fail(line_, col[i], std::string(1, c),
             "polar coordinates (LinuxCNC's @ distance, ^ angle) on a control that is not "
             "declared dialect=\"linuxcnc\": post X and Y");
      // Fanuc's (and HAAS's) optional chamfering and corner rounding between two straight or
      // circular moves (Fanuc 0i-MF, "Optional Chamfering and Corner R": ",C" the chamfer's
      // length, ",R" the corner's radius): the corner is cut off, so the path is not the one the
      // end points give. Named.
      if (c == ',' && i + 1 < upper.size() && (upper[i + 1] == 'R' || upper[i + 1] == 'C'))
        fail(line_, col[i], std::string(",") + upper[i + 1],
             std::string(upper[i + 1] == 'R' ? "corner rounding (,R" : "chamfering (,C") +
                 ", Fanuc's optional chamfering and corner R) is not carried out: the corner is "
                 "cut off where the program's end points do not say; post the corner as moves");
      if (!std::isalpha(static_cast<unsigned char>(c)) && !polar)
        fail(line_, col[i], "", "expected a word letter, found '" + clip(text.substr(i, 12)) + "'");
      // Fanuc custom macro B's control flow (Fanuc 0i-MF, "Custom macro": WHILE [..] DOn ..
      // ENDn, IF [..] GOTOn, IF [..] THEN, GOTOn; HAAS likewise): named, not read as words.
      {
        size_t e = i;
        while (e < upper.size() && std::isalpha(static_cast<unsigned char>(upper[e]))) ++e;
        const std::string kw = upper.substr(i, e - i);
        if (kw == "WHILE" || kw == "IF" || kw == "GOTO" || kw == "THEN" || kw == "END" ||
            kw == "DO")
          fail(line_, col[i], kw,
               "custom macro control flow (" + kw +
                   ": Fanuc macro B's WHILE/DO/END, IF, GOTO) is not carried out: post the "
                   "program without it (expanded)");
      }
      Word w;
      w.letter = c;
      w.column = col[i];
      ++i;
      size_t next = i;
      while (next < upper.size() && upper[next] == ' ') ++next;
      if (next == upper.size() || std::isalpha(static_cast<unsigned char>(upper[next])))
        fail(line_, w.column, std::string(1, c),
             "the word has no value: every word of ISO G-code is a letter and a number (a letter "
             "alone, as in Marlin's 'G28 X' that homes X, is not G-code a machine tool's control "
             "reads)");
      const size_t value_at = i;
      w.value = expression(upper, i, 0);
      noteResolution(std::string_view(upper).substr(value_at, i - value_at), c);
      noteDecimalPoint(std::string_view(upper).substr(value_at, i - value_at), c);
      // A feed or a speed places no point: "F1e9" is a program's way of asking for the
      // control's fastest feed (LinuxCNC clamps it to its velocity limit); read as unknown.
      const bool rate = c == 'F' || c == 'S';
      if (!std::isfinite(w.value) || std::abs(w.value) > (rate ? 1e15 : 1e7))
        fail(line_, w.column, std::string(1, c),
             "value " + clip(formatNumber(w.value)) + " is beyond any plausible " +
                 (rate ? "feed or speed" : "length or angle"));
      if (c == 'F' && std::abs(w.value) > 1e7 && huge_feed_line_ == 0) huge_feed_line_ = line_;
      if (c == 'G' || c == 'M') w.code = codeOf(c, w.value);
      words.push_back(w);
    }
    for (const auto& [n, v] : numbered_set) numbered_[n] = v;
    for (const auto& [n, v] : named_set) named_[n] = v;
    return words.empty() ? std::string() : execute(words);
  }

  // ---------------------------------------------------------------- execution
  // The words of a block by letter: X Y Z and rotary letters, I J K R, P Q L H (once each).
  using AxisWords = std::map<char, const Word*>;

  // What a block's G words ask for beyond the modes they set.
  struct BlockModes {
    std::string motion;  // G0-G3 or a drilling cycle, when the block has one
    bool g53 = false, g28 = false, g10 = false, g75 = false;
    bool g30 = false;  // with g28: LinuxCNC's G30 to the position G30.1 stored
    const Word* g682 = nullptr;
    const Word* g92 = nullptr;  // G92, G92.1, G92.2 or G92.3
    const Word* g531 = nullptr;
  };

  std::string execute(const std::vector<Word>& words) {
    executed_block_ = true;
    AxisWords axis_words;
    std::vector<const Word*> g, m;
    sortWords(words, &axis_words, &g, &m);
    // M words first (subprograms refused, program end, TCP switches, tool number), then the G
    // words in modal-group order.
    for (const Word* w : m) mWord(*w, axis_words);
    BlockModes modes;
    for (const Word* w : g) gWord(*w, axis_words, &modes);
    if (modes.g10) return setOffsetByG10(axis_words, g);
    if (modes.g92) return g92Offset(axis_words, *modes.g92);
    if (modes.g682 || modes.g531) return tiltedPlane(axis_words, modes.g682, modes.g531);
    analog_io_block_ = false;
    if (model_.control.dialect == "linuxcnc")
      for (const Word* w : m)
        analog_io_block_ =
            analog_io_block_ || w->code == "M66" || w->code == "M67" || w->code == "M68";
    const bool any_axis = checkAxisWords(axis_words);
    if (!modes.motion.empty()) {
      if (isDrillingCycle(modes.motion)) {
        if (!cycle_ || cycle_code_ != modes.motion) ++prog_.cycles;
        // The initial level: where the tool stood when the cycle mode began (Fanuc: "G81
        // specified while not in canned cycle mode"; LinuxCNC's cycle_il, kept until a motion
        // other than a cycle), not at each cycle block: a sub that repeats "G91 G81 X1 Z-1 R.25"
        // keeps its R plane (LinuxCNC tests/interp/m98m99/05-M98-loops).
        if (!cycle_) cycle_initial_z_ = cur_xyz_[plane_];  // along the drilling axis
        cycle_ = true;
        cycle_code_ = modes.motion;
      } else {
        cycle_ = false;
      }
      motion_ = modes.motion;
    }
    if (sin_mcall_) cycle_ = true;  // Sinumerik MCALL: modal until MCALL alone, whatever G0/G1
    if (modes.g28) return homeMove(axis_words, modes.g30);
    if (modes.g75) return fixedPointMove(axis_words);
    if (modes.g53) return machineMove(axis_words);
    if (sin_cycle_here_) {  // Sinumerik CYCLE8x(...) without MCALL: once, where the block ends
      sin_cycle_here_ = false;
      if (any_axis) move(axis_words, motion_);
      const std::string c = drillCycle({});
      cycle_ = sin_mcall_;
      return c;
    }
    // An arc with its centre words and no axis word ends where it starts: a full circle (RS274NGC
    // and LinuxCNC: "G2 I1"; Fanuc and HAAS: "G02 I-10."), the hole-milling circle. It was read
    // as no move.
    const char* in_plane = plane_ == 2 ? "IJ" : plane_ == 1 ? "IK" : "JK";
    const bool full_circle = !any_axis && !cycle_ && (motion_ == "G2" || motion_ == "G3") &&
                             (axis_words.count(in_plane[0]) || axis_words.count(in_plane[1]));
    if (!any_axis && !full_circle) return "";
    if (cycle_ && comp_side_ != 0) compRefuse(0, cycle_code_, "a drilling cycle");
    if (cycle_) return drillCycle(axis_words);
    return move(axis_words, motion_);
  }

  // The block's words sorted into G, M and the others by letter; T and (Sinumerik) D words
  // carried out here, N F S skipped.
  void sortWords(const std::vector<Word>& words, AxisWords* axis_words, std::vector<const Word*>* g,
                 std::vector<const Word*>* m) {
    block_d_.reset();
    for (const Word& w : words) {
      if (w.letter == 'D' && model_.control.dialect != "sinumerik") {
        block_d_ = w.value;  // G41/G42's tool or G41.1/G42.1's diameter (compOn)
        block_d_column_ = w.column;
      }
      if (w.letter == 'G') {
        g->push_back(&w);
      } else if (w.letter == 'M') {
        m->push_back(&w);
      } else if (w.letter == 'D' && model_.control.dialect == "sinumerik") {
        // Sinumerik: D0 switches the tool length offset off, Dn on (cutting edge n).
        tlc_ = w.value != 0.0;
        if (tlc_) h_ = static_cast<int>(w.value);
      } else if (w.letter == 'F') {
        // modal; its unit is the feed mode in force (G93/G94/G95); beyond any machine's feed
        // (F1e9: "as fast as the control goes"), unknown
        feed_word_ = std::abs(w.value) > 1e7 ? 0.0 : w.value;
      } else if (w.letter == 'N' || w.letter == 'S' || w.letter == 'D') {
        continue;
      } else if (w.letter == 'T') {
        tool_ = static_cast<int>(w.value);
        selected_tool_ = "T" + std::to_string(tool_);
        // Posts that write no M6 (Fusion for personal use, grbl): the T word changes the tool.
        if (!seen_m6_ && !blockHasM6(words)) toolChange(selected_tool_);
      } else {
        if (axis_words->count(w.letter))
          fail(line_, w.column, std::string(1, w.letter), "the word appears twice in the block");
        (*axis_words)[w.letter] = &w;
      }
    }
  }

  void mWord(const Word& w, const AxisWords& axis_words) {
    if (w.code == "M99")
      fail(line_, w.column, w.code,
           model_.control.dialect == "iso"
               ? "M99 outside a subprogram that M98/M97 called: a file of a subprogram (O... "
                 "M99) is run by the program that calls it (give that one, with it after its "
                 "M30); in a main program M99 starts it again, a program that never ends"
               : "subprogram calls are not supported: expand them in the post");
    if (w.code == "M98" || w.code == "M97")
      fail(line_, w.column, w.code, "subprogram calls are not supported: expand them in the post");
    if (w.code == "M0" || w.code == "M1" || w.code == "M60") compStop();
    if (comp_side_ != 0 && (w.code == "M6" || w.code == "M61"))
      compRefuse(w.column, w.code, "a tool change");
    if (comp_side_ != 0 && tcpWordName(w.code))
      compRefuse(w.column, w.code, "a TCP switch (" + w.code + ")");
    if (w.code == "M2" || w.code == "M30") {
      compOff();
      endAt(w.code);
      endModes(w.code);
    } else if (w.code == "M6") {
      seen_m6_ = true;
      toolChange(selected_tool_);
    } else if (w.code == "M61" && axis_words.count('Q')) {
      tool_ = static_cast<int>(axis_words.at('Q')->value);
      loaded_tool_ = tool_;  // LinuxCNC: the tool in the spindle, without a change
    } else if (model_.control.dialect == "linuxcnc" &&
               (w.code == "M70" || w.code == "M71" || w.code == "M72" || w.code == "M73")) {
      modalState(w);
    } else if (!tcpWord(w.code) && !harmlessM().count(w.code)) {
      unknown_.emplace(w.code, line_);
    }
  }

  // LinuxCNC's M70 (save the modal state), M71 (forget it), M72 (restore it), M73 (save it and
  // restore it when the sub returns) (LinuxCNC M-code reference, "M70-M73"): of what they save,
  // the modes that place points: units, plane, distance and arc distance modes, feed mode, work
  // offset, tool length compensation (and its H), cycle return level.
  struct ModalState {
    double unit = 1.0;
    bool units_seen = false;
    int plane = 2;
    bool absolute = true, arc_absolute = false, tlc = false, return_initial = true;
    std::string feed_mode, work;
    int h = 0;
  };

  ModalState modalNow() const {
    return {unit_, units_seen_,           plane_,     absolute_, arc_absolute_,
            tlc_,  cycle_return_initial_, feed_mode_, work_,     h_};
  }

  void restoreModal(const ModalState& m) {
    if (m.unit != unit_ && m.units_seen) setUnits(m.unit);
    plane_ = m.plane;
    absolute_ = m.absolute;
    arc_absolute_ = m.arc_absolute;
    cycle_return_initial_ = m.return_initial;
    feed_mode_ = m.feed_mode;
    tlc_ = m.tlc;
    h_ = m.h;
    if (m.work != work_) selectWorkOffset(m.work);
    cur_xyz_ = currentProgramXyz();  // the tool length in force may have changed
  }

  void modalState(const Word& w) {
    if (w.code == "M70") {
      saved_modal_ = modalNow();
    } else if (w.code == "M71") {
      saved_modal_.reset();
    } else if (w.code == "M72") {
      if (!saved_modal_) fail(line_, w.column, w.code, "M72 restores a modal state no M70 saved");
      restoreModal(*saved_modal_);
    } else {  // M73
      if (call_depth_ == 0 || autorestore_.size() < static_cast<size_t>(call_depth_))
        fail(line_, w.column, w.code,
             "M73 (restore the modal state when the sub returns) outside an o-word sub");
      autorestore_[static_cast<size_t>(call_depth_) - 1] = modalNow();
    }
  }

  // One G word: a mode set (plane, units, distance modes, tool length, work offset, cycle
  // return), a motion or an instruction for the block recorded in modes, or a refusal.
  void gWord(const Word& w, const AxisWords& axis_words, BlockModes* modes) {
    const std::string& c = w.code;
    auto h_word = [&]() -> std::optional<int> {
      if (!axis_words.count('H')) return std::nullopt;
      return static_cast<int>(axis_words.at('H')->value);
    };
    endModes(c);
    if (comp_side_ != 0 && tcpWordName(c)) compRefuse(w.column, c, "a TCP switch (" + c + ")");
    if (comp_side_ != 0 && (c == "G43" || c == "G43.1" || c == "G49"))
      compRefuse(w.column, c, "a tool length offset change (" + c + ")");
    if (tcpWord(c)) {
      if (c == "G49") tlc_ = false;
      if (c.rfind("G43", 0) == 0 || c == "G234") {
        tlc_ = true;
        if (h_word())
          h_ = *h_word();
        else if (h_ == 0)
          h_ = tool_;
      }
      return;
    }
    const bool sinumerik = model_.control.dialect == "sinumerik";
    if (!sinumerik && (c == "G92" || c == "G92.1" || c == "G92.2" || c == "G92.3")) {
      modes->g92 = &w;
      return;
    }
    if ((c == "G41" || c == "G42") && opt_.cutter_comp_wear) {
      // The path is the tool centre by the user's word (GcodeReadOptions::cutter_comp_wear).
      if (wear_comp_line_ == 0) wear_comp_line_ = line_;
      return;
    }
    const bool linuxcnc = model_.control.dialect == "linuxcnc";
    if (linuxcnc && (c == "G28.1" || c == "G30.1")) {
      // LinuxCNC: the current position becomes G28's (G30's) home, #5161-#5166 (#5181-#5186).
      (c == "G28.1" ? home28_ : home30_) = StoredHome{q_, rot_word_};
      return;
    }
    if (linuxcnc && c == "G30" && home30_) {
      modes->g28 = true;
      modes->g30 = true;
      return;
    }
    if (linuxcnc && c == "G43.2")
      fail(line_, w.column, c,
           "G43.2 (an additional tool length offset, LinuxCNC) is not carried out");
    if (linuxcnc && (c == "G41" || c == "G42" || c == "G41.1" || c == "G42.1")) {
      compOn(w, axis_words);
      return;
    }
    if (c == "G40") {
      compOff();
      return;
    }
    // What LinuxCNC refuses while cutter radius compensation is on (interp_convert.cc): a plane
    // change (the plane in force again is fine), coordinate systems, axis offsets, homes, G53,
    // the control mode (G61, G64), canned cycles. A unit change it allows (the queue scaled;
    // here everything is in mm already).
    const int plane_of = c == "G17" ? 2 : c == "G18" ? 1 : c == "G19" ? 0 : -1;
    if (comp_side_ != 0 && ((plane_of >= 0 && plane_of != plane_) || c.rfind("G54", 0) == 0 ||
                            c.rfind("G55", 0) == 0 || c == "G56" || c == "G57" || c == "G58" ||
                            c.rfind("G59", 0) == 0 || c == "G154" || isHaasG110(c) || c == "G10" ||
                            c.rfind("G92", 0) == 0 || c == "G28" || c == "G30" || c == "G53" ||
                            c == "G61" || c == "G61.1" || c == "G64" || isDrillingCycle(c)))
      compRefuse(w.column, c, c);
    auto refused = refusedG().find(c);
    if (refused != refusedG().end() && !isDrillingCycle(c))
      fail(line_, w.column, c, refused->second);
    if (const char* why = refusedMotion(c, model_.control.dialect)) fail(line_, w.column, c, why);
    // G70/G71 as inch and mm are Sinumerik's (and old ISO posts'); on a HAAS they are bolt-hole
    // patterns (G70 circle, G71 arc, G72 along an angle: I, J, L words under a drilling cycle),
    // refused there.
    if ((c == "G70" || c == "G71" || c == "G72") && model_.control.dialect == "iso" &&
        (c == "G72" || cycle_ || axis_words.count('I') || axis_words.count('J') ||
         axis_words.count('L')))
      fail(line_, w.column, c,
           "bolt-hole patterns (G70-G72, HAAS) are not expanded: post the holes one by one");
    if (c == "G0" || c == "G1" || c == "G2" || c == "G3" || isDrillingCycle(c)) {
      modes->motion = c;
    } else if (c == "G17" || c == "G18" || c == "G19") {
      plane_ = c == "G17" ? 2 : (c == "G18" ? 1 : 0);
    } else if (c == "G93" || c == "G94" || c == "G95") {
      feed_mode_ = c;
    } else if (c == "G20" || c == "G70") {
      setUnits(25.4);
    } else if (c == "G21" || c == "G71") {
      setUnits(1.0);
    } else if (c == "G90" || c == "G91") {
      absolute_ = c == "G90";
    } else if (c == "G90.1" || c == "G91.1") {
      arc_absolute_ = c == "G90.1";
    } else if (c == "G43") {
      tlc_ = true;
      h_ = h_word() ? *h_word() : tool_;
    } else if (c == "G49") {  // (a TCP mode that G49 ends was switched off by tcpWord)
      tlc_ = false;
    } else if (c == "G53") {
      modes->g53 = true;
    } else if (c == "G28") {
      modes->g28 = true;
    } else if (c == "G75" && model_.control.dialect == "sinumerik") {
      modes->g75 = true;
    } else if (c == "G10") {
      modes->g10 = true;
    } else if (c == "G68.2") {
      modes->g682 = &w;
    } else if (c == "G53.1") {
      modes->g531 = &w;
    } else if (c == "G69") {
      if (swivel_on_) {
        swivel_ = Eigen::Isometry3d::Identity();
        swivel_on_ = false;
        setFrame(swivel_ * pframe_);
        cur_xyz_ = currentProgramXyz();
      }
    } else if (c == "G80") {
      motion_ = "G0";
      cycle_ = false;
    } else if (c == "G98" || c == "G99") {
      cycle_return_initial_ = c == "G98";
    } else if (c == "G54" || c == "G55" || c == "G56" || c == "G57" || c == "G58" || c == "G59" ||
               c == "G59.1" || c == "G59.2" || c == "G59.3") {
      selectWorkOffset(c);
    } else if (c == "G54.1") {
      if (!axis_words.count('P')) fail(line_, w.column, c, "G54.1 needs a P number");
      selectWorkOffset("G54.1P" + std::to_string(static_cast<int>(axis_words.at('P')->value)));
    } else if (model_.control.dialect == "iso" && (c == "G154" || isHaasG110(c))) {
      // HAAS's additional work offsets (mill operator's manual 96-8000, "G154 Select Work
      // Coordinates P1-P99"; "G110-G129 ... the same as G154 P1-P20"), which are Fanuc's G54.1 Pn
      // (additional workpiece coordinate systems): one offset, G54.1P<n> (set-up key
      // g54.1p<n>_mm; G10 L20 Pn sets it on either control).
      long n = 0;
      if (c == "G154") {
        const double p = axis_words.count('P') ? axis_words.at('P')->value : 0.0;
        if (!(p >= 1 && p <= 99 && p == std::floor(p)))
          fail(line_, w.column, c, "G154 needs P1 to P99 (HAAS's additional work offsets)");
        n = static_cast<long>(p);
      } else {
        n = std::lround(w.value) - 109;
      }
      selectWorkOffset("G54.1P" + std::to_string(n));
    } else if (!harmlessG().count(c)) {
      // Read as not moving the tool, which holds only when no axis word rides with it: with
      // one, the code may be a motion of its own (a spline, a probe, a pocket) and the words
      // would be read as a move of the modal G0/G1.
      for (char l : {'X', 'Y', 'Z', 'A', 'B', 'C', 'U', 'V', 'W'})
        if (axis_words.count(l))
          fail(line_, w.column, c,
               "a code tolver does not know, in a block with axis words (" + std::string(1, l) +
                   "): what the control does with them is not known");
      unknown_.emplace(c, line_);
    }
  }

  // The block's axis words (program units, absolute or incremental): true when it moves an axis;
  // an E word, or a rotary letter the machine lacks, is refused; other letters are noted.
  bool checkAxisWords(const AxisWords& axis_words) {
    bool any_axis = false;
    for (char l : {'X', 'Y', 'Z', '@', '^'}) any_axis |= axis_words.count(l) > 0;
    for (const auto& [l, w] : axis_words) {
      // G-code numbers have no exponent: "Y1e5" is Y1 and an E word, which no milling control
      // here reads (Fanuc's E is a thread lead). Refused, so that Y1e5 is never read as Y1.
      if (l == 'E' && model_.control.dialect == "sinumerik")
        fail(line_, w->column, "E",
             "the program commands axis E (E=" + formatNumber(w->value) + ") but the machine has " +
                 axisList());
      if (l == 'E' && analog_io_block_) {
        // LinuxCNC's M66/M67/M68 E-: the number of an analog input or output (G-code
        // reference, "M66", "M67", "M68"; plasma posts set the torch height control this way).
        ignored_.insert("E (analog I/O number with M66-M68)");
        continue;
      }
      if (l == 'E')
        fail(line_, w->column, "E",
             "an E word (E" + formatNumber(w->value) +
                 "): G-code numbers have no exponent, so '1e5' reads "
                 "as 1 followed by E5; write the number out (100000)");
      if (l == 'X' || l == 'Y' || l == 'Z' || l == 'I' || l == 'J' || l == 'K' || l == 'R' ||
          l == 'P' || l == 'Q' || l == 'L' || l == 'H' || l == '@' || l == '^')
        continue;
      if (letter_axis_.count(l) && model_.axes[letter_axis_.at(l)].isRotary()) {
        any_axis = true;
        continue;
      }
      if (l == 'A' || l == 'B' || l == 'C' || l == 'U' || l == 'V' || l == 'W')
        fail(line_, w->column, std::string(1, l),
             std::string("the program commands axis ") + l + " but the machine has " + axisList());
      ignored_.insert(std::string(1, l) + " word");
    }
    return any_axis;
  }

  // Canned cycles expanded into the motions the control makes along the tool axis (over the
  // hole, down to R, in to Z, out to R or the initial level; pecks and dwells stay within that
  // line): G73, G81-G86, G88, G89 (Fanuc, HAAS, LinuxCNC); G74 and G76 (counter tapping and
  // fine boring) on ISO controls, where LinuxCNC's G76 is threading (refused).
  bool isDrillingCycle(const std::string& c) const {
    static const std::set<std::string> cycles = {"G73", "G81", "G82", "G83", "G84",
                                                 "G85", "G86", "G88", "G89"};
    if (cycles.count(c)) return true;
    return (c == "G74" || c == "G76") && model_.control.dialect != "linuxcnc";
  }

  static bool blockHasM6(const std::vector<Word>& words) {
    for (const Word& w : words)
      if (w.letter == 'M' && w.code == "M6") return true;
    return false;
  }

  std::string axisList() const {
    std::string s;
    for (const Axis& a : model_.axes) s += (s.empty() ? "" : ", ") + a.name;
    return s;
  }

  void setUnits(double u) {
    if (opt_.unit_mm > 0) return;  // forced by the user
    if (units_seen_ && u != unit_)
      prog_.notes.push_back("units change at line " + std::to_string(line_));
    unit_ = u;
    units_seen_ = true;
    prog_.units_declared = true;
    prog_.units = u == 25.4 ? "INCH" : "MM";
  }

  // Modes the word c ends besides the declared off words: a G word of modal group 08 ends a
  // group-08 TCP mode other than itself (Fanuc and HAAS: G43, G44, G49, G43.4, G43.5, G234 are
  // one group, each replacing the other); the machine file's ended_by words (HAAS: G28 cancels
  // tool length compensation, and with it G234); M2 and M30 end every mode.
  void endModes(const std::string& c) {
    static const std::set<std::string> group08 = {"G43",   "G44",   "G49", "G43.1",
                                                  "G43.4", "G43.5", "G234"};
    std::vector<std::string> ended;
    for (const std::string& on : tcp_active_) {
      bool ends = c == "M2" || c == "M30";
      ends = ends || (group08.count(c) && group08.count(on) && c != on);
      auto it = model_.control.tcp_ended_by.find(on);
      if (it != model_.control.tcp_ended_by.end())
        ends = ends || std::find(it->second.begin(), it->second.end(), c) != it->second.end();
      if (ends) ended.push_back(on);
    }
    if (ended.empty()) return;
    for (const std::string& on : ended) tcp_active_.erase(on);
    cur_xyz_ = currentProgramXyz();  // the control converts its position into the new mode
  }

  // TCP words of the control: switches the state; true when c is one.
  bool tcpWord(const std::string& c) {
    bool any = false;
    for (const auto& [on, off] : model_.control.tcp_words) {
      if (c == on) {
        tcp_active_.insert(on);
        any = true;
        if (c[0] == 'M' && !tlc_) tcp_without_tlc_ = true;
      } else if (c == off) {
        tcp_active_.erase(on);
        any = true;
      }
    }
    if (any) {
      // The control converts its current position into the new mode's coordinates.
      cur_xyz_ = currentProgramXyz();
      return true;
    }
    static const std::set<std::string> known = {"G43.4", "G43.5", "G234", "M428", "M128", "G254"};
    if (known.count(c)) {
      std::string declared;
      for (const auto& [on, off] : model_.control.tcp_words)
        declared += (declared.empty() ? "" : ", ") + on;
      fail(line_, 0, c,
           declared.empty()
               ? "a tool-centre-point word, but the machine file declares no TCP words: add "
                 "<control><tcp on=\"" +
                     c + "\" off=\"...\"/></control> to it"
               : "a tool-centre-point word this machine's control does not use (it declares " +
                     declared + "): is the program posted for this machine?");
    }
    return false;
  }
  // TCP mode, or a swivelled plane (CYCLE800), in which the control holds the tool tip at the
  // program's points the same way.
  bool tcpMode() const { return !tcp_active_.empty() || swivel_on_; }

  // The program coordinates (mm) of the current position in the current mode.
  Eigen::Vector3d currentProgramXyz() const {
    if (tcpMode()) {
      if (points_read_ == 0) return Eigen::Vector3d::Zero();
      return frame_.inverse() * Eigen::Vector3d(Gm_inv_ * (last_tip_w_ - g0_) - last_offset_);
    }
    return frame_.inverse() * Eigen::Vector3d(machineOfJoints(q_) - last_offset_);
  }

  // The target of the block in program coordinates (mm), from the words present.
  // An incremental X, Y or Z after a Sinumerik frame changed (TRANS, ATRANS, ROT, CYCLE800) and
  // before that axis was given absolutely: whether the control also moves by the frame's change
  // is machine data (MD 42440 FRAME_OFFSET_INCR_PROG), so the target is not known. Refused.
  Eigen::Vector3d target(const std::map<char, const Word*>& aw) {
    Eigen::Vector3d t = cur_xyz_;
    const char L[3] = {'X', 'Y', 'Z'};
    for (int k = 0; k < 3; ++k) {
      auto it = aw.find(L[k]);
      if (it == aw.end()) continue;
      const double v = it->second->value * unit_;
      const auto dim = sin_dim_.find(L[k]);
      const bool abs = dim == sin_dim_.end() ? absolute_ : dim->second == "AC";
      if (!abs && frame_moved_[k] && model_.control.dialect == "sinumerik")
        fail(line_, it->second->column, std::string(1, L[k]),
             std::string("an incremental ") + L[k] +
                 " (G91 or IC) after the frame changed at line " + std::to_string(frame_line_) +
                 ", before " + L[k] +
                 " was given absolutely: whether the control moves by the frame's change too is "
                 "machine data (MD 42440 FRAME_OFFSET_INCR_PROG); give " +
                 L[k] + " absolutely after the frame");
      if (abs) frame_moved_[k] = false;
      t[k] = abs ? v : t[k] + v;
    }
    if (aw.count('@') || aw.count('^')) polarTarget(aw, &t);
    return t;
  }

  // LinuxCNC's polar coordinates (G-code reference, "Polar Coordinates"; interp_find.cc
  // find_ends): @ the distance from the program origin in XY, ^ the angle from +X (deg). In G90
  // a word missing is the current point's; in G91 each adds to the current point's distance or
  // angle (about the origin, not the current point). Refused as LinuxCNC refuses them: with X or
  // Y, with G53, at the origin without the angle (G90) or at all (G91).
  void polarTarget(const std::map<char, const Word*>& aw, Eigen::Vector3d* t) {
    const Word* w = aw.count('@') ? aw.at('@') : aw.at('^');
    if (aw.count('X') || aw.count('Y'))
      fail(line_, w->column, std::string(1, w->letter),
           "X or Y with polar coordinates (@ ^): LinuxCNC refuses it");
    if (plane_ != 2 && !polar_plane_noted_) {
      polar_plane_noted_ = true;
      prog_.notes.push_back("polar coordinates (@ ^, line " + std::to_string(line_) +
                            ") outside G17: LinuxCNC reads them in XY whatever the plane");
    }
    const Eigen::Vector2d now = cur_xyz_.head<2>();
    const bool at_origin = now.x() == 0 && now.y() == 0;
    double radius = now.norm(), theta = std::atan2(now.y(), now.x());
    if (absolute_) {
      if (aw.count('@') && !aw.count('^') && at_origin)
        fail(line_, w->column, "@", "@ without ^ at the origin: the angle is not known");
      if (aw.count('@')) radius = aw.at('@')->value * unit_;
      if (aw.count('^')) theta = degToRad(aw.at('^')->value);
    } else {
      if (at_origin)
        fail(line_, w->column, std::string(1, w->letter),
             "G91 polar coordinates at the origin: the direction is not known (LinuxCNC refuses "
             "it)");
      if (aw.count('@')) radius += aw.at('@')->value * unit_;
      if (aw.count('^')) theta += degToRad(aw.at('^')->value);
    }
    (*t)[0] = radius * std::cos(theta);
    (*t)[1] = radius * std::sin(theta);
  }

  void updateRotaryWords(const std::map<char, const Word*>& aw) {
    for (const auto& [l, w] : aw) {
      auto it = letter_axis_.find(l);
      if (it == letter_axis_.end() || !model_.axes[it->second].isRotary()) continue;
      const int a = it->second;
      rot_word_[a] = rotaryWordValue(l, rot_word_[a], w->value);
      const Axis& ax = model_.axes[a];
      const double q = ax.nc_sign * rot_word_[a] * kDegToRad;
      if (!ax.endless && (q < ax.travel_min - 1e-9 || q > ax.travel_max + 1e-9))
        fail(line_, w->column, std::string(1, l),
             "rotary word " + formatNumber(rot_word_[a]) + " deg is outside the travel of " +
                 ax.name + " [" + formatNumber(ax.travel_min / kDegToRad) + ", " +
                 formatNumber(ax.travel_max / kDegToRad) +
                 "] deg (mark the axis endless=\"true\" "
                 "in the machine file if it turns without stops)");
    }
  }

  // Emits the point for program coordinates xyz (mm) in the current mode.
  void emit(const Eigen::Vector3d& xyz, bool rapid) {
    const Eigen::Vector3d off = workOffset(work_);
    last_offset_ = off;
    const Eigen::Vector3d xyz_s = frame_ * xyz;  // in the settable frame (G54...)
    ClPoint p;
    p.line = line_;
    p.rapid = rapid;
    // Feed per minute (G94, every control's default) in the program's unit; inverse time (G93)
    // and per revolution (G95) leave it unknown.
    if (feed_mode_ == "G94" && feed_word_ > 0)
      p.feed_mm_min = static_cast<float>(feed_word_ * unit_);
    JointVector q;
    if (tcpMode()) {
      q = q_;
      setRotaries(q);
      Eigen::Vector3d tip, axis;
      nominal_.tipAndAxis(q, &tip, &axis);
      p.p_w = g0_ + Gm_ * (xyz_s + off);
      p.u_w = axis;
      checkFrameAxis(p.u_w);
      // The prismatic joints follow by inverse kinematics (the rotaries stay as commanded).
      const IkSolution sol = ik_.solve(p.p_w, p.u_w, &q);
      if (sol.status == IkStatus::Ok)
        for (int k = 0; k < 3; ++k) q[prismatic_[k]] = sol.q[prismatic_[k]];
    } else {
      q = jointsFromMachine(xyz_s + off);
      // A coordinate last set in machine coordinates stays where it is: a move that does not
      // name it does not carry it into the work offset.
      bool kept = false;
      for (int k = 0; k < 3; ++k)
        if (coord_[k] == kFixed) {
          q[prismatic_[k]] = q_[prismatic_[k]];
          kept = true;
        }
      nominal_.tipAndAxis(q, &p.p_w, &p.u_w);
      if (kept) {
        q_ = q;
        cur_xyz_ = frame_.inverse() * Eigen::Vector3d(machineOfJoints(q) - off);
        pushPoint(p, q, ClProgram::kJointWords);
        return;
      }
    }
    q_ = q;
    cur_xyz_ = xyz;
    pushPoint(p, q, tcpMode() ? ClProgram::kTcpWords : ClProgram::kJointWords);
  }

  // Under a rotated programmable frame in TCP mode (3+2 work as posts write it: the rotaries
  // position the table, the frame turns the program's coordinates with it), the tool axis the
  // rotary words give must be the frame's z: when it is not, the rotary senses or zeros of the
  // machine file differ from the program's, and every point would be placed wrong.
  void checkFrameAxis(const Eigen::Vector3d& u_w) {
    if (frame_checked_ || frame_.linear().isIdentity(1e-12)) return;
    frame_checked_ = true;
    const Eigen::Vector3d z_w = Gm_ * frame_.linear() * Eigen::Vector3d::UnitZ();
    const double angle = std::acos(std::clamp(z_w.normalized().dot(u_w.normalized()), -1.0, 1.0));
    if (angle < degToRad(0.5)) return;
    std::string words;
    for (size_t a = 0; a < model_.axes.size(); ++a)
      if (model_.axes[a].isRotary())
        words += (words.empty() ? "" : " ") + model_.axes[a].name + formatNumber(rot_word_[a]);
    fail(line_, 0, "frame",
         "the tool axis the rotary words give (" + words + ") is " +
             formatWith("%.1f", radToDeg(angle)) +
             " deg from the z axis of the rotated frame "
             "the program works in: the machine file's rotary senses or zeros (nc_sign, "
             "direction) differ from those the program was posted for");
  }

  // The point into the path, unless a coordinate is still unknown.
  void pushPoint(const ClPoint& p, const JointVector& q, char kind) {
    if (!positionKnown()) return;
    last_tip_w_ = p.p_w;
    prog_.path.push_back(p);
    ++points_read_;
    prog_.point_frame.push_back(frame_index_);
    prog_.cycle_orientation.push_back(swivel_on_ ? 1 : 0);
    prog_.joints.push_back(q);
    prog_.tcp.push_back(kind);
    // The axes of a work offset the program sets itself (G10) are fixed in machine coordinates:
    // the set-up does not move the points given in it along them. Only the axes the G10 named
    // (a touch-off `G10 L20 P0 Z0` fixes Z; X and Y stay the set-up's).
    const unsigned char own = kind == ClProgram::kJointWords ? ownAxes(work_) : 0;
    prog_.fixed_axes.push_back(kind == ClProgram::kTcpWords ? 0 : own | fixedMask());
  }

  // Where each of X Y Z stands: given in the work offset (moves with it), in machine
  // coordinates (G53, G28, SUPA: fixed), or not yet commanded (unknown: the control's position
  // at the program start). A move made while a coordinate is unknown is not a point of the path
  // (the tool's position there is not in the program): counted and said once.
  enum Coordinate : char { kInOffset = 0, kFixed = 1, kUnknown = 2 };
  bool positionKnown() {
    if (coord_[0] != kUnknown && coord_[1] != kUnknown && coord_[2] != kUnknown) return true;
    // (lines in order: a jump or a loop runs them in another)
    if (unknown_moves_++ == 0 || line_ < first_unknown_line_) first_unknown_line_ = line_;
    last_unknown_line_ = std::max(last_unknown_line_, line_);
    return false;
  }
  // The axes (bit k: X, Y, Z) of work offset `name` that the program set itself (G10).
  unsigned char ownAxes(const std::string& name) const {
    const auto it = set_axes_.find(name);
    return it == set_axes_.end() ? 0 : it->second;
  }

  unsigned char fixedMask() const {
    unsigned char m = 0;
    for (int k = 0; k < 3; ++k)
      if (coord_[k] == kFixed) m |= static_cast<unsigned char>(1u << k);
    return m;
  }
  void coordinatesGiven(const std::map<char, const Word*>& aw, Coordinate state) {
    const char L[3] = {'X', 'Y', 'Z'};
    for (int k = 0; k < 3; ++k)
      if (aw.count(L[k])) coord_[k] = state;
  }

  // A joint-space point (G53, G28): machine coordinates of the gauge point as given.
  void emitJoints(const JointVector& q) {
    ClPoint p;
    p.line = line_;
    p.rapid = true;
    nominal_.tipAndAxis(q, &p.p_w, &p.u_w);
    q_ = q;
    pushPoint(p, q, ClProgram::kMachineCoordinates);
    cur_xyz_ = currentProgramXyz();
  }

  std::string move(const std::map<char, const Word*>& aw, const std::string& motion) {
    const Eigen::Vector3d start = cur_xyz_;
    const Eigen::Vector3d end = target(aw);
    coordinatesGiven(aw, kInOffset);
    const bool rotary_words = std::any_of(aw.begin(), aw.end(), [&](const auto& kv) {
      auto it = letter_axis_.find(kv.first);
      return it != letter_axis_.end() && model_.axes[it->second].isRotary();
    });
    if (motion == "G2" || motion == "G3") {
      if (rotary_words)
        fail(line_, 0, motion, "an arc with rotary words: arcs must keep the rotary axes fixed");
      arc(aw, motion, start, end);
      return motion;
    }
    if (sin_turns_ > 0)
      fail(line_, 0, "TURN",
           "TURN= (full circles of a helix) on a block that is not an arc (G2/G3)");
    comp_arc_not_allowed_ = false;
    if (compActive()) {
      if (rotary_words) compRefuse(0, motion, "a move with rotary words");
      compStraight(start, end, motion == "G0");
      return motion;
    }
    updateRotaryWords(aw);
    emit(end, motion == "G0");
    return motion;
  }

  // ------------------------------------------------------- cutter radius compensation (LinuxCNC)
  // G41/G42 (the radius from the tool table, --tool-table: the D word's tool, else the tool in the
  // spindle) and G41.1/G42.1 D<diameter> (LinuxCNC G-code reference, "G41, G42" and "G41.1,
  // G42.1"), carried out as LinuxCNC's interpreter does (src/emc/rs274ngc: convert_straight_comp1/
  // comp2 and convert_arc_comp1/comp2 in interp_convert.cc, the queue of interp_queue.cc), in G17
  // (X Y) or G18 (Z X):
  // - the entry move (the first after G41/G42) ends a radius from its programmed end, square to
  //   it (a line) or on the arc offset to the tool's side (an arc), from the uncompensated start;
  // - each later move is offset by the radius to the tool's side and held until the next: an
  //   outside (convex) corner gets an arc of the tool radius about the programmed corner (a G0
  //   a straight traverse to its end); at an inside (concave) corner the held move's end is drawn
  //   back to where the two offset paths meet (line-line, line-arc, arc-line, arc-arc), Z-only
  //   moves held with it; a corner the tool cannot reach without gouging is refused as LinuxCNC
  //   refuses it (concave within 0.05 rad: TOLERANCE_CONCAVE_CORNER);
  // - G40 ends it: the next move starts from the compensated point (a line; an arc is refused);
  //   M0, M1, M2, M30, M60 and the end of the file let the held move go as it is.
  // A negative radius swaps the side. With a zero radius the path is as programmed. Refused while
  // it is on (as LinuxCNC refuses them): drilling cycles, G28/G30/G53, work offset, G92, G10,
  // plane, control mode (G61/G64), tool and tool length changes, TCP switches; and (LinuxCNC
  // carries them out) rotary words and arcs with P turns. Other controls' G41/G42 stay refused
  // (their corners differ: Fanuc's types A/B/C).
  struct CompMove {
    bool arc = false, rapid = false;
    Eigen::Vector3d end = Eigen::Vector3d::Zero();  // the tool centre's end (program coordinates)
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();  // an arc's centre
    int turn = 0;      // an arc's sense: +1 counter-clockwise, -1 clockwise
    double sweep = 0;  // an arc's sweep as queued (rad; 0: a corner arc), for the gouge test
    Eigen::Vector2d dir = Eigen::Vector2d::Zero();  // a line's programmed direction, XY
    int line = 0;
    double feed = 0;
  };
  static constexpr double kConcaveCorner = 0.05;  // rad, LinuxCNC's TOLERANCE_CONCAVE_CORNER

  // The plane's coordinates (LinuxCNC: X Y in G17, Z X in G18), and back with the third
  // coordinate of `w3` (the one along the plane's normal).
  Eigen::Vector2d uv(const Eigen::Vector3d& p) const {
    return plane_ == 2 ? Eigen::Vector2d(p.x(), p.y()) : Eigen::Vector2d(p.z(), p.x());
  }
  Eigen::Vector3d fromUv(const Eigen::Vector2d& q, const Eigen::Vector3d& w3) const {
    return plane_ == 2 ? Eigen::Vector3d(q.x(), q.y(), w3.z())
                       : Eigen::Vector3d(q.y(), w3.y(), q.x());
  }

  bool compActive() const { return comp_side_ != 0 && comp_radius_ > 0; }
  bool toolInsideArc(int turn) const {
    return (comp_side_ > 0 && turn > 0) || (comp_side_ < 0 && turn < 0);
  }
  [[noreturn]] void compRefuse(int column, const std::string& word, const std::string& what) {
    fail(line_, column, word,
         what + " under cutter radius compensation (G4" + (comp_side_ > 0 ? "1" : "2") +
             " at line " + std::to_string(comp_line_) + ") is not carried out: end it (G40) first");
  }
  [[noreturn]] void compGouge(const std::string& what) {
    fail(line_, 0, "G4" + std::string(comp_side_ > 0 ? "1" : "2"),
         what + " (LinuxCNC refuses the program here: cutter radius compensation from line " +
             std::to_string(comp_line_) + ", tool radius " + formatNumber(comp_radius_ / unit_) +
             ")");
  }

  // G41/G42 (tool table) or G41.1/G42.1 (D: the diameter) on a LinuxCNC control.
  void compOn(const Word& w, const AxisWords& aw) {
    const bool by_diameter = w.code == "G41.1" || w.code == "G42.1";
    int side = w.code.rfind("G41", 0) == 0 ? 1 : -1;
    if (plane_ == 0)
      fail(line_, w.column, w.code,
           "cutter radius compensation in G19 (LinuxCNC refuses it: G17 or G18 only)");
    if (comp_side_ != 0)
      fail(line_, w.column, w.code,
           "cutter radius compensation is already on (line " + std::to_string(comp_line_) +
               "): LinuxCNC refuses to turn it on again");
    double radius = 0;
    if (by_diameter) {
      if (!block_d_) fail(line_, w.column, w.code, w.code + " without D (the tool's diameter)");
      if (aw.count('L'))
        fail(line_, aw.at('L')->column, "L",
             w.code + " L (a lathe tool's orientation) is not carried out");
      radius = *block_d_ * unit_ / 2.0;
    } else {
      int tool = loaded_tool_;  // LinuxCNC: the tool in the spindle (not one selected since)
      if (block_d_) {
        if (*block_d_ != std::round(*block_d_) || *block_d_ < 0)
          fail(line_, block_d_column_, "D", w.code + " D must be a tool number (whole, >= 0)");
        tool = static_cast<int>(*block_d_);
      }
      // The program's own G10 L1 R first, then the tool table; LinuxCNC's tool 0 is no tool,
      // of no diameter.
      std::optional<double> diameter;
      if (const auto g10 = set_tool_diameters_.find(tool); g10 != set_tool_diameters_.end())
        diameter = g10->second;
      else if (const auto t = opt_.tool_diameter_mm.find(tool); t != opt_.tool_diameter_mm.end())
        diameter = t->second;
      else if (tool == 0 && !opt_.tool_diameter_mm.empty())
        diameter = 0.0;
      if (!diameter)
        fail(line_, w.column, w.code,
             opt_.tool_diameter_mm.empty()
                 ? "cutter radius compensation needs the tool's diameter: give the control's "
                   "tool table (--tool-table), or --cutter-comp wear if the path already is the "
                   "tool centre (the CAM's wear compensation)"
                 : "tool " + std::to_string(tool) + " is not in the tool table (--tool-table)");
      radius = *diameter / 2.0;
      if (!std::isfinite(radius))
        fail(line_, w.column, w.code,
             "tool " + std::to_string(tool) +
                 " is a lathe tool in the tool table (Q orientation): its compensation is not "
                 "carried out");
    }
    if (radius < 0) {
      radius = -radius;
      side = -side;
    }
    comp_side_ = side;
    comp_radius_ = radius;
    comp_first_ = true;
    comp_line_ = line_;
    comp_cur_ = cur_xyz_;
    comp_emitted_ = cur_xyz_;
    if (prog_.radius_comp_line == 0) prog_.radius_comp_line = line_;
    ++radius_comp_blocks_;
  }

  // G40, and the program's stops and end: the held moves go as they are.
  void compOff() {
    if (compActive() && !comp_first_) {
      compFlush();
      cur_xyz_ = comp_programmed_;
      comp_arc_not_allowed_ = true;
    }
    comp_side_ = 0;
    comp_first_ = true;
  }
  void compStop() {
    if (compActive()) compFlush();
  }

  void compSetEndpoint(const Eigen::Vector2d& e) {
    comp_endpoint_ = e;
    comp_endpoint_valid_ = true;
  }
  static double findTurn(const Eigen::Vector2d& p1, const Eigen::Vector2d& c, int turn,
                         const Eigen::Vector2d& p2) {
    if (turn == 0) return 0.0;
    double alpha = std::atan2(p1.y() - c.y(), p1.x() - c.x());
    double beta = std::atan2(p2.y() - c.y(), p2.x() - c.x());
    if (turn > 0) {
      if (beta <= alpha) beta += 2 * M_PI;
      return beta - alpha + (turn - 1) * 2 * M_PI;
    }
    if (alpha <= beta) alpha += 2 * M_PI;
    return beta - alpha + (turn + 1) * 2 * M_PI;
  }

  // LinuxCNC's move_endpoint_and_flush: the held moves' XY end moved to e, then let go.
  void compMoveEndpointAndFlush(const Eigen::Vector2d& e) {
    for (CompMove& q : comp_queue_) {
      if (q.arc) {
        const double r1 = (uv(q.end) - q.centre).norm(), r2 = (e - q.centre).norm();
        const double l2 = findTurn(comp_endpoint_, q.centre, q.turn, e);
        if (std::abs(r1 - r2) > 0.01 * unit_)
          compGouge("the compensated arc's ends are " + formatNumber((r1 - r2) / unit_) +
                    " apart in radius");
        if (q.sweep != 0.0 && comp_endpoint_valid_ && std::abs(l2) > std::abs(q.sweep) + 0.0254)
          compGouge("an arc in a concave corner the tool cannot reach without gouging");
      } else if (comp_endpoint_valid_ && q.dir.dot(e - comp_endpoint_) < 0) {
        compGouge(std::string(q.rapid ? "a straight traverse" : "a straight feed") +
                  " in a concave corner the tool cannot reach without gouging");
      }
      q.end = fromUv(e, q.end);
    }
    compFlush();
    compSetEndpoint(e);
  }

  // The held moves emitted in order (their own line and feed), the queue emptied.
  void compFlush() {
    comp_endpoint_valid_ = false;
    if (comp_queue_.empty()) return;
    const Eigen::Vector3d programmed = cur_xyz_;
    const int line = line_;
    const double feed = feed_word_;
    for (const CompMove& q : comp_queue_) {
      line_ = q.line;
      feed_word_ = q.feed;
      const int before = static_cast<int>(prog_.path.size());
      if (q.arc) {
        const Eigen::Vector3d c = fromUv(q.centre, comp_emitted_);
        emitArc(q.turn > 0 ? "G3" : "G2", comp_emitted_, q.end, c, 0, std::nullopt);
      } else {
        emit(q.end, q.rapid);
      }
      comp_emitted_ = q.end;
      // Points of an earlier line, at the top level (a sub's belong to its call): noted for
      // compLateToTheirLines.
      const int count = static_cast<int>(prog_.path.size()) - before;
      if (q.line != line && count > 0 && flow_depth_ == 0 && call_depth_ == 0) {
        if (!comp_late_.empty() && comp_late_.back().line == q.line &&
            comp_late_.back().first + comp_late_.back().count == before)
          comp_late_.back().count += count;
        else
          comp_late_.push_back({before, count, q.line});
      }
    }
    comp_queue_.clear();
    line_ = line;
    feed_word_ = feed;
    cur_xyz_ = programmed;
  }

  void compEnqueue(CompMove m) {
    m.line = line_;
    m.feed = feed_word_;
    comp_queue_.push_back(m);
  }

  // The block's own move held until the next: the tool centre at its end, the programmed point
  // the next move starts from (what relative words and arc centres read).
  void compHold(const CompMove& m, const Eigen::Vector3d& programmed_end) {
    compEnqueue(m);
    comp_first_ = false;
    comp_cur_ = m.end;
    comp_programmed_ = programmed_end;
    cur_xyz_ = programmed_end;
  }

  // An outside corner: an arc of the tool radius about the programmed corner to `mid` (a G0: a
  // straight traverse), emitted at once.
  void compCorner(const Eigen::Vector2d& mid, const Eigen::Vector2d& corner_at, bool rapid) {
    CompMove corner;
    corner.arc = !rapid;
    corner.rapid = rapid;
    corner.end = fromUv(mid, comp_cur_);
    corner.centre = corner_at;
    corner.turn = comp_side_ > 0 ? -1 : 1;
    compEnqueue(corner);
    compFlush();
    compSetEndpoint(mid);
  }

  // A straight move (G0/G1) from the programmed start to the programmed end.
  void compStraight(const Eigen::Vector3d& start, const Eigen::Vector3d& end, bool rapid) {
    const double R = comp_radius_;
    const Eigen::Vector2d c = uv(comp_cur_), p = uv(end);
    if (comp_first_) {  // convert_straight_comp1
      if (!((p - c).norm() > R))
        compGouge(
            "the entry move of cutter radius compensation is not longer than the tool "
            "radius");
      const double alpha = std::atan2(p.y() - c.y(), p.x() - c.x()) + comp_side_ * M_PI / 2;
      const Eigen::Vector2d e = p + R * Eigen::Vector2d(std::cos(alpha), std::sin(alpha));
      compSetEndpoint(c);
      CompMove m;
      m.rapid = rapid;
      m.end = fromUv(e, end);
      m.dir = Eigen::Vector2d(std::cos(alpha), std::sin(alpha));
      compHold(m, end);
      return;
    }
    const Eigen::Vector2d op = uv(start);
    CompMove m;
    m.rapid = rapid;
    if (p == op) {  // no XY motion: held with the move before it
      m.end = fromUv(c, end);
      m.dir = Eigen::Vector2d::Zero();
      compHold(m, end);
      return;
    }
    double theta = std::atan2(c.y() - op.y(), c.x() - op.x());
    double alpha = std::atan2(p.y() - op.y(), p.x() - op.x());
    double beta = 0, gamma = 0;
    if (comp_side_ > 0) {
      if (theta < alpha) theta += 2 * M_PI;
      beta = theta - alpha - M_PI / 2;
      gamma = M_PI / 2;
    } else {
      if (alpha < theta) alpha += 2 * M_PI;
      beta = alpha - theta - M_PI / 2;
      gamma = -M_PI / 2;
    }
    const Eigen::Vector2d to_side(std::cos(alpha + gamma), std::sin(alpha + gamma));
    const Eigen::Vector2d e = p + R * to_side;
    Eigen::Vector2d mid = op + R * to_side;
    const double small = kConcaveCorner;
    const CompMove* front = comp_queue_.empty() ? nullptr : &comp_queue_.front();
    const bool front_arc = front != nullptr && front->arc;
    bool concave = beta < -small || beta > M_PI + small;
    if (!concave && beta > M_PI - small && front_arc &&
        ((comp_side_ < 0 && front->turn > 0) || (comp_side_ > 0 && front->turn < 0)))
      concave = true;                // an "h": kept above and to the side
    if (!concave && beta > small) {  // an outside corner: an arc about it (a G0: a line)
      compMoveEndpointAndFlush(c);
      compCorner(mid, op, rapid);
    } else if (concave) {
      if (!front_arc) {  // line to line: the held line's end drawn back
        const double halfcorner = (beta + M_PI) / 2.0;
        if (halfcorner == 0.0) compGouge("a zero-degree inside corner");
        const double retreat = R / std::tan(halfcorner);
        mid = c + retreat * Eigen::Vector2d(std::cos(theta + gamma), std::sin(theta + gamma));
        compMoveEndpointAndFlush(mid);
      } else {  // arc to line: where the line's offset meets the held arc
        const CompMove& prev = *front;
        const double oldrad = (prev.centre - uv(prev.end)).norm();
        const double base_dir = std::atan2(p.y() - op.y(), p.x() - op.x());
        const double th = prev.turn > 0 ? base_dir + M_PI / 2 : base_dir - M_PI / 2;
        const double phi = std::atan2(prev.centre.y() - op.y(), prev.centre.x() - op.x());
        const bool inside = toolInsideArc(prev.turn);
        const double oldrad_uncomp = inside ? oldrad + R : oldrad - R;
        const double d = oldrad_uncomp * std::cos(th - phi);
        const double l = (inside ? d - R : d + R) / oldrad;
        if (l > 1.0 || l < -1.0)
          compGouge(
              "an arc to a line makes a corner the compensated tool cannot fit in "
              "without gouging");
        const double a = std::acos(l);
        const double angle =
            inside ? (prev.turn > 0 ? -a : a) + th + M_PI : (prev.turn > 0 ? a : -a) + th + M_PI;
        mid = prev.centre + oldrad * Eigen::Vector2d(std::cos(angle), std::sin(angle));
        compMoveEndpointAndFlush(mid);
      }
    } else {  // straight on, or a tangent arc to a line
      compFlush();
      compSetEndpoint(c);
    }
    m.end = fromUv(e, end);
    m.dir = p - op;
    compHold(m, end);
  }

  // An arc (G2/G3) from the programmed start to the programmed end about its centre.
  void compArc(const std::map<char, const Word*>& aw, const std::string& motion,
               const Eigen::Vector3d& start, const Eigen::Vector3d& end,
               const Eigen::Vector3d& centre3, int turns) {
    if (turns != 0) compRefuse(aw.count('P') ? aw.at('P')->column : 0, "P", "an arc of P turns");
    const double R = comp_radius_;
    const int turn = motion == "G3" ? 1 : -1;
    const Eigen::Vector2d c = uv(comp_cur_), p = uv(end);
    Eigen::Vector2d centre = uv(centre3);
    const bool inside = toolInsideArc(turn);
    const double arc_radius = (centre - p).norm();
    CompMove m;
    m.arc = true;
    m.turn = turn;
    if (comp_first_) {  // convert_arc_comp1
      if (!((p - c).norm() > R))
        compGouge(
            "the entry arc of cutter radius compensation does not end farther than the "
            "tool radius from its start");
      if (inside && arc_radius <= R) compGouge("the tool radius is not less than the arc's");
      const double gamma = inside ? std::atan2(centre.y() - p.y(), centre.x() - p.x())
                                  : std::atan2(p.y() - centre.y(), p.x() - centre.x());
      const Eigen::Vector2d e = p + R * Eigen::Vector2d(std::cos(gamma), std::sin(gamma));
      // The compensated arc's centre: on the line from its end toward the programmed centre,
      // as far from its start as from its end.
      const double b_len = (c - e).norm() / 2.0;
      const double ab_ang = std::atan2(centre.y() - e.y(), centre.x() - e.x());
      const double a_ang = std::atan2(c.y() - e.y(), c.x() - e.x()) - ab_ang;
      if (std::abs(std::cos(a_ang)) < 1e-7) compGouge("the tool radius is not less than the arc's");
      const double c_len = b_len / std::cos(a_ang);
      centre = e + c_len * Eigen::Vector2d(std::cos(ab_ang), std::sin(ab_ang));
      m.end = fromUv(e, end);
      m.centre = centre;
      m.sweep = findTurn(c, centre, turn, e);
      compHold(m, end);
      return;
    }
    const Eigen::Vector2d op = uv(start);
    double theta = std::atan2(c.y() - op.y(), c.x() - op.x());
    theta = comp_side_ > 0 ? theta - M_PI / 2 : theta + M_PI / 2;
    double delta = std::atan2(centre.y() - op.y(), centre.x() - op.x());
    const double alpha = turn > 0 ? delta - M_PI / 2 : delta + M_PI / 2;
    double beta = comp_side_ > 0 ? theta - alpha : alpha - theta;
    beta = beta > 1.5 * M_PI ? beta - 2 * M_PI : beta < -M_PI / 2 ? beta + 2 * M_PI : beta;
    double gamma = 0;
    if (inside) {
      gamma = std::atan2(centre.y() - p.y(), centre.x() - p.x());
      if (arc_radius <= R) compGouge("the tool radius is not less than the arc's");
    } else {
      gamma = std::atan2(p.y() - centre.y(), p.x() - centre.x());
      delta += M_PI;
    }
    const Eigen::Vector2d e = p + R * Eigen::Vector2d(std::cos(gamma), std::sin(gamma));
    const double small = kConcaveCorner;
    const CompMove* front = comp_queue_.empty() ? nullptr : &comp_queue_.front();
    if (beta < -small || beta > M_PI + small || (std::abs(beta - M_PI) < small && !inside)) {
      Eigen::Vector2d mid;
      if (front == nullptr || !front->arc) {  // line to arc
        const double cy = arc_radius * std::sin(beta - M_PI / 2);
        const double dist = inside ? arc_radius - R : arc_radius + R;
        const double l = (inside ? cy + R : cy - R) / dist;
        if (l > 1.0 || l < -1.0)
          compGouge("an arc in a concave corner the tool cannot reach without gouging");
        const double a = std::asin(l);
        const double angle = inside ? (turn > 0 ? theta + a : theta - a)
                                    : (turn > 0 ? theta + M_PI - a : theta + M_PI + a);
        mid = centre + dist * Eigen::Vector2d(std::cos(angle), std::sin(angle));
      } else {  // arc to arc
        const CompMove& prev = *front;
        const double oldrad = (prev.centre - uv(prev.end)).norm();
        const double newrad = inside ? arc_radius - R : arc_radius + R;
        const double arc_cc = (prev.centre - centre).norm();
        if (oldrad == 0 || arc_cc == 0)
          compGouge("an arc to an arc about the same centre at a corner");
        const double a =
            (oldrad * oldrad + arc_cc * arc_cc - newrad * newrad) / (2 * oldrad * arc_cc);
        if (a > 1.0 || a < -1.0)
          compGouge(
              "an arc to an arc makes a corner the compensated tool cannot fit in "
              "without gouging");
        const double pullback = std::acos(a);
        const double cc_dir =
            std::atan2(centre.y() - prev.centre.y(), centre.x() - prev.centre.x());
        const bool prev_inside = toolInsideArc(prev.turn);
        const double dir = prev_inside == (turn > 0) ? cc_dir + pullback : cc_dir - pullback;
        mid = prev.centre + oldrad * Eigen::Vector2d(std::cos(dir), std::sin(dir));
      }
      compMoveEndpointAndFlush(mid);
    } else if (beta > small) {  // an outside corner: an arc about it first
      const Eigen::Vector2d mid = op + R * Eigen::Vector2d(std::cos(delta), std::sin(delta));
      compFlush();
      compCorner(mid, op, false);
    } else {  // tangent
      compFlush();
      compSetEndpoint(c);
    }
    m.end = fromUv(e, end);
    m.centre = centre;
    m.sweep = findTurn(op, centre, turn, p);
    compHold(m, end);
  }

  void arc(const std::map<char, const Word*>& aw, const std::string& motion,
           const Eigen::Vector3d& start, const Eigen::Vector3d& end) {
    std::optional<Eigen::Vector3d> other_centre;
    const Eigen::Vector3d centre = arcCentre(aw, motion, start, end, &other_centre);
    const int turns = arcTurns(aw);
    if (comp_arc_not_allowed_)
      fail(line_, 0, motion,
           "an arc as the first move after G40 (LinuxCNC refuses it: the move from the "
           "compensated point must be a line)");
    if (compActive()) {
      compArc(aw, motion, start, end, centre, turns);
      return;
    }
    emitArc(motion, start, end, centre, turns, other_centre);
  }

  // The centre of the block's arc from start to end (R, or I J K as the arc distance mode reads
  // them); `other_centre`: I J K read the other way, for a refusal's hint.
  Eigen::Vector3d arcCentre(const std::map<char, const Word*>& aw, const std::string& motion,
                            const Eigen::Vector3d& start, const Eigen::Vector3d& end,
                            std::optional<Eigen::Vector3d>* other_centre_out) {
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    n[plane_] = 1.0;
    const Eigen::Vector3d axis = motion == "G3" ? n : -n;
    // L on an arc (HAAS: the full circle repeated L times, as its thread milling posts write
    // G91 G03 I.. Z.. L..): not carried out, never dropped.
    if (aw.count('L'))
      fail(line_, aw.at('L')->column, "L",
           "L on an arc (HAAS: the full circle repeated) is not carried out: post the turns as "
           "arcs");
    Eigen::Vector3d centre;
    // The centre read the other way (I J K absolute when the control reads them incremental, and
    // back), for the refusal's hint when the end is off the circle (Sinumerik's AC/IC aside).
    std::optional<Eigen::Vector3d> other_centre;
    if (aw.count('R')) {
      const double r = aw.at('R')->value * unit_;
      Eigen::Vector3d chord = end - start;
      chord -= n * n.dot(chord);
      const double d = chord.norm();
      if (d < 1e-9) fail(line_, aw.at('R')->column, "R", "an R arc needs distinct end points");
      const double h2 = r * r - d * d / 4.0;
      if (h2 < 0 && d / 2.0 - std::abs(r) > arcRadiusTolerance(std::abs(r)))
        fail(line_, aw.at('R')->column, "R",
             "radius " + formatNumber(std::abs(r / unit_)) + " is shorter than half the chord");
      const double h = std::sqrt(std::max(0.0, h2));
      const Eigen::Vector3d left = axis.cross(chord / d);
      const Eigen::Vector3d mid = start + 0.5 * chord;
      centre = mid + (r > 0 ? h : -h) * left;
    } else {
      const char ijk[3] = {'I', 'J', 'K'};
      Eigen::Vector3d off = Eigen::Vector3d::Zero();
      bool any = false;
      for (int k = 0; k < 3; ++k)
        if (aw.count(ijk[k])) {
          off[k] = aw.at(ijk[k])->value * unit_;
          any = true;
        }
      if (!any) fail(line_, 0, motion, "an arc needs I, J, K or R");
      bool in_plane = true;  // both of the plane's letters given
      for (int k = 0; k < 3; ++k) {
        // I=AC(v): that coordinate of the centre is absolute (Sinumerik); the others relative.
        const auto dim = sin_dim_.find(ijk[k]);
        const bool abs = dim == sin_dim_.end() ? arc_absolute_ : dim->second == "AC";
        centre[k] = abs ? off[k] : start[k] + off[k];
        in_plane = in_plane && (k == plane_ || aw.count(ijk[k]));
      }
      centre -= n * n.dot(centre - start);
      if (in_plane && sin_dim_.empty()) {
        Eigen::Vector3d c;
        for (int k = 0; k < 3; ++k) c[k] = arc_absolute_ ? start[k] + off[k] : off[k];
        other_centre = c - n * n.dot(c - start);
      }
    }
    *other_centre_out = other_centre;
    return centre;
  }

  // The full turns before the end: LinuxCNC's P (the number of turns, 1 by default) less one,
  // Sinumerik's TURN=.
  int arcTurns(const std::map<char, const Word*>& aw) {
    int turns = 0;
    if (aw.count('P')) {
      const Word& p = *aw.at('P');
      if (model_.control.dialect != "linuxcnc")
        fail(line_, p.column, "P",
             "a P word on an arc (LinuxCNC's turns) on a control that is "
             "not declared dialect=\"linuxcnc\"");
      if (!(p.value >= 1 && p.value <= 1000 && p.value == std::round(p.value)))
        fail(line_, p.column, "P", "the number of turns must be a whole number from 1 to 1000");
      turns = static_cast<int>(p.value) - 1;
    }
    if (sin_turns_ >= 0) turns = sin_turns_;  // Sinumerik's TURN= on this block
    return turns;
  }

  // The arc from start to end about centre (G2 clockwise, G3 counter-clockwise about the
  // plane's normal), expanded within the chordal tolerance and emitted.
  void emitArc(const std::string& motion, const Eigen::Vector3d& start, const Eigen::Vector3d& end,
               const Eigen::Vector3d& centre, int turns,
               const std::optional<Eigen::Vector3d>& other_centre) {
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    n[plane_] = 1.0;
    const Eigen::Vector3d axis = motion == "G3" ? n : -n;
    std::vector<Eigen::Vector3d> pts;
    const double tol = opt_.chordal_tolerance_mm;
    const double r0 = (start - centre - n * n.dot(start - centre)).norm();
    // Bounded work: a full turn at this radius and tolerance, before anything is expanded.
    if (!(arcPointsPerTurn(r0, tol) * (turns + 1) <= kMaxArcPoints))
      fail(line_, 0, motion,
           "an arc of radius " + formatNumber(r0) +
               " mm would expand into more than a million "
               "points at chordal tolerance " +
               formatNumber(tol) + " mm (raise --chordal-tol)");
    const double radius_tol = arcRadiusTolerance(r0);
    if (!interpolateArc(start, end, centre, axis, tol, radius_tol, pts, turns)) {
      const Eigen::Vector3d re = end - centre - n * n.dot(end - centre);
      fail(line_, 0, motion,
           "the end point is not on the arc's circle: its radius differs from the start's by " +
               formatWith("%.2f", std::abs(re.norm() - r0) * 1000.0) + " um, more than the " +
               formatWith("%.2f", radius_tol * 1000.0) + " um the control accepts (" +
               (model_.control.dialect == "linuxcnc" ? "LinuxCNC's rule"
                : model_.control.arc_radius_tolerance_mm > 0
                    ? "the machine file's arc_radius_tolerance_mm"
                    : "RS274NGC's rule") +
               ", or four steps of the program's " + std::to_string(max_decimals_) + " decimals)" +
               otherCentreHint(other_centre, start, end, n, radius_tol));
    }
    ++prog_.arcs_expanded;
    for (const Eigen::Vector3d& p : pts) emit(p, false);
  }

  // When the arc closes with I J K read the other way (absolute against incremental), the post
  // most likely wrote them so: said, with the word that makes the control read them that way.
  std::string otherCentreHint(const std::optional<Eigen::Vector3d>& c, const Eigen::Vector3d& start,
                              const Eigen::Vector3d& end, const Eigen::Vector3d& n,
                              double radius_tol) const {
    if (!c) return "";
    const double r0 = (start - *c - n * n.dot(start - *c)).norm();
    const double r1 = (end - *c - n * n.dot(end - *c)).norm();
    if (!(r0 > 1e-6) || std::abs(r1 - r0) > std::max(radius_tol, arcRadiusTolerance(r0))) return "";
    return arc_absolute_
               ? "; read incremental (from the start, G91.1) I J K put the end on the circle: "
                 "the post wrote incremental centres"
               : "; read as the centre's absolute coordinates, I J K put the end on the circle "
                 "(within " +
                     formatWith("%.2f", std::abs(r1 - r0) * 1000.0) +
                     " um): the post wrote absolute arc centres, which LinuxCNC and Mach3 read "
                     "so under G90.1 (other controls by a setting): if yours does, add G90.1 "
                     "before the arcs";
  }

  std::string machineMove(const std::map<char, const Word*>& aw) {
    JointVector q = q_;
    bool named = false;  // G53 (SUPA, G153) alone moves nothing
    for (const auto& [l, w] : aw) named |= letter_axis_.count(l) > 0;
    if (!named) return "G53";
    // In G91 controls differ: LinuxCNC refuses the block ("Cannot use g53 incremental",
    // rs274ngc_return.hh), Fanuc documents G53 for G90 only. Refused, never guessed.
    if (!absolute_)
      fail(line_, 0, "G53",
           "a move in machine coordinates (G53, SUPA, G153) in G91: controls differ (LinuxCNC "
           "refuses it; Fanuc documents it for G90 only): write it in G90");
    for (const auto& [l, w] : aw) {
      auto it = letter_axis_.find(l);
      if (it == letter_axis_.end()) continue;
      const Axis& ax = model_.axes[it->second];
      if (ax.isRotary()) {
        rot_word_[it->second] = w->value;
        q[it->second] = ax.nc_sign * w->value * kDegToRad;
      } else {
        q[it->second] = ax.nc_sign * w->value * unit_;
        for (int k = 0; k < 3; ++k)
          if (prismatic_[k] == it->second) coord_[k] = kFixed;
      }
    }
    emitJoints(q);
    return "G53";
  }

  // G28 (and LinuxCNC's G30 once G30.1 stored its position): via the intermediate point to the
  // home position, machine zero unless LinuxCNC's G28.1 stored another.
  std::string homeMove(const std::map<char, const Word*>& aw, bool g30 = false) {
    const std::optional<StoredHome>& stored = g30 ? home30_ : home28_;
    bool named = false;
    for (const auto& [l, w] : aw) named |= letter_axis_.count(l) > 0;
    // G28 without axis words: HAAS returns every axis to machine zero (Mill Operator's Manual,
    // G28), as LinuxCNC does; a Fanuc control moves none (G28 IP_: only the axes named). Read
    // as HAAS and LinuxCNC; on an ISO control it is said in a note.
    if (!named && model_.control.dialect == "iso" && bare_g28_line_ == 0) bare_g28_line_ = line_;
    if (named) {  // via the intermediate point, in program coordinates
      const auto saved = motion_;
      move(aw, "G0");
      motion_ = saved;
    }
    JointVector q = q_;
    for (size_t a = 0; a < model_.axes.size(); ++a) {
      const std::string& n = model_.axes[a].name;
      if (!named || (n.size() == 1 && aw.count(static_cast<char>(std::toupper(n[0]))))) {
        q[a] = stored ? stored->q[static_cast<int>(a)] : 0.0;
        if (model_.axes[a].isRotary()) rot_word_[a] = stored ? stored->rot_word[a] : 0.0;
        for (int k = 0; k < 3; ++k)
          if (prismatic_[k] == static_cast<int>(a)) coord_[k] = kFixed;
      }
    }
    emitJoints(q);
    return g30 ? "G30" : "G28";
  }

  // Sinumerik G75, fixed-point approach (SINUMERIK 840D sl Programming Manual, Fundamentals,
  // "Fixed-point approach (G75)"): G75 FP=n X1=0 Z1=0 takes the axes named to fixed point n
  // (1 by default), a position in machine data ($MA_FIX_POINT_POS) that a machine file does not
  // carry; the values written are not positions. Not a point of the path: the axes named are
  // unknown until the program commands them again (as at the program start). A rotary axis
  // named is refused: its angle would be needed by the next point.
  std::string fixedPointMove(const std::map<char, const Word*>& aw) {
    const char L[3] = {'X', 'Y', 'Z'};
    bool named = false;
    for (const auto& [l, w] : aw) {
      const auto it = letter_axis_.find(l);
      if (it == letter_axis_.end()) continue;
      if (model_.axes[it->second].isRotary())
        fail(line_, w->column, std::string(1, l),
             "G75 takes " + std::string(1, l) +
                 " to a fixed point in the control's machine data ($MA_FIX_POINT_POS), which "
                 "the machine file does not give: position the rotary axis with G0 or SUPA");
      for (int k = 0; k < 3; ++k)
        if (l == L[k]) {
          coord_[k] = kUnknown;
          named = true;
        }
    }
    if (!named) fail(line_, 0, "G75", "G75 names no axis (write G75 X0 Y0 or G75 Z0)");
    if (g75_line_ == 0) g75_line_ = line_;
    return "G75";
  }

  // G92 coordinate system offset (LinuxCNC G-code reference, "G92"; Fanuc 0i-MF "Setting a
  // workpiece coordinate system (G92)"; HAAS "G92 Set Work Coordinate Systems Shift Value"):
  // the current point's coordinates become the words given, by an offset that shifts every
  // work coordinate system (held here as a translation of the programmable frame, so that a
  // later G54..G59 keeps it); the axes not named keep their offset. G92.1 clears the offset,
  // G92.2 suspends it, G92.3 restores it. Not a point of the path. Refused: a rotary word (an
  // angle offset is not modelled), an axis whose position is not known yet.
  std::string g92Offset(const std::map<char, const Word*>& aw, const Word& g) {
    const char L[3] = {'X', 'Y', 'Z'};
    for (const auto& [l, w] : aw) {
      const auto it = letter_axis_.find(l);
      if (it != letter_axis_.end() && model_.axes[it->second].isRotary())
        fail(line_, w->column, std::string(1, l),
             g.code + " on the rotary axis " + std::string(1, l) +
                 " is not supported (an angle offset)");
    }
    if (g.code == "G92") {
      Eigen::Vector3d o = g92_offset_;
      // In a LinuxCNC turned system the offset is taken before the turn (interp_convert.cc
      // convert_axis_offsets: offset = current + offset - word, in program coordinates).
      const Eigen::Vector3d settable =
          rotationOf(work_) != 0.0
              ? Eigen::Vector3d(cur_xyz_ + (g92_on_ ? g92_offset_ : Eigen::Vector3d::Zero()))
              : Eigen::Vector3d(frame_ * cur_xyz_);
      bool any = false;
      for (int k = 0; k < 3; ++k) {
        const auto it = aw.find(L[k]);
        if (it == aw.end()) continue;
        if (coord_[k] == kUnknown)
          fail(line_, it->second->column, "G92",
               std::string("G92 names ") + L[k] + " before the program gave its position");
        o[k] = settable[k] - it->second->value * unit_;
        any = true;
      }
      if (!any) fail(line_, g.column, "G92", "G92 without an X, Y or Z word");
      g92_offset_ = o;
      g92_on_ = true;
    } else if (g.code == "G92.1") {
      g92_offset_.setZero();
      g92_on_ = false;
    } else {
      g92_on_ = g.code == "G92.3";
    }
    if (g92_line_ == 0) g92_line_ = line_;
    Eigen::Isometry3d f = Eigen::Isometry3d::Identity();
    if (g92_on_) f.translation() = g92_offset_;
    if (rotationOf(work_) != 0.0)
      applyG92Frame();
    else
      setFrame(f);
    return g.code;
  }

  // A drilling cycle's hole(s). In G91 (Fanuc 0i-MF "Canned cycle for drilling", HAAS, LinuxCNC
  // interp_cycles.cc, which cites NCMS p. 98): X Y move from the current position, R is the
  // distance from the initial level (the Z where the cycle began) to the R point and Z the
  // distance from the R point to the bottom. Repeats (L; Fanuc's K on an ISO control where K is
  // no peck depth): in G91 each at the next increment, in G90 at the same place. R and Z are kept
  // as given; read in the other distance mode than they were given in, controls differ (LinuxCNC
  // and Fanuc take the kept numbers in the new mode): refused until they are given again.
  //
  // The drilling axis: Z in G17; in G18 and G19 LinuxCNC drills along Y and X (G-code reference,
  // "Canned cycles": "in the XZ plane ... Y"), a Fanuc control along Z or by the plane as its
  // parameter 5101#0 FXY says, which a machine file does not carry: refused there.
  std::string drillCycle(const std::map<char, const Word*>& aw) {
    const bool sinumerik_cycle = cycle_code_.rfind("CYCLE", 0) == 0;  // planes from its values
    if (plane_ != 2 && model_.control.dialect != "linuxcnc")
      fail(line_, 0, cycle_code_,
           cycle_code_ + " in " + (plane_ == 1 ? "G18" : "G19") +
               ": whether the control drills along Z or along the plane's normal is a setting "
               "(Fanuc parameter 5101#0 FXY); post the holes in G17");
    const int d = plane_;                // the drilling axis
    const char depth_letter = "XYZ"[d];  // its word: Z in G17, Y in G18, X in G19
    const bool k_repeats = cycle_code_ != "G73" && cycle_code_ != "G83" && !sinumerik_cycle;
    const Word* repeat = aw.count('L') ? aw.at('L')
                         : k_repeats && model_.control.dialect == "iso" && aw.count('K')
                             ? aw.at('K')
                             : nullptr;
    long repeats = 1;
    if (repeat) {
      const double v = repeat->value;
      if (!(v >= 0 && v <= 9999 && v == std::floor(v)))
        fail(line_, repeat->column, std::string(1, repeat->letter),
             std::string(1, repeat->letter) + ": expected a whole number of holes, 0 to 9999");
      repeats = static_cast<long>(v);
    }
    if (aw.count('R') && !sinumerik_cycle) {
      cycle_r_ = aw.at('R')->value * unit_;
      cycle_r_incremental_ = !absolute_;
    }
    if (aw.count(depth_letter) && !sinumerik_cycle) {
      cycle_z_ = aw.at(depth_letter)->value * unit_;
      cycle_z_incremental_ = !absolute_;
    }
    if (!sinumerik_cycle && ((!std::isnan(cycle_r_) && cycle_r_incremental_ == absolute_) ||
                             (!std::isnan(cycle_z_) && cycle_z_incremental_ == absolute_)))
      fail(line_, 0, cycle_code_,
           cycle_code_ + "'s R and Z were given in " + (absolute_ ? "G91" : "G90") +
               " and the cycle now runs in " + (absolute_ ? "G90" : "G91") +
               ": controls differ on how they read the kept values; give R and Z again");
    // L0 (and Fanuc's K0 where K is no peck depth): the cycle's data is stored and no hole is
    // made at this block (Fanuc 0i-MF, "Canned cycle": "When K0 is specified, drilling data is
    // stored, but drilling is not performed"; HAAS L0 likewise). A position in that block is
    // refused: whether the control moves there is not said.
    const Word* none = aw.count('L') && aw.at('L')->value == 0.0                ? aw.at('L')
                       : k_repeats && aw.count('K') && aw.at('K')->value == 0.0 ? aw.at('K')
                                                                                : nullptr;
    if (none) {
      for (char l : {'X', 'Y', 'Z'})
        if (l != depth_letter && aw.count(l) &&
            std::abs(target(aw)[l - 'X'] - cur_xyz_[l - 'X']) > 1e-9)
          fail(line_, none->column, std::string(1, none->letter),
               cycle_code_ + " " + none->letter +
                   "0 with a new position: the cycle makes no hole there, and whether the "
                   "control moves to it is not said: post the position in its own block");
      ++stored_cycles_;
      return cycle_code_;
    }
    if (std::isnan(cycle_r_) || std::isnan(cycle_z_))
      fail(line_, 0, cycle_code_, "a drilling cycle needs R and Z");
    if (!absolute_) {
      for (int k = 0; k < 3; ++k)
        if (coord_[k] == kUnknown)
          fail(line_, 0, cycle_code_,
               cycle_code_ + " in G91 with " + "XYZ"[k] +
                   " not yet known: its holes are at increments from an unknown position");
    }
    const double r_plane = cycle_r_incremental_ ? cycle_initial_z_ + cycle_r_ : cycle_r_;
    const double bottom = cycle_z_incremental_ ? r_plane + cycle_z_ : cycle_z_;
    if (cycle_z_incremental_ && bottom > r_plane)
      fail(line_, 0, cycle_code_,
           cycle_code_ + " in G91: " + depth_letter + " " + formatNumber(cycle_z_ / unit_) +
               " puts the bottom above the R point");
    updateRotaryWords(aw);
    for (long k = 0; k < repeats; ++k) {
      Eigen::Vector3d xy = target(aw);
      const bool known = coord_[d] == kInOffset;
      const double z_before = known ? cur_xyz_[d] : cycle_initial_z_;
      // Below the R point: straight up to it first, where the tool is (LinuxCNC
      // interp_cycles.cc: "if we're below the R plane, rapid straight up to the R plane").
      if (known && z_before < r_plane && positionKnown()) {
        Eigen::Vector3d up = cur_xyz_;
        up[d] = r_plane;
        emit(up, true);
      }
      coordinatesGiven(aw, kInOffset);
      coord_[d] = kInOffset;
      const double clear = std::max(z_before, r_plane);
      xy[d] = clear;
      emit(xy, true);  // over the hole at the clearance height
      xy[d] = r_plane;
      emit(xy, true);
      xy[d] = bottom;
      emit(xy, false);
      xy[d] = cycle_return_initial_ ? std::max(cycle_initial_z_, r_plane) : r_plane;
      emit(xy, true);
      ++prog_.cycle_holes;
    }
    return cycle_code_;
  }

  // G10 L1 P<tool> Z<length> R<radius> (LinuxCNC G-code reference, "G10 L1 Set Tool Table"):
  // the tool table's length for tool P, which a later G43 (H P, or the tool in the spindle)
  // applies, as the program sets it; R (the radius, for cutter compensation) changes no point
  // here (tolver takes the cutter from --tools or the post's comments) and is noted. An X or Y
  // offset (a lathe tool's) is refused unless zero.
  std::string setToolByG10(const std::map<char, const Word*>& aw) {
    if (!aw.count('P')) fail(line_, 0, "G10", "G10 L1 needs P (the tool number)");
    const int P = static_cast<int>(aw.at('P')->value);
    for (const auto& [l, w] : aw)
      if (l != 'L' && l != 'P' && l != 'Z' && l != 'R' && w->value != 0.0)
        fail(line_, w->column, std::string(1, l),
             "G10 L1 " + std::string(1, l) +
                 " (a tool offset other than its length) is not "
                 "supported");
    if (aw.count('Z')) set_tool_lengths_[P] = aw.at('Z')->value * unit_;
    // LinuxCNC's G10 L1 R: the tool's radius in the table, which G41/G42 compensate by.
    if (aw.count('R')) set_tool_diameters_[P] = 2.0 * aw.at('R')->value * unit_;
    return "G10";
  }

  // Fanuc's tool offsets by program (Fanuc 0i-MF, "Changing of tool offset value (programmable
  // data input) (G10)": memory C, L10 the length's geometry, L11 its wear, L12/L13 the radius's;
  // memory A, L1 one offset for both), HAAS alike for L10 and L12/L13: L10 P R sets the length
  // a later G43 H P applies (G91: adds to it); L12/L13 (radius, used only by G41/G42) are noted;
  // L1 and L11 with R are refused (memory A's offset or a wear, by the control's memory type).
  std::string setIsoToolOffsetByG10(int L, const std::map<char, const Word*>& aw) {
    if (L == 12 || L == 13) {
      ignored_.insert("G10 L" + std::to_string(L) + " (tool radius)");
      return "G10";
    }
    if (!aw.count('P')) fail(line_, 0, "G10", "G10 L" + std::to_string(L) + " needs P");
    if (!aw.count('R'))
      fail(line_, 0, "G10", "G10 L" + std::to_string(L) + " needs R (the offset value)");
    if (L != 10)
      fail(line_, aw.at('R')->column, "R",
           "G10 L" + std::to_string(L) +
               " R: a tool offset whose meaning is the control's offset memory type (Fanuc "
               "memory A: the one offset for H and D; L11: a wear) is not carried out");
    const int P = static_cast<int>(aw.at('P')->value);
    const double r = aw.at('R')->value * unit_;
    set_tool_lengths_[P] = absolute_ ? r : toolLength(P) + r;
    return "G10";
  }

  std::string setOffsetByG10(const std::map<char, const Word*>& aw,
                             const std::vector<const Word*>& g) {
    const int L = aw.count('L') ? static_cast<int>(aw.at('L')->value) : -1;
    if (model_.control.dialect == "iso" &&
        (L == 10 || L == 11 || L == 12 || L == 13 || (L == 1 && aw.count('R') && !aw.count('Z'))))
      return setIsoToolOffsetByG10(L, aw);
    if (L == 1) return setToolByG10(aw);
    if (L != 2 && L != 20)
      fail(line_, g.front()->column, "G10",
           model_.control.dialect == "iso"
               ? "only G10 L2 and L20 (work offsets), L10 (tool length) and L12/L13 (radius) "
                 "are supported"
               : "only G10 L1 (tool length), L2 and L20 (work offsets) are supported");
    const int P = aw.count('P') ? static_cast<int>(aw.at('P')->value) : 0;
    static const char* names[] = {"G54", "G55",   "G56",   "G57",  "G58",
                                  "G59", "G59.1", "G59.2", "G59.3"};
    // L20 on an ISO control sets the additional work offsets' values (Fanuc 0i-MF, "G10 L20 Pn":
    // G54.1 Pn, n 1 to 300; HAAS: G154 Pn, n 1 to 99), as L2 sets G54..G59's; on LinuxCNC, L20
    // Pn makes the current point have the words' coordinates in G54..G59.3.
    const bool additional = L == 20 && model_.control.dialect == "iso";
    // P0 on an ISO control is the external offset that shifts every work offset (Fanuc; HAAS's
    // G52), not LinuxCNC's "the one in force": refused, never applied to the wrong one.
    if (P == 0 && aw.count('P') && model_.control.dialect == "iso")
      fail(line_, aw.at('P')->column, "P",
           "G10 L" + std::to_string(L) +
               " P0 sets the external work offset that shifts every work offset (Fanuc; HAAS: "
               "G52): not carried out (on LinuxCNC P0 is the offset in force: a LinuxCNC "
               "machine file declares dialect=\"linuxcnc\" in its <control>)");
    if (additional ? (P < 0 || P > 300) : (P < 0 || P > 9))
      fail(line_, aw.at('P')->column, "P",
           additional ? "expected P0 to P300" : "expected P0 to P9");
    const std::string name = P == 0       ? work_
                             : additional ? "G54.1P" + std::to_string(P)
                                          : names[P - 1];
    // LinuxCNC's R: the coordinate system turned about Z by R degrees (G-code reference, "G10 L2",
    // "R: rotation about the Z axis"; emccanon.cc rotate_and_offset_pos: machine = Rz(R)
    // (program + G92) + G5x), with L2; with L20 refused (the point that takes the words' values
    // in a turned system), as are offsets of rotary axes: refused unless zero, never dropped.
    const bool linuxcnc = model_.control.dialect == "linuxcnc";
    if (linuxcnc && L == 2 && aw.count('R')) rotation_rad_[name] = degToRad(aw.at('R')->value);
    if (linuxcnc && L == 20 && rotationOf(name) != 0.0)
      fail(line_, g.front()->column, "G10",
           "G10 L20 on a turned coordinate system (G10 L2 R) is not carried out");
    for (const auto& [l, w] : aw) {
      const auto ax = letter_axis_.find(l);
      const bool rotary = ax != letter_axis_.end() && model_.axes[ax->second].isRotary();
      if (l == 'R' && linuxcnc && L == 2) continue;
      if ((l == 'R' || rotary) && w->value != 0.0)
        fail(line_, w->column, std::string(1, l),
             l == 'R' ? "G10 L" + std::to_string(L) +
                            " R (the work coordinate system turned about Z) is not supported"
                      : "G10 L" + std::to_string(L) + " offset of the rotary axis " +
                            std::string(1, l) + " is not supported");
    }
    Eigen::Vector3d off = set_offsets_.count(name) ? set_offsets_[name] : workOffset(name);
    const Eigen::Vector3d here = machineOfJoints(q_);
    const char xyz[3] = {'X', 'Y', 'Z'};
    // L20: the current point takes the words' values (in the program's frame: a G92 offset
    // stays on top of the work offset).
    Eigen::Vector3d p = cur_xyz_;
    for (int k = 0; k < 3; ++k)
      if (aw.count(xyz[k])) p[k] = aw.at(xyz[k])->value * unit_;
    const Eigen::Vector3d p_s = frame_ * p;
    unsigned char own = ownAxes(name);
    for (int k = 0; k < 3; ++k) {
      if (!aw.count(xyz[k])) continue;
      off[k] = L == 2 || additional ? aw.at(xyz[k])->value * unit_ : here[k] - p_s[k];
      // L2 (and ISO L20) give the offset in machine coordinates: fixed. LinuxCNC's L20 takes it
      // from where the tool is: fixed only where that position is (a G53 move, or an axis of an
      // offset the program set).
      const unsigned char bit = static_cast<unsigned char>(1u << k);
      const bool here_fixed =
          coord_[k] == kFixed || (coord_[k] == kInOffset && (ownAxes(work_) & bit));
      if (L == 2 || additional || here_fixed)
        own |= bit;
      else
        own &= static_cast<unsigned char>(~bit);
    }
    set_offsets_[name] = off;
    set_axes_[name] = own;
    // The axes it left keep the set-up's (or the part zero's): its note stays until all three
    // are the program's.
    if (own == 7) missing_offsets_.erase(name);
    if (name == work_ && linuxcnc) {
      last_offset_ = off;
      applyG92Frame();
    }
    cur_xyz_ = currentProgramXyz();
    return "G10";
  }

  // LinuxCNC's turned coordinate systems (G10 L2 R) and G92: the settable frame Rz(R) (p + G92)
  // of the system in force.
  double rotationOf(const std::string& name) const {
    const auto it = rotation_rad_.find(name);
    return it == rotation_rad_.end() ? 0.0 : it->second;
  }
  void applyG92Frame() {
    Eigen::Isometry3d f = Eigen::Isometry3d::Identity();
    f.linear() = Eigen::AngleAxisd(rotationOf(work_), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    if (g92_on_) f.translation() = f.linear() * g92_offset_;
    if (!f.isApprox(frame_, 0.0)) setFrame(f);
  }

  const MachineModel& model_;
  GcodeReadOptions opt_;
  ForwardKinematics nominal_;
  InverseKinematics ik_;
  const ProgramBlocks* blocks_;  // or nullptr: the whole program at once
  size_t points_read_ = 0;       // points made, those passed on included
  ClProgram prog_;
  static constexpr int kMaxNesting = 64;      // signs, brackets and '#' within one expression
  static constexpr int kMaxParameter = 5601;  // LinuxCNC's numbered parameters: #1 to #5601
  int nesting_ = 0;
  int brackets_ = 0;  // '[' open in the expression being read (binary operators live inside)
  LineSource* source_ = nullptr;
  int line_ = 0;
  // The program's end (M2, M30 or a second '%'): where, by what, and the lines after it that
  // hold more than a comment.
  void endAt(const std::string& cause) {
    ended_ = true;
    end_line_ = line_;
    end_cause_ = cause;
  }
  int end_line_ = 0, after_end_ = 0, first_after_end_ = 0;
  int nested_comments_ = 0, first_nested_comment_ = 0;
  std::string end_cause_;
  bool ended_ = false, seen_block_ = false, any_ = false;
  int percent_ = 0;
  std::array<char, 3> coord_ = {2, 2, 2};  // Coordinate per X Y Z
  int unknown_moves_ = 0, first_unknown_line_ = 0, last_unknown_line_ = 0;
  // Sinumerik state.
  std::map<std::string, double> sin_vars_;
  std::set<std::string> sin_texts_;      // declared STRING and CHAR variables
  std::map<char, std::string> sin_dim_;  // the block's X=IC(...) etc. (sinDimension)
  std::array<bool, 3> frame_moved_{};    // X Y Z not given absolutely since the frame changed
  int frame_line_ = 0;                   // where the frame last changed
  int sin_turns_ = -1;  // the Sinumerik block's TURN= (sinumerikBlock), -1 when it gives none
  bool sin_mcall_ = false, sin_cycle_here_ = false;
  // Frames (mm): the swivel frame (CYCLE800), the programmable frame (TRANS, ROT, ...) and
  // frame_ = swivel_ * pframe_, which maps program coordinates into the settable frame (G54...).
  Eigen::Isometry3d swivel_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d pframe_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d frame_ = Eigen::Isometry3d::Identity();
  bool swivel_on_ = false;
  bool orimks_ = false;        // ORIMKS: orientation vectors in machine coordinates (refused)
  int frame_index_ = 0;        // into prog_.frames
  bool frame_checked_ = true;  // the tool axis checked against a rotated frame's z
  std::string tool_name_;
  int max_decimals_ = 3;         // assumed until the program prints more
  bool executed_block_ = false;  // a block of words was executed (O names come before)
  static constexpr size_t kMaxLeaderLines = 2000;  // lines held while looking for a first '%'
  double unit_ = 1.0;
  bool units_seen_ = false;
  int plane_ = 2;  // normal index: 2 = G17 (XY), 1 = G18 (ZX), 0 = G19 (YZ)
  bool absolute_ = true, arc_absolute_ = false;
  std::string motion_ = "G0";
  std::string feed_mode_ = "G94";
  double feed_word_ = 0.0;  // the last F word, in the unit of the feed mode
  int huge_feed_line_ = 0;  // the first F above 1e7 (read as the control's fastest)
  bool polar_plane_noted_ = false;
  std::map<std::string, double> rotation_rad_;  // LinuxCNC's G10 L2 R, per work offset (rad)
  std::string work_ = "G54";
  bool tlc_ = false, tcp_without_tlc_ = false;
  int h_ = 0, tool_ = 0;
  struct StoredHome {
    JointVector q;
    std::array<double, kMaxAxes> rot_word{};
  };
  std::optional<StoredHome> home28_, home30_;           // LinuxCNC's G28.1, G30.1
  std::optional<ModalState> saved_modal_;               // M70's
  std::vector<std::optional<ModalState>> autorestore_;  // M73's, per o-word call
  std::string active_tool_, selected_tool_;             // "T1" or a Sinumerik tool name
  bool seen_m6_ = false;
  std::map<std::string, std::pair<double, double>>
      tool_table_;  // "T1" -> diameter, corner radius (program unit: comments come before G20/G21)
  std::set<std::string> diameter_only_;  // of tool_table_: tools whose shape the list does not give
  std::map<std::string, int> tool_line_;  // of tool_table_: the line that first listed each tool
  std::set<std::string> tcp_active_;
  std::set<std::string> ignored_;
  std::map<std::string, int> missing_offsets_;      // work offset -> first line that used it
  int bare_g28_line_ = 0;                           // the first G28 without axis words (ISO)
  int g75_line_ = 0;                                // the first Sinumerik G75 (fixed point)
  int block_deletes_ = 0, first_block_delete_ = 0;  // blocks marked '/', read as run
  bool bare_point_ = false;                         // a number written "10." (noteDecimalPoint)
  int first_integer_line_ = 0;                      // a non-zero number without a point
  std::string first_integer_;
  int wear_comp_line_ = 0;  // the first G41/G42 read as wear compensation
  // Cutter radius compensation (compOn): +1 left (G41), -1 right (G42), 0 off; the radius (mm);
  // the first move after it turned on still to come; the G41/G42 line; the tool centre's
  // position, the last point emitted and the programmed point (program coordinates); the held
  // moves and the start of the first (LinuxCNC's endpoint); a G40 just made (an arc refused).
  int comp_side_ = 0;
  double comp_radius_ = 0;
  bool comp_first_ = true;
  int comp_line_ = 0, radius_comp_blocks_ = 0;
  Eigen::Vector3d comp_cur_ = Eigen::Vector3d::Zero(), comp_emitted_ = Eigen::Vector3d::Zero(),
                  comp_programmed_ = Eigen::Vector3d::Zero();
  std::vector<CompMove> comp_queue_;
  Eigen::Vector2d comp_endpoint_ = Eigen::Vector2d::Zero();
  bool comp_endpoint_valid_ = false, comp_arc_not_allowed_ = false;
  std::optional<double> block_d_;  // the block's D word (LinuxCNC, ISO)
  struct CompLate {
    int first, count, line;  // points (path indices) of a held move of an earlier line
  };
  std::vector<CompLate> comp_late_;
  std::map<int, double> set_tool_diameters_;  // LinuxCNC's G10 L1 P R (mm), per tool
  int loaded_tool_ = 0;                       // the tool in the spindle (M6, M61 Q), 0: none
  int block_d_column_ = 0;
  int g92_line_ = 0;                        // the first G92..G92.3
  int stored_cycles_ = 0;                   // cycle blocks with L0/K0 (no hole)
  std::map<int, double> set_tool_lengths_;  // G10 L1 P Z: tool lengths the program sets (mm)
  Eigen::Vector3d g92_offset_ = Eigen::Vector3d::Zero();  // G92's offset (mm, settable frame)
  bool g92_on_ = false;                                   // in force (not G92.1/G92.2)
  std::set<std::string> commanded_offsets_;               // work offsets a block selects (G54...)
  std::map<std::string, int> unknown_;  // G and M codes tolver does not know -> first line
  std::map<std::string, Eigen::Vector3d> set_offsets_;
  std::map<std::string, unsigned char> set_axes_;  // of set_offsets_: the axes G10 set (bits XYZ)
  std::map<std::string, double> named_;
  std::map<int, double> numbered_;
  std::vector<SourceLine> held_flow_;  // a LinuxCNC O-word construct being read up to its end
  OWord held_open_;                    // its first line's O-word
  std::map<std::string, Sub> subs_;    // o<name> sub definitions, by label
  int call_depth_ = 0;
  int flow_depth_ = 0;            // runLines nesting
  long flow_lines_ = 0;           // lines carried out within constructs
  bool analog_io_block_ = false;  // the block has LinuxCNC's M66/M67/M68 (its E: a port)
  bool subs_defined_ = false;     // the file defines a sub at its top level
  bool tail_mode_ = false, replaying_ = false;
  std::vector<std::string> tail_;  // the file from a call of a sub defined further on
  std::set<int> sub_lines_;        // lines of ISO subprograms after the end (not "unread")
  std::map<char, int> letter_axis_;
  std::array<double, kMaxAxes> rot_word_{};
  // Drilling cycle state.
  bool cycle_ = false, cycle_return_initial_ = true;
  std::string cycle_code_;
  double cycle_r_ = std::numeric_limits<double>::quiet_NaN();
  double cycle_z_ = std::numeric_limits<double>::quiet_NaN();
  bool cycle_r_incremental_ = false, cycle_z_incremental_ = false;  // given in G91
  double cycle_initial_z_ = 0.0;
  // Machine coordinates.
  Eigen::Vector3d g0_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d Gm_ = Eigen::Matrix3d::Identity(), Gm_inv_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d spindle_m_ = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d default_offset_ = Eigen::Vector3d::Zero();
  std::array<int, 3> prismatic_{};
  // Current state.
  JointVector q_;
  Eigen::Vector3d cur_xyz_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d last_tip_w_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d last_offset_ = Eigen::Vector3d::Zero();
};

}  // namespace

ClProgram readGcode(LineSource& source, const std::string& file_name, const MachineModel& model,
                    const GcodeReadOptions& options) {
  return Reader(source, file_name, model, options, nullptr).run();
}

ClProgram readGcode(LineSource& source, const std::string& file_name, const MachineModel& model,
                    const GcodeReadOptions& options, const ProgramBlocks& blocks) {
  return Reader(source, file_name, model, options, &blocks).run();
}

ClProgram parseGcode(const std::string& text, const std::string& file_name,
                     const MachineModel& model, const GcodeReadOptions& options) {
  LineSource source(text);
  return readGcode(source, file_name, model, options);
}

ClProgram readGcodeFile(const std::string& path, const MachineModel& model,
                        const GcodeReadOptions& options) {
  LineSource source = LineSource::file(path);
  return readGcode(source, path, model, options);
}

size_t commentEnd(std::string_view s, size_t open) {
  const size_t first = s.find(')', open);
  if (first == std::string_view::npos) return first;
  const size_t inner = s.find('(', open + 1);
  if (inner == std::string_view::npos || inner > first) return first;
  int depth = 0;
  for (size_t k = open; k < s.size(); ++k) {
    if (s[k] == '(') ++depth;
    if (s[k] == ')' && --depth == 0) return k;
  }
  return first;  // never balanced: the first ')' ends it
}

void refuseUnreadLanguage(const std::string& text, const std::string& file_name) {
  int line = 0;
  for (const std::string& raw : splitLines(text)) {
    ++line;
    std::string_view l = trim(raw);
    if (l.rfind("\xEF\xBB\xBF", 0) == 0) l = trim(l.substr(3));
    if (l.empty()) continue;
    const int column = static_cast<int>(l.data() - raw.data()) + 1;
    const std::string u = toUpper(l);
    // Klartext: an optional block number, then BEGIN PGM (TNC 640 User's Manual, Klartext
    // Programming, "Program structure": "0 BEGIN PGM NEW MM" ... "END PGM NEW MM").
    size_t k = 0;
    while (k < u.size() && std::isdigit(static_cast<unsigned char>(u[k]))) ++k;
    while (k < u.size() && u[k] == ' ') ++k;
    if (u.compare(k, 10, "BEGIN PGM ") == 0)
      throw InputError(file_name, line, column + static_cast<int>(k), "BEGIN PGM",
                       "a HEIDENHAIN conversational (Klartext) program: tolver reads CL data "
                       "(APT/CLSF) and ISO G-code (Fanuc, HAAS, LinuxCNC, Sinumerik 840D); post "
                       "the program for one of those, or give the CAM's CL file");
    // HEIDENHAIN DIN/ISO: "%NAME G71 *" (TNC User's Manual, DIN/ISO Programming: the program
    // begins with %, its name and G70/G71, every block ends with '*').
    if (u[0] == '%' && u.size() > 2 && u.back() == '*' &&
        (u.find(" G70") != std::string::npos || u.find(" G71") != std::string::npos))
      throw InputError(file_name, line, column, "%",
                       "a HEIDENHAIN DIN/ISO program (blocks ending in '*'): not a dialect "
                       "tolver reads; post the program for Fanuc, HAAS, LinuxCNC or Sinumerik "
                       "840D G-code, or give the CAM's CL file");
    // OpenSBP (ShopBot): comma-separated two-letter commands, "'" comments (OpenSBP Reference
    // Manual: MS move speed, J2/M2 jog and move in X Y, J3/M3 in X Y Z, JZ/MZ, SA/SR absolute
    // and relative, C# cuts).
    if (u[0] == '\'') continue;  // an OpenSBP comment line: the statements after it decide
    static const char* const kSbp[] = {"SA", "SR", "MS", "JS", "J2", "J3", "J5", "JZ",
                                       "JX", "JY", "M2", "M3", "M5", "MZ", "MX", "MY",
                                       "CG", "VD", "VC", "VU", "TR", "SO"};
    const std::string head = u.substr(0, u.find_first_of(", "));
    bool sbp = false;
    for (const char* c : kSbp)
      sbp = sbp || (head == c && (u.size() == head.size() || u[head.size()] == ','));
    if (sbp)
      throw InputError(file_name, line, column, head,
                       "an OpenSBP (ShopBot) program: not a language tolver reads (CL data "
                       "APT/CLSF, ISO G-code); post the program for G-code, or give the CAM's "
                       "CL file");
    return;  // the first statement is neither
  }
}

bool looksLikeGcode(const std::string& text) {
  int gcode = 0, apt = 0, seen = 0;
  for (const std::string& raw : splitLines(text)) {
    std::string_view l = trim(raw);
    if (l.rfind("\xEF\xBB\xBF", 0) == 0) l = trim(l.substr(3));
    if (l.empty()) continue;
    if (l[0] == '(' || l[0] == ';') continue;
    if (l.rfind("$$", 0) == 0) {
      ++apt;
      continue;
    }
    const std::string u = toUpper(l.substr(0, std::min<size_t>(l.size(), 12)));
    if (u[0] == '%' || u[0] == 'N' || u[0] == 'G' || u[0] == 'M' || u[0] == 'O' || u[0] == 'T' ||
        u[0] == 'X' || u[0] == 'Y' || u[0] == 'Z' || u[0] == '#') {
      // An APT major ("GOTO/", "MULTAX", "TOOL PATH/") has a slash or letters after the first.
      const size_t slash = l.find('/');
      const bool apt_like = slash != std::string_view::npos && slash < 16 &&
                            std::isalpha(static_cast<unsigned char>(u[1]));
      if (apt_like || u.rfind("MULTAX", 0) == 0 || u.rfind("PARTNO", 0) == 0 ||
          u.rfind("TOOL PATH", 0) == 0 || u.rfind("MSYS", 0) == 0 || u.rfind("FINI", 0) == 0)
        ++apt;
      else
        ++gcode;
    } else {
      ++apt;
    }
    if (++seen >= 20) break;
  }
  return gcode > apt;
}

}  // namespace tolver
