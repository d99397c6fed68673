#include "io/program/compensated_program.h"

#include <Eigen/LU>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <map>

#include "core/kinematics/forward_kinematics.h"
#include "core/numerics/units.h"

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
  t->value = std::strtod(s.substr(i, j - i).c_str(), nullptr);
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
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  std::string s = buf;
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
  for (size_t k = 0; k < lines.size() && k < 8; ++k) s += (k ? ", " : "") + std::to_string(lines[k]);
  if (lines.size() > 8) s += ", ...";
  return s;
}

}  // namespace

// Long by design: one pass over the source's statements, keeping every line it does not change
// byte for byte.
CompensatedProgramText formatCompensatedApt(const ClProgram& program,
                                            const std::vector<ClPoint>& corrected,
                                            const std::vector<std::string>& header) {
  CompensatedProgramText out;
  out.written.assign(program.path.size(), 1);
  const bool inch = program.units == "INCH";
  const int pos_min = inch ? 8 : 6, axis_min = 9;
  for (const std::string& h : header) {
    out.text += "$$ " + h + "\n";
    out.source_line.push_back(0);
  }
  // The file's coordinates of a corrected point.
  auto inFile = [&](int k, Eigen::Vector3d* p, Eigen::Vector3d* u) {
    const ClFrame& f = program.frames[program.point_frame[k]];
    *p = f.T.inverse(Eigen::Isometry) * (corrected[k].p_w / f.scale);
    *u = f.T.linear().transpose() * corrected[k].u_w.normalized();
  };
  int expanded = 0;
  std::vector<int> expanded_lines;
  for (const AptStatement& st : program.statements) {
    const bool single = st.point_count == 1 && (st.major == "GOTO" || st.major == "FROM");
    if (single) {
      // The numbers of the statement, across its continuation lines, after the '/'.
      std::vector<std::string> lines;
      for (int l = st.first_line; l <= st.last_line; ++l) lines.emplace_back(program.lines[l - 1]);
      std::vector<std::pair<size_t, NumToken>> tokens;
      for (size_t l = 0; l < lines.size(); ++l) {
        size_t from = 0;
        if (l == 0) {
          const size_t slash = lines[0].find('/');
          from = slash == std::string::npos ? lines[0].size() : slash + 1;
        }
        for (const NumToken& t : numbersIn(lines[l], from)) tokens.push_back({l, t});
      }
      Eigen::Vector3d p, u;
      inFile(st.first_point, &p, &u);
      if (tokens.size() >= 3) {
        const double v[6] = {p.x(), p.y(), p.z(), u.x(), u.y(), u.z()};
        const size_t n = std::min<size_t>(tokens.size(), 6);
        // Replace from the last token backwards, so that earlier offsets stay valid.
        std::string append;
        if (program.multiax && tokens.size() < 6) {
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
          out.text += lines[l] + "\n";
          out.source_line.push_back(st.first_line + static_cast<int>(l));
        }
        continue;
      }
    }
    if (st.point_count >= 1) {
      // Points the reader expanded (an arc, a curve): GOTOs of their compensated points.
      ++expanded;
      expanded_lines.push_back(st.first_line);
      out.text += "$$ tolver: " + (st.major.empty() ? std::string("statement") : st.major) + " of line " +
                  std::to_string(st.first_line) + " as the GOTOs of its compensated points\n";
      out.source_line.push_back(st.first_line);
      for (int k = st.first_point; k < st.first_point + st.point_count; ++k) {
        Eigen::Vector3d p, u;
        inFile(k, &p, &u);
        out.text += "GOTO/" + fixed(p.x(), pos_min) + "," + fixed(p.y(), pos_min) + "," + fixed(p.z(), pos_min);
        if (program.multiax)
          out.text += "," + fixed(u.x(), axis_min) + "," + fixed(u.y(), axis_min) + "," + fixed(u.z(), axis_min);
        out.text += "\n";
        out.source_line.push_back(st.first_line);
      }
      continue;
    }
    if (st.major == "CIRCLE" || st.major == "MOVARC") {
      out.text += "$$ tolver: " + st.major + " of line " + std::to_string(st.first_line) +
                  " replaced by the compensated points of its arc that follow\n";
      out.source_line.push_back(st.first_line);
      continue;
    }
    for (int l = st.first_line; l <= st.last_line; ++l) {
      out.text += program.lines[l - 1];
      out.text += '\n';
      out.source_line.push_back(l);
    }
  }
  if (expanded > 0)
    out.notes.push_back(std::to_string(expanded) + " statements whose points the reader expanded " +
                        "(arcs, curves; lines " + lineList(expanded_lines) +
                        ") were written as GOTOs of their compensated points");
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
      const size_t close = s.find(')', i);
      i = close == std::string::npos ? s.size() : close + 1;
      continue;
    }
    if (c == ';') break;
    if (!std::isalpha(static_cast<unsigned char>(c))) {
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
          while (k < s.size() && (std::isdigit(static_cast<unsigned char>(s[k])) || s[k] == '.')) ++k;
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

// Long by design: one pass over the source's blocks carrying the control's modal state (units,
// G90/G91, TCP, arcs, the block before an arc); split up, every part would take that state.
CompensatedProgramText formatCompensatedGcode(const ClProgram& program, const MachineModel& model,
                                              const std::vector<JointVector>& q0,
                                              const std::vector<JointVector>& q,
                                              const std::vector<Eigen::Vector3d>& corrected_p_w,
                                              const std::vector<std::string>& header) {
  CompensatedProgramText out;
  out.written.assign(program.path.size(), 0);
  const double unit = program.units == "INCH" ? 25.4 : 1.0;
  const int lin_min = unit == 25.4 ? 5 : 4, rot_min = 4;
  const int n = static_cast<int>(model.axes.size());
  std::map<char, int> axis_of;  // word letter -> axis
  for (int a = 0; a < n; ++a)
    if (model.axes[a].name.size() == 1)
      axis_of[static_cast<char>(std::toupper(static_cast<unsigned char>(model.axes[a].name[0])))] = a;
  // In TCP mode X Y Z are program coordinates of the tip: p_w = g0 + Gm (xyz + offset), Gm the
  // prismatic joints' effect (times nc_sign) at rotaries zero.
  Eigen::Matrix3d Gm = Eigen::Matrix3d::Identity();
  {
    const ForwardKinematics nominal(model, Eigen::VectorXd::Zero(model.parameterCount()));
    const char L[3] = {'X', 'Y', 'Z'};
    const JointVector z = JointVector::Zero(n);
    Eigen::Vector3d p0, u;
    nominal.tipAndAxis(z, &p0, &u);
    for (int k = 0; k < 3; ++k) {
      auto it = axis_of.find(L[k]);
      if (it == axis_of.end()) continue;
      JointVector qk = z;
      qk[it->second] += model.axes[it->second].nc_sign;
      Eigen::Vector3d pk;
      nominal.tipAndAxis(qk, &pk, &u);
      Gm.col(k) = pk - p0;
    }
  }
  const Eigen::Matrix3d Gm_inv = Gm.inverse();
  // The program's word in force per axis, the compensated program's, and their decimals.
  std::vector<double> old_word(n, 0.0), new_word(n, 0.0);
  std::vector<char> known(n, 0);
  std::vector<int> decimals(n, -1);
  int motion = 0;        // 0, 1, 2, 3, 80 (none), 81+ (cycles)
  bool absolute = true;
  std::vector<int> arcs, cycles, incremental, machine_moves, expressions, rapid_kept;
  // The header after a leading '%' line.
  size_t first = 0;
  if (!program.lines.empty() && !program.lines[0].empty() && program.lines[0][0] == '%') {
    out.text += program.lines[0];
    out.text += '\n';
    out.source_line.push_back(1);
    first = 1;
  }
  // A Sinumerik control reads "( )" as a call: its comments start with ';'.
  const bool semicolon = model.control.dialect == "sinumerik";
  for (const std::string& h : header) {
    out.text += semicolon ? "; " + h + "\n" : "(" + withoutParentheses(h) + ")\n";
    out.source_line.push_back(0);
  }
  // Which blocks are arcs (the motion mode in force, modal): the block before an arc gives the
  // arc's start, which must stay on the arc's circle, so it is left as programmed too.
  std::vector<char> arc_block(program.lines.size(), 0);
  {
    int mode = 0;
    for (size_t li = 0; li < program.lines.size(); ++li) {
      for (const GWord& w : gcodeWords(std::string(program.lines[li])))
        if (w.letter == 'G' && w.numeric && (w.value == 0 || w.value == 1 || w.value == 2 || w.value == 3))
          mode = static_cast<int>(w.value);
      arc_block[li] = (mode == 2 || mode == 3) && li < program.statements.size() &&
                      program.statements[li].point_count > 0;
    }
  }
  auto startsArc = [&](size_t li) {
    for (size_t k = li + 1; k < program.lines.size() && k < program.statements.size(); ++k)
      if (program.statements[k].point_count > 0) return arc_block[k] != 0;
    return false;
  };
  std::vector<int> arc_starts;
  for (size_t li = first; li < program.lines.size(); ++li) {
    std::string line(program.lines[li]);
    const AptStatement* st = li < program.statements.size() ? &program.statements[li] : nullptr;
    const std::vector<GWord> words = gcodeWords(line);
    bool special = false, expression = false;
    std::map<int, const GWord*> axis_words;
    for (const GWord& w : words) {
      if (w.letter == 'G' && w.numeric) {
        const double g = w.value;
        if (g == 0 || g == 1 || g == 2 || g == 3) motion = static_cast<int>(g);
        else if (g == 80) motion = 80;
        else if (g >= 73 && g <= 89 && g != 80) motion = static_cast<int>(g);
        else if (g == 90) absolute = true;
        else if (g == 91) absolute = false;
        else if (g == 53 || g == 28 || g == 30 || g == 10 || g == 92) special = true;
      }
      auto it = axis_of.find(w.letter);
      if (it != axis_of.end()) {
        axis_words[it->second] = &w;
        if (!w.numeric) expression = true;
      }
    }
    const int points = st ? st->point_count : 0;
    const int i = points > 0 ? st->first_point : -1;
    const int line_no = static_cast<int>(li) + 1;
    bool write = points == 1 && (motion == 0 || motion == 1) && absolute && !special && !expression;
    // The block before an arc is written back to the program's own position, all axes (the
    // values in force may carry earlier corrections): the arc starts where it was programmed.
    const bool restore = write && startsArc(li);
    if (restore) {
      arc_starts.push_back(line_no);
    } else if (points > 0 && !write) {
      (motion == 2 || motion == 3)   ? arcs.push_back(line_no)
      : motion >= 73 && motion != 80 ? cycles.push_back(line_no)
      : !absolute                    ? incremental.push_back(line_no)
      : special                      ? machine_moves.push_back(line_no)
                                     : expressions.push_back(line_no);
    }
    std::vector<double> target(n, 0.0);
    if (write) {
      const JointVector dq = restore ? JointVector::Zero(n) : JointVector(q[i] - q0[i]);
      const bool tcp = i < static_cast<int>(program.tcp.size()) &&
                       program.tcp[i] == ClProgram::kTcpWords;
      Eigen::Vector3d dxyz = Eigen::Vector3d::Zero();
      if (tcp && !restore) {
        // In the program's frame (a Sinumerik ROT or CYCLE800 frame turns its XYZ words).
        dxyz = Gm_inv * (corrected_p_w[i] - program.path[i].p_w) / unit;
        if (i < static_cast<int>(program.point_frame.size()))
          dxyz = program.frames[program.point_frame[i]].T.linear().transpose() * dxyz;
      }
      const char L[3] = {'X', 'Y', 'Z'};
      for (int a = 0; a < n; ++a) {
        const Axis& ax = model.axes[a];
        const auto w = axis_words.find(a);
        const double old = w != axis_words.end() ? w->second->value : old_word[a];
        double delta = ax.isRotary() ? ax.nc_sign * radToDeg(dq[a]) : ax.nc_sign * dq[a] / unit;
        if (tcp && !ax.isRotary())
          for (int k = 0; k < 3; ++k)
            if (axis_of.count(L[k]) && axis_of[L[k]] == a) delta = dxyz[k];
        target[a] = old + delta;
        if (w == axis_words.end() && !known[a] && std::abs(delta) > 0) write = false;
      }
      if (!write) {
        expressions.push_back(line_no);
        if (restore) arc_starts.pop_back();
      }
    }
    // A rapid (a rotary index, a retract) is never given words it did not have: its motion
    // would change kind (issue 32: X Y added to "G00 B82.875 C-90." after G53). Such a block
    // is left as programmed and listed.
    if (write && motion == 0 && !restore) {
      for (int a = 0; a < n && write; ++a) {
        if (axis_words.count(a) || !known[a]) continue;
        const int d = std::max(std::max(decimals[a], 0), model.axes[a].isRotary() ? rot_min : lin_min);
        if (fixed(target[a], d) != fixed(new_word[a], d)) write = false;
      }
      if (!write) {
        rapid_kept.push_back(line_no);
        for (const auto& [a, w] : axis_words)
          if (w->numeric) new_word[a] = w->value;  // the block as written
      }
    }
    if (write) {
      // Replace the words present (last first), then add the ones whose value in force differs.
      std::string added;
      size_t insert_at = 0;
      for (const auto& [a, w] : axis_words) insert_at = std::max(insert_at, w->end);
      std::vector<std::pair<size_t, std::pair<size_t, std::string>>> edits;
      for (int a = 0; a < n; ++a) {
        const Axis& ax = model.axes[a];
        const auto w = axis_words.find(a);
        const int d = std::max(w != axis_words.end() ? w->second->decimals : std::max(decimals[a], 0),
                               ax.isRotary() ? rot_min : lin_min);
        const std::string text = fixed(target[a], d);
        if (w != axis_words.end()) {
          edits.push_back({w->second->start, {w->second->end - w->second->start, text}});
          decimals[a] = std::max(decimals[a], w->second->decimals);
        } else if (known[a] && text != fixed(new_word[a], d)) {
          char letter = static_cast<char>(std::toupper(static_cast<unsigned char>(ax.name[0])));
          added += std::string(" ") + letter + text;
        }
        new_word[a] = std::strtod(text.c_str(), nullptr);
      }
      std::sort(edits.begin(), edits.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
      if (!added.empty()) line.insert(insert_at, added);
      for (const auto& [start, e] : edits) line.replace(start, e.first, e.second);
      out.written[i] = !restore;
    } else {
      for (const auto& [a, w] : axis_words)
        if (w->numeric) new_word[a] = w->value;  // the block as written
    }
    // The program's words in force after this block.
    for (const auto& [a, w] : axis_words) {
      if (w->numeric && absolute && !special) {
        old_word[a] = w->value;
        known[a] = 1;
        decimals[a] = std::max(decimals[a], w->decimals);
      } else {
        known[a] = 0;
      }
    }
    if (special)
      for (const auto& [a, w] : axis_words) known[a] = 0;
    out.text += line + "\n";
    out.source_line.push_back(static_cast<int>(li) + 1);
  }
  auto note = [&](const std::vector<int>& lines, const char* what) {
    if (!lines.empty())
      out.notes.push_back(std::to_string(lines.size()) + " " + what + " left as programmed, uncompensated (lines " +
                          lineList(lines) + ")");
  };
  note(arcs, "arc blocks (G2/G3)");
  note(arc_starts, "blocks that start an arc (written back to their programmed position: the arc's start must stay on its circle)");
  note(cycles, "drilling-cycle blocks");
  note(incremental, "incremental (G91) blocks");
  note(machine_moves, "moves in machine coordinates (G53, G28, ...)");
  note(expressions, "blocks with words given by expressions or parameters, or without the word in force");
  note(rapid_kept, "rapid blocks that would need an axis they do not name (a rapid keeps its words)");
  return out;
}

bool gcodeGivesRotaryWords(const ClProgram& program, const MachineModel& model) {
  std::vector<char> rotary(256, 0);
  for (const Axis& ax : model.axes)
    if (ax.isRotary() && ax.name.size() == 1)
      rotary[static_cast<unsigned char>(std::toupper(static_cast<unsigned char>(ax.name[0])))] = 1;
  for (size_t li = 0; li < program.lines.size(); ++li)
    for (const GWord& w : gcodeWords(std::string(program.lines[li])))
      if (rotary[static_cast<unsigned char>(w.letter)]) return true;
  return false;
}

}  // namespace tolver
