#include "io/program/compensated_program.h"

#include <Eigen/LU>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <string_view>

#include "core/kinematics/forward_kinematics.h"
#include "core/numerics/units.h"
#include "io/common/text_util.h"
#include "io/program/gcode_reader.h"

namespace tolver {
namespace {

// A number in the text: [+-]?(d+[.d*]|.d+)([eE][+-]?d+)?
struct NumToken {
  size_t start = 0, len = 0;
  int decimals = 0;
  double value = 0;
};

bool numberAt(const std::string& s, size_t i, NumToken* t) {
  size_t j = i;
  if (j < s.size() && (s[j] == '+' || s[j] == '-')) ++j;
  const size_t digits_from = j;
  while (j < s.size() && std::isdigit(static_cast<unsigned char>(s[j]))) ++j;
  int decimals = 0;
  bool any = j > digits_from;
  if (j < s.size() && s[j] == '.') {
    ++j;
    while (j < s.size() && std::isdigit(static_cast<unsigned char>(s[j]))) ++j, ++decimals;
    any = any || decimals > 0;
  }
  if (!any) return false;
  if (j < s.size() && (s[j] == 'e' || s[j] == 'E')) {
    size_t k = j + 1;
    if (k < s.size() && (s[k] == '+' || s[k] == '-')) ++k;
    if (k < s.size() && std::isdigit(static_cast<unsigned char>(s[k]))) {
      while (k < s.size() && std::isdigit(static_cast<unsigned char>(s[k]))) ++k;
      j = k;
    }
  }
  t->start = i;
  t->len = j - i;
  t->decimals = decimals;
  // strtod's value (parseNumber: the same bits, without a copy).
  const std::optional<double> v = parseNumber(std::string_view(s).substr(i, j - i));
  t->value = v ? *v : std::strtod(s.substr(i, j - i).c_str(), nullptr);
  return true;
}

// The numbers of a CL statement's line from `from` on (a "$$" comment ends the line).
std::vector<NumToken> numbersIn(const std::string& s, size_t from) {
  std::vector<NumToken> out;
  const size_t end = std::min(s.size(), s.find("$$", from));
  for (size_t i = from; i < end;) {
    NumToken t;
    const bool boundary = i == 0 || !std::isalnum(static_cast<unsigned char>(s[i - 1]));
    if (boundary && numberAt(s, i, &t) && t.start + t.len <= end) {
      out.push_back(t);
      i = t.start + t.len;
    } else {
      ++i;
    }
  }
  return out;
}

std::string fixed(double v, int decimals) {
  LineBuilder b;  // printf's "%.<decimals>f"
  b.fixed(v, decimals);
  std::string s(b.view());
  // No "-0.000".
  if (s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

std::string withoutParentheses(std::string s) {
  for (char& c : s) c = c == '(' ? '[' : c == ')' ? ']' : c;
  return s;
}

std::string lineList(const std::vector<int>& lines) {
  std::string s;
  for (size_t k = 0; k < lines.size() && k < 8; ++k)
    s += (k ? ", " : "") + std::to_string(lines[k]);
  if (lines.size() > 8) s += ", ...";
  return s;
}

}  // namespace

// Long by design: one pass over the source's statements, keeping every line it does not change
// byte for byte.
CompensatedAptWriter::CompensatedAptWriter(bool multiax) : multiax_(multiax) {}

void CompensatedAptWriter::start(const std::vector<std::string>& header, std::string& out,
                                 std::vector<int>* source_line) {
  for (const std::string& h : header) {
    out += "$$ " + h + "\n";
    if (source_line) source_line->push_back(0);
  }
}

void CompensatedAptWriter::statements(const ClProgram& program,
                                      const std::vector<ClPoint>& corrected, std::string& out,
                                      std::vector<char>& written, std::vector<int>* source_line) {
  written.assign(program.path.size(), 1);
  const bool inch = program.units == "INCH";
  const int pos_min = inch ? 8 : 6, axis_min = 9;
  auto from = [&](int l) {
    if (source_line) source_line->push_back(l);
  };
  // The file's coordinates of a corrected point.
  auto inFile = [&](int k, Eigen::Vector3d* p, Eigen::Vector3d* u) {
    const ClFrame& f = program.frames[program.point_frame[k]];
    *p = f.T.inverse(Eigen::Isometry) * (corrected[k].p_w / f.scale);
    *u = f.T.linear().transpose() * corrected[k].u_w.normalized();
  };
  for (const AptStatement& st : program.statements) {
    if (st.cycle) {
      // A hole of a drilling cycle: the control makes its motions from the GOTO and the cycle's
      // distances, so its compensated points cannot be written as GOTOs (read again, each would
      // be a hole of its own). Left as programmed, as the G-code writer leaves canned cycles.
      cycle_lines_.push_back(st.first_line);
      for (int k = st.first_point; k < st.first_point + st.point_count; ++k) written[k] = 0;
      for (int l = st.first_line; l <= st.last_line; ++l) {
        out += program.lines[l - 1];
        out += '\n';
        from(l);
      }
      continue;
    }
    const bool single = st.point_count == 1 && (st.major == "GOTO" || st.major == "FROM");
    if (single) {
      // The numbers of the statement, across its continuation lines, after the '/'.
      std::vector<std::string> lines;
      for (int l = st.first_line; l <= st.last_line; ++l) lines.emplace_back(program.lines[l - 1]);
      std::vector<std::pair<size_t, NumToken>> tokens;
      for (size_t l = 0; l < lines.size(); ++l) {
        size_t from_at = 0;
        if (l == 0) {
          const size_t slash = lines[0].find('/');
          from_at = slash == std::string::npos ? lines[0].size() : slash + 1;
        }
        for (const NumToken& t : numbersIn(lines[l], from_at)) tokens.push_back({l, t});
      }
      Eigen::Vector3d p, u;
      inFile(st.first_point, &p, &u);
      if (tokens.size() >= 3) {
        const double v[6] = {p.x(), p.y(), p.z(), u.x(), u.y(), u.z()};
        const size_t n = std::min<size_t>(tokens.size(), 6);
        // Replace from the last token backwards, so that earlier offsets stay valid.
        std::string append;
        if (multiax_ && tokens.size() < 6) {
          const int d = std::max(tokens[2].second.decimals, axis_min);
          append = "," + fixed(u.x(), d) + "," + fixed(u.y(), d) + "," + fixed(u.z(), d);
        }
        for (size_t k = n; k-- > 0;) {
          const auto& [l, t] = tokens[k];
          const int d = std::max(t.decimals, k < 3 ? pos_min : axis_min);
          std::string text = fixed(v[k], d);
          if (k == 2 && !append.empty()) text += append;
          lines[l].replace(t.start, t.len, text);
        }
        for (size_t l = 0; l < lines.size(); ++l) {
          out += lines[l];
          out += '\n';
          from(st.first_line + static_cast<int>(l));
        }
        continue;
      }
    }
    if (st.point_count >= 1) {
      // Points the reader expanded (an arc, a curve): GOTOs of their compensated points.
      expanded_lines_.push_back(st.first_line);
      out += "$$ tolver: " + (st.major.empty() ? std::string("statement") : st.major) +
             " of line " + std::to_string(st.first_line) +
             " as the GOTOs of its compensated points\n";
      from(st.first_line);
      for (int k = st.first_point; k < st.first_point + st.point_count; ++k) {
        Eigen::Vector3d p, u;
        inFile(k, &p, &u);
        out += "GOTO/" + fixed(p.x(), pos_min) + "," + fixed(p.y(), pos_min) + "," +
               fixed(p.z(), pos_min);
        if (multiax_)
          out += "," + fixed(u.x(), axis_min) + "," + fixed(u.y(), axis_min) + "," +
                 fixed(u.z(), axis_min);
        out += "\n";
        from(st.first_line);
      }
      continue;
    }
    if (st.major == "CIRCLE" || st.major == "MOVARC") {
      out += "$$ tolver: " + st.major + " of line " + std::to_string(st.first_line) +
             " replaced by the compensated points of its arc that follow\n";
      from(st.first_line);
      continue;
    }
    for (int l = st.first_line; l <= st.last_line; ++l) {
      out += program.lines[l - 1];
      out += '\n';
      from(l);
    }
  }
}

std::vector<std::string> CompensatedAptWriter::notes() const {
  std::vector<std::string> notes;
  if (!cycle_lines_.empty())
    notes.push_back(std::to_string(cycle_lines_.size()) +
                    " drilling-cycle holes left as programmed, uncompensated (lines " +
                    lineList(cycle_lines_) + ")");
  if (!expanded_lines_.empty())
    notes.push_back(std::to_string(expanded_lines_.size()) +
                    " statements whose points the reader expanded " + "(arcs, curves; lines " +
                    lineList(expanded_lines_) +
                    ") were written as GOTOs of their compensated points");
  return notes;
}

CompensatedProgramText formatCompensatedApt(const ClProgram& program,
                                            const std::vector<ClPoint>& corrected,
                                            const std::vector<std::string>& header) {
  CompensatedProgramText out;
  CompensatedAptWriter writer(program.multiax);
  writer.start(header, out.text, &out.source_line);
  writer.statements(program, corrected, out.text, out.written, &out.source_line);
  out.notes = writer.notes();
  return out;
}

namespace {

// A word of a G-code block: its letter and the span of its value.
struct GWord {
  char letter = 0;
  size_t start = 0, end = 0;  // value span
  bool numeric = false;
  int decimals = 0;
  double value = 0;
};

std::vector<GWord> gcodeWords(const std::string& s) {
  std::vector<GWord> out;
  size_t i = 0;
  while (i < s.size()) {
    const char c = s[i];
    if (c == '(') {
      const size_t close = commentEnd(s, i);  // as the reader ends it
      i = close == std::string::npos ? s.size() : close + 1;
      continue;
    }
    if (c == ';') break;
    // (LinuxCNC's polar words @ and ^ are words too: a block with them names no X Y)
    if (!std::isalpha(static_cast<unsigned char>(c)) && c != '@' && c != '^') {
      ++i;
      continue;
    }
    GWord w;
    w.letter = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    size_t j = i + 1;
    while (j < s.size() && s[j] == ' ') ++j;
    NumToken t;
    if (j < s.size() && numberAt(s, j, &t)) {
      w.numeric = true;
      w.start = t.start;
      w.end = t.start + t.len;
      w.decimals = t.decimals;
      w.value = t.value;
      i = w.end;
    } else {
      // An expression ([...]) or a parameter (#...): not a plain number.
      w.start = j;
      size_t k = j;
      if (k < s.size() && s[k] == '[') {
        int depth = 0;
        for (; k < s.size(); ++k) {
          depth += s[k] == '[' ? 1 : s[k] == ']' ? -1 : 0;
          if (depth == 0) break;
        }
        ++k;
      } else if (k < s.size() && s[k] == '#') {
        ++k;
        if (k < s.size() && s[k] == '<') {
          const size_t close = s.find('>', k);
          k = close == std::string::npos ? s.size() : close + 1;
        } else {
          while (k < s.size() && (std::isdigit(static_cast<unsigned char>(s[k])) || s[k] == '.'))
            ++k;
        }
      }
      w.end = std::min(k, s.size());
      i = std::max(w.end, i + 1);
    }
    out.push_back(w);
  }
  return out;
}

}  // namespace

namespace {

// The compensated G-code, block by block: one pass over the source carrying the control's modal
// state (motion mode, G90/G91, the words in force and their decimals), each block scanned,
// judged (written or left as programmed, and why), given its target words, edited in place.
class GcodeEditor {
 public:
  GcodeEditor(const MachineModel& model, const std::string& units, const GcodeArcStarts& arcs)
      : model_(model),
        arcs_(arcs),
        unit_(units == "INCH" ? 25.4 : 1.0),
        lin_min_(unit_ == 25.4 ? 5 : 4),
        n_(static_cast<int>(model.axes.size())),
        old_word_(n_, 0.0),
        new_word_(n_, 0.0),
        known_(n_, 0),
        decimals_(n_, -1) {
    for (int a = 0; a < n_; ++a)
      if (model.axes[a].name.size() == 1)
        axis_of_[static_cast<char>(
            std::toupper(static_cast<unsigned char>(model.axes[a].name[0])))] = a;
    gm_inv_ = tcpWordMatrix().inverse();
  }

  // The header, after a leading '%' line (the first block's first line).
  void start(const ClProgram& first, const std::vector<std::string>& header, std::string& out,
             std::vector<int>* source_line) {
    if (first.lines.first() == 0 && first.lines.size() > 0 && !first.lines[0].empty() &&
        first.lines[0][0] == '%') {
      out += first.lines[0];
      out += '\n';
      if (source_line) source_line->push_back(1);
      skip_first_ = true;
    }
    // A Sinumerik control reads "( )" as a call: its comments start with ';'.
    const bool semicolon = model_.control.dialect == "sinumerik";
    for (const std::string& h : header) {
      out += semicolon ? "; " + h + "\n" : "(" + withoutParentheses(h) + ")\n";
      if (source_line) source_line->push_back(0);
    }
  }

  // A block's lines, edited, into out; written: one flag per block point.
  void lines(const ClProgram& block, const std::vector<JointVector>& q0,
             const std::vector<JointVector>& q, const std::vector<Eigen::Vector3d>& corrected_p_w,
             std::string& out, std::vector<char>& written, std::vector<int>* source_line) {
    program_ = &block;
    q0_ = &q0;
    q_ = &q;
    corrected_p_w_ = &corrected_p_w;
    written_ = &written;
    written.assign(block.path.size(), 0);
    for (size_t li = block.lines.first(); li < block.lines.size(); ++li) {
      if (li == 0 && skip_first_) continue;
      out += this->block(li);
      out += '\n';
      if (source_line) source_line->push_back(static_cast<int>(li) + 1);
    }
  }

  // What was left as programmed, by reason.
  std::vector<std::string> notes() const {
    std::vector<std::string> out;
    auto note = [&](const std::vector<int>& lines, const char* what) {
      if (!lines.empty())
        out.push_back(std::to_string(lines.size()) + " " + what +
                      " left as programmed, uncompensated (lines " + lineList(lines) + ")");
    };
    note(arcs_list_, "arc blocks (G2/G3)");
    note(arc_starts_,
         "blocks that start an arc (written back to their programmed position: the arc's start "
         "must stay on its circle)");
    note(relative_starts_,
         "blocks before an incremental (G91) or drilling-cycle block (written back to their "
         "programmed position: that block, left as programmed, moves from it)");
    note(cycles_, "drilling-cycle blocks");
    note(incremental_, "incremental (G91) blocks");
    note(machine_moves_, "moves in machine coordinates (G53, G28, ...)");
    note(expressions_,
         "blocks with words given by expressions or parameters, or without the word in force");
    note(rapid_kept_,
         "rapid blocks that would need an axis they do not name (a rapid keeps its words)");
    return out;
  }

 private:
  static constexpr int kRotMin = 4;  // decimals written at least, rotary words

  // A block's words: the axis words by axis, and whether it moves in machine coordinates (or
  // sets an offset) or gives an axis word by an expression.
  struct Block {
    std::string line;
    std::vector<GWord> words;
    std::map<int, const GWord*> axis_words;
    bool special = false, expression = false;
    bool polar = false;  // LinuxCNC's @ ^: its X Y are not words of the block
    int point = -1;      // its program point when it has exactly one, else -1
    int line_no = 0;
    bool write = false, restore = false;
    std::vector<int>* restored_in = nullptr;  // the list a restored block is named in
    std::vector<double> target;
  };

  // In TCP mode X Y Z are program coordinates of the tip: p_w = g0 + Gm (xyz + offset), Gm the
  // prismatic joints' effect (times nc_sign) at rotaries zero.
  Eigen::Matrix3d tcpWordMatrix() const {
    Eigen::Matrix3d gm = Eigen::Matrix3d::Identity();
    const ForwardKinematics nominal(model_, Eigen::VectorXd::Zero(model_.parameterCount()));
    const char L[3] = {'X', 'Y', 'Z'};
    const JointVector z = JointVector::Zero(n_);
    Eigen::Vector3d p0, u;
    nominal.tipAndAxis(z, &p0, &u);
    for (int k = 0; k < 3; ++k) {
      auto it = axis_of_.find(L[k]);
      if (it == axis_of_.end()) continue;
      JointVector qk = z;
      qk[it->second] += model_.axes[it->second].nc_sign;
      Eigen::Vector3d pk;
      nominal.tipAndAxis(qk, &pk, &u);
      gm.col(k) = pk - p0;
    }
    return gm;
  }

  std::string block(size_t li) {
    Block b;
    b.line = std::string(program_->lines[li]);
    b.line_no = static_cast<int>(li) + 1;
    scan(b, li);
    judge(b, li);
    if (b.write) targets(b);
    if (b.write && motion_ == 0 && !b.restore) keepRapidWords(b);
    if (b.write) {
      edit(b);
    } else {
      for (const auto& [a, w] : b.axis_words)
        if (w->numeric) new_word_[a] = w->value;  // the block as written
    }
    updateWordsInForce(b);
    return b.line;
  }

  // The block's words and the modal state they set.
  void scan(Block& b, size_t li) {
    b.words = gcodeWords(b.line);
    for (const GWord& w : b.words) {
      if (w.letter == 'G' && w.numeric) {
        const double g = w.value;
        if (g == 0 || g == 1 || g == 2 || g == 3)
          motion_ = static_cast<int>(g);
        else if (g == 80)
          motion_ = 80;
        else if (g >= 73 && g <= 89 && g != 80)
          motion_ = static_cast<int>(g);
        else if (g == 90)
          absolute_ = true;
        else if (g == 91)
          absolute_ = false;
        else if (g == 53 || g == 28 || g == 30 || g == 10 || g == 92)
          b.special = true;
        else if ((g >= 54 && g <= 59.35) || g == 154 || (g >= 110 && g <= 129))
          // Another work offset: the words in force were the last one's coordinates.
          std::fill(known_.begin(), known_.end(), 0);
      }
      auto it = axis_of_.find(w.letter);
      if (it != axis_of_.end()) {
        b.axis_words[it->second] = &w;
        if (!w.numeric) b.expression = true;
      }
      // A polar block: left as programmed (writing its X Y beside @ ^ is refused by LinuxCNC,
      // and its words say nothing of X Y in force).
      if (w.letter == '@' || w.letter == '^') b.polar = b.expression = true;
    }
    const size_t k = li - program_->lines.first();  // the block's statements: one per line
    const AptStatement* st = k < program_->statements.size() ? &program_->statements[k] : nullptr;
    const int points = st ? st->point_count : 0;
    if (points == 1) b.point = st->first_point;
    b.write =
        points == 1 && (motion_ == 0 || motion_ == 1) && absolute_ && !b.special && !b.expression;
    if (points > 1) b.point = -2;  // several points: listed below as left as programmed
  }

  // Written or left as programmed, and why. The block before an arc is written back to the
  // program's own position, all axes (the values in force may carry earlier corrections): the
  // arc starts where it was programmed.
  void judge(Block& b, size_t li) {
    const int starts = arcs_.startKind(static_cast<int>(li) + 1);
    b.restore = b.write && starts > 0;
    if (b.restore) {
      b.restored_in = starts == GcodeArcStarts::kArc ? &arc_starts_ : &relative_starts_;
      b.restored_in->push_back(b.line_no);
    } else if (b.point != -1 && !b.write) {
      (motion_ == 2 || motion_ == 3)   ? arcs_list_.push_back(b.line_no)
      : motion_ >= 73 && motion_ != 80 ? cycles_.push_back(b.line_no)
      : !absolute_                     ? incremental_.push_back(b.line_no)
      : b.special                      ? machine_moves_.push_back(b.line_no)
                                       : expressions_.push_back(b.line_no);
    }
  }

  // Each axis's new word: the word (or the one in force) plus the joint's correction, or in TCP
  // mode the tip's correction in the program's frame (a Sinumerik ROT or CYCLE800 frame turns its
  // XYZ words). A correction to an axis the block does not name and whose word in force is
  // unknown cannot be written.
  void targets(Block& b) {
    const int i = b.point;
    const JointVector dq = b.restore ? JointVector::Zero(n_) : JointVector((*q_)[i] - (*q0_)[i]);
    const bool tcp =
        i < static_cast<int>(program_->tcp.size()) && program_->tcp[i] == ClProgram::kTcpWords;
    Eigen::Vector3d dxyz = Eigen::Vector3d::Zero();
    if (tcp && !b.restore) {
      dxyz = gm_inv_ * ((*corrected_p_w_)[i] - program_->path[i].p_w) / unit_;
      if (i < static_cast<int>(program_->point_frame.size()))
        dxyz = program_->frames[program_->point_frame[i]].T.linear().transpose() * dxyz;
    }
    const char L[3] = {'X', 'Y', 'Z'};
    // Joint words under a turned frame (LinuxCNC's G10 L2 R, Sinumerik's ROT): the machine's
    // X Y Z are the frame's turn of the words, so the joints' corrections are turned back.
    bool turned = false;
    if (!tcp && !b.restore && i < static_cast<int>(program_->point_frame.size())) {
      const Eigen::Matrix3d R = program_->frames[program_->point_frame[i]].T.linear();
      if (!R.isIdentity(1e-15)) {
        Eigen::Vector3d dm = Eigen::Vector3d::Zero();
        for (int k = 0; k < 3; ++k)
          if (axis_of_.count(L[k])) {
            const int a = axis_of_.at(L[k]);
            dm[k] = model_.axes[a].nc_sign * dq[a] / unit_;
          }
        dxyz = R.transpose() * dm;
        turned = true;
      }
    }
    b.target.assign(n_, 0.0);
    for (int a = 0; a < n_; ++a) {
      const Axis& ax = model_.axes[a];
      const auto w = b.axis_words.find(a);
      const double old = w != b.axis_words.end() ? w->second->value : old_word_[a];
      double delta = ax.isRotary() ? ax.nc_sign * radToDeg(dq[a]) : ax.nc_sign * dq[a] / unit_;
      if ((tcp || turned) && !ax.isRotary())
        for (int k = 0; k < 3; ++k)
          if (axis_of_.count(L[k]) && axis_of_.at(L[k]) == a) delta = dxyz[k];
      b.target[a] = old + delta;
      if (w == b.axis_words.end() && !known_[a] && std::abs(delta) > 0) b.write = false;
    }
    if (!b.write) {
      expressions_.push_back(b.line_no);
      if (b.restore) b.restored_in->pop_back();
    }
  }

  // A rapid (a rotary index, a retract) is never given words it did not have: its motion would
  // change kind (issue 32: X Y added to "G00 B82.875 C-90." after G53). Such a block is left as
  // programmed and listed.
  void keepRapidWords(Block& b) {
    for (int a = 0; a < n_ && b.write; ++a) {
      if (b.axis_words.count(a) || !known_[a]) continue;
      const int d =
          std::max(std::max(decimals_[a], 0), model_.axes[a].isRotary() ? kRotMin : lin_min_);
      if (fixed(b.target[a], d) != fixed(new_word_[a], d)) b.write = false;
    }
    if (!b.write) rapid_kept_.push_back(b.line_no);
  }

  // Replaces the words present (last first), then adds the ones whose value in force differs.
  void edit(Block& b) {
    std::string added;
    size_t insert_at = 0;
    for (const auto& [a, w] : b.axis_words) insert_at = std::max(insert_at, w->end);
    std::vector<std::pair<size_t, std::pair<size_t, std::string>>> edits;
    for (int a = 0; a < n_; ++a) {
      const Axis& ax = model_.axes[a];
      const auto w = b.axis_words.find(a);
      const int d =
          std::max(w != b.axis_words.end() ? w->second->decimals : std::max(decimals_[a], 0),
                   ax.isRotary() ? kRotMin : lin_min_);
      const std::string text = fixed(b.target[a], d);
      if (w != b.axis_words.end()) {
        edits.push_back({w->second->start, {w->second->end - w->second->start, text}});
        decimals_[a] = std::max(decimals_[a], w->second->decimals);
      } else if (known_[a] && text != fixed(new_word_[a], d)) {
        const char letter = static_cast<char>(std::toupper(static_cast<unsigned char>(ax.name[0])));
        added += std::string(" ") + letter + text;
      }
      new_word_[a] = std::strtod(text.c_str(), nullptr);
    }
    std::sort(edits.begin(), edits.end(),
              [](const auto& x, const auto& y) { return x.first > y.first; });
    if (!added.empty()) b.line.insert(insert_at, added);
    for (const auto& [start, e] : edits) b.line.replace(start, e.first, e.second);
    (*written_)[b.point] = !b.restore;
  }

  // The program's words in force after the block.
  void updateWordsInForce(const Block& b) {
    for (const auto& [a, w] : b.axis_words) {
      if (w->numeric && absolute_ && !b.special) {
        old_word_[a] = w->value;
        known_[a] = 1;
        decimals_[a] = std::max(decimals_[a], w->decimals);
      } else {
        known_[a] = 0;
      }
    }
    if (b.special)
      for (const auto& [a, w] : b.axis_words) known_[a] = 0;
    if (b.polar)
      for (const char l : {'X', 'Y'})
        if (axis_of_.count(l)) known_[axis_of_.at(l)] = 0;
  }

  const MachineModel& model_;
  const GcodeArcStarts& arcs_;
  const double unit_;
  const int lin_min_;
  const int n_;
  std::map<char, int> axis_of_;  // word letter -> axis
  Eigen::Matrix3d gm_inv_;
  bool skip_first_ = false;  // the leading '%', written with the header
  // The block being edited, its points' joints (commanded, compensating), corrected tips, flags.
  const ClProgram* program_ = nullptr;
  const std::vector<JointVector>* q0_ = nullptr;
  const std::vector<JointVector>* q_ = nullptr;
  const std::vector<Eigen::Vector3d>* corrected_p_w_ = nullptr;
  std::vector<char>* written_ = nullptr;
  // Modal state: the program's word in force per axis, the compensated program's, their decimals.
  std::vector<double> old_word_, new_word_;
  std::vector<char> known_;
  std::vector<int> decimals_;
  int motion_ = 0;  // 0, 1, 2, 3, 80 (none), 81+ (cycles)
  bool absolute_ = true;
  std::vector<int> arcs_list_, arc_starts_, relative_starts_, cycles_, incremental_, machine_moves_,
      expressions_, rapid_kept_;
};

}  // namespace

void GcodeArcStarts::add(const ClProgram& block) {
  for (size_t li = block.lines.first(); li < block.lines.size(); ++li) {
    for (const GWord& w : gcodeWords(std::string(block.lines[li]))) {
      if (w.letter != 'G' || !w.numeric) continue;
      if (w.value == 0 || w.value == 1 || w.value == 2 || w.value == 3 ||
          (w.value >= 73 && w.value <= 89))
        mode_ = static_cast<int>(w.value);
      else if (w.value == 90 || w.value == 91)
        absolute_ = w.value == 90;
    }
    const size_t k = li - block.lines.first();
    if (k >= block.statements.size() || block.statements[k].point_count <= 0) continue;
    // A block with points: the previous one starts an arc when this is one, or an incremental
    // or cycle block (left as programmed, it moves from where the previous one ends).
    const char kind = mode_ == 2 || mode_ == 3                     ? kArc
                      : !absolute_ || (mode_ >= 73 && mode_ != 80) ? kRelative
                                                                   : 0;
    if (last_point_line_ > 0 && kind) {
      if (starts_.size() <= static_cast<size_t>(last_point_line_)) starts_.resize(li + 1, 0);
      starts_[last_point_line_] = kind;
    }
    last_point_line_ = static_cast<int>(li) + 1;
  }
}

int GcodeArcStarts::startKind(int line) const {
  return line > 0 && static_cast<size_t>(line) < starts_.size() ? starts_[line] : 0;
}

struct CompensatedGcodeWriter::Editor : GcodeEditor {
  using GcodeEditor::GcodeEditor;
};

CompensatedGcodeWriter::CompensatedGcodeWriter(const MachineModel& model, const std::string& units,
                                               const GcodeArcStarts& arcs)
    : editor_(std::make_unique<Editor>(model, units, arcs)) {}

CompensatedGcodeWriter::~CompensatedGcodeWriter() = default;

void CompensatedGcodeWriter::start(const ClProgram& first, const std::vector<std::string>& header,
                                   std::string& out, std::vector<int>* source_line) {
  editor_->start(first, header, out, source_line);
}

void CompensatedGcodeWriter::lines(const ClProgram& block, const std::vector<JointVector>& q0,
                                   const std::vector<JointVector>& q,
                                   const std::vector<Eigen::Vector3d>& corrected_p_w,
                                   std::string& out, std::vector<char>& written,
                                   std::vector<int>* source_line) {
  editor_->lines(block, q0, q, corrected_p_w, out, written, source_line);
}

std::vector<std::string> CompensatedGcodeWriter::notes() const { return editor_->notes(); }

CompensatedProgramText formatCompensatedGcode(const ClProgram& program, const MachineModel& model,
                                              const std::vector<JointVector>& q0,
                                              const std::vector<JointVector>& q,
                                              const std::vector<Eigen::Vector3d>& corrected_p_w,
                                              const std::vector<std::string>& header) {
  GcodeArcStarts arcs;
  arcs.add(program);
  CompensatedGcodeWriter writer(model, program.units, arcs);
  CompensatedProgramText out;
  writer.start(program, header, out.text, &out.source_line);
  writer.lines(program, q0, q, corrected_p_w, out.text, out.written, &out.source_line);
  out.notes = writer.notes();
  return out;
}

bool gcodeGivesRotaryWords(const ClProgram& program, const MachineModel& model) {
  std::vector<char> rotary(256, 0);
  for (const Axis& ax : model.axes)
    if (ax.isRotary() && ax.name.size() == 1)
      rotary[static_cast<unsigned char>(std::toupper(static_cast<unsigned char>(ax.name[0])))] = 1;
  for (size_t li = program.lines.first(); li < program.lines.size(); ++li)
    for (const GWord& w : gcodeWords(std::string(program.lines[li])))
      if (rotary[static_cast<unsigned char>(w.letter)]) return true;
  return false;
}

}  // namespace tolver
