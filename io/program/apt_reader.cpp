#include "io/program/apt_reader.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <deque>
#include <optional>
#include <set>

#include "core/numerics/units.h"
#include "core/path/arc_interpolation.h"
#include "io/common/io_error.h"
#include "io/common/line_source.h"
#include "io/common/text_util.h"

namespace tolver {
namespace {

// A logical statement assembled from one or more physical lines, with the source position of
// every character so that errors can name line and column.
struct Logical {
  std::string text;
  std::vector<std::pair<int, int>> pos;  // (line, column), 1-based, per character
};

struct Arg {
  std::string text;  // trimmed
  int line = 0;
  int column = 0;
};

const std::set<std::string>& noOpStatements() {
  static const std::set<std::string> s = {
      "SPINDL",      "LOADTL", "LOAD",      "SELECT", "PPRINT", "INSERT", "COOLNT", "TOOL PATH",
      "END-OF-PATH", "END",    "PAINT",     "MACHIN", "DELAY",  "OPSTOP", "STOP",   "CLRSRF",
      "FEATNO",      "MFGNO",  "OPERATION", "DISPLY", "AUTOPS", "PLABEL", "PPWORD"};
  return s;
}

class Parser {
 public:
  Parser(LineSource& source, const std::string& file, const AptReadOptions& opt,
         const ProgramBlocks* blocks)
      : opt_(opt), source_(source), blocks_(blocks) {
    prog_.file = file;
    prog_.frames.push_back(ClFrame{});
    prog_.frames[0].scale = opt.unit_mm;
    if (opt.unit_mm == 25.4) prog_.units = "INCH";
    // Line ends for a line of about 40 bytes; the text when it is kept (growing it by doubling
    // would copy it and fault in fresh pages over and over).
    const size_t bytes = source.sizeHint();
    if (!blocks_) prog_.lines.reserve(opt.keep_motion_text ? bytes : 0, bytes / 40);
  }

  ClProgram run() {
    bool any = false;
    size_t i = 0;
    bool finished = false;
    while (line(i) != nullptr) {
      const size_t start = i;
      const std::string& raw = *line(i);
      const std::string_view t = trim(raw);
      any = any || !t.empty();
      AptStatement st;
      st.first_line = static_cast<int>(i) + 1;
      if (finished || t.empty()) {
        ++i;
      } else if (t.rfind("$$*CATIA0", 0) == 0) {
        i = catiaFrame(i);
        st.major = "$$*CATIA0";
      } else if (t.rfind("$$->", 0) == 0) {
        const Logical& lg = gather(i, 4 + (t.data() - raw.data()), /*pseudo=*/true);
        st.major = statement(lg, /*pseudo=*/true, st);
        st.major.clear();  // Creo pseudo-comments are copied verbatim, never rewritten
      } else if (const size_t arrow = remarkArrow(t); arrow != 0) {
        // APT's REMARK is a comment to the end of its line (ISO 4343); Pro/CLFILE 9 writes its
        // pseudo-comments as `REMARK -> CUTTER / 6.0` where version 8 wrote `$$-> ...`: read
        // the same way.
        if (arrow != std::string_view::npos) {
          const Logical& lg = gather(i, arrow + (t.data() - raw.data()), /*pseudo=*/true);
          statement(lg, /*pseudo=*/true, st);
        } else {
          ++i;
        }
        st.major.clear();  // copied verbatim, never rewritten
      } else if (t.rfind("$$", 0) == 0 || t[0] == '$') {
        operation(static_cast<int>(i) + 1, operationName(t));
        ++i;
      } else if (plainGoto(t, static_cast<int>(i) + 1, st)) {
        ++i;
        st.major = "GOTO";
      } else {
        const Logical& lg = gather(i, 0, /*pseudo=*/false);
        st.major = statement(lg, /*pseudo=*/false, st);
        if (st.major == "FINI") finished = true;
      }
      st.last_line = static_cast<int>(std::max(i, start + 1));
      // The writers regenerate GOTO and FROM from their points: their text is not needed.
      keepUpTo(static_cast<size_t>(st.last_line),
               opt_.keep_motion_text || (st.major != "GOTO" && st.major != "FROM"));
      prog_.statements.push_back(st);
      if (blocks_ && prog_.path.size() >= blocks_->points) passOn(false);
    }
    if (!any) fail(0, 0, "", "empty file: no statements");
    // The main MCS read as the part frame while its z points down in the CAD's absolute frame
    // and the tool axes point down in it: they point up in the absolute frame, so the part may
    // be fixtured in that frame instead. Said, not guessed.
    countDown();
    if (main_mcs_ && !opt_.absolute_msys && main_mcs_->linear()(2, 2) < -0.5 && read_ > 0 &&
        2 * down_ > read_)
      prog_.notes.push_back(
          "the tool axis points down (-z) in the main MCS on " + std::to_string(down_) + " of " +
          std::to_string(read_) +
          " points; that MCS's z points down in the CAD's "
          "absolute frame, where the tool points up: if the part is fixtured in the absolute "
          "frame, read the program with --absolute-msys");
    if (blocks_) passOn(true);
    return std::move(prog_);
  }

 private:
  // Physical line i (0-based) of the file, read on demand; nullptr past its end. The lines of
  // the statement being read stay in the window; earlier ones are in prog_.lines.
  const std::string* line(size_t i) {
    while (i >= window_first_ + window_.size() && !at_end_) {
      // A string of a line already passed on, whose buffer is reused (no allocation per line).
      std::string l;
      if (!spare_.empty()) {
        l = std::move(spare_.back());
        spare_.pop_back();
      }
      if (source_.next(l))
        window_.push_back(std::move(l));
      else
        at_end_ = true;
    }
    return i < window_first_ + window_.size() ? &window_[i - window_first_] : nullptr;
  }

  // The points held whose tool axis points down (-z), counted once.
  void countDown() {
    for (size_t i = down_counted_; i < prog_.path.size(); ++i)
      down_ += prog_.path[i].u_w.z() < -0.5;
    read_ += prog_.path.size() - down_counted_;
    down_counted_ = prog_.path.size();
  }

  // The block read so far to the sink, then dropped (the last point kept apart: an arc starts
  // there).
  void passOn(bool last) {
    countDown();
    if (!prog_.path.empty()) {
      last_passed_ = prog_.path.back();
      passed_any_ = true;
    }
    blocks_->sink(prog_, last);
    prog_.dropBlock();
    down_counted_ = 0;
  }

  // The path's last point, held or passed on; nullptr before the first.
  const ClPoint* lastPoint() const {
    if (!prog_.path.empty()) return &prog_.path.back();
    return passed_any_ ? &last_passed_ : nullptr;
  }

  // Moves the lines before `end` (0-based, exclusive) from the window into prog_.lines.
  void keepUpTo(size_t end, bool keep_text) {
    while (window_first_ < end && !window_.empty()) {
      prog_.lines.push(window_.front(), keep_text);
      spare_.push_back(std::move(window_.front()));
      window_.pop_front();
      ++window_first_;
    }
  }

  [[noreturn]] void fail(int line, int column, const std::string& field, const std::string& msg) {
    throw InputError(prog_.file, line, column, field, msg);
  }

  // For a line that is an APT REMARK: npos for a plain remark, else the offset just past the
  // `->` of a Creo pseudo-comment (`REMARK -> CUTTER / 6.0`); 0 for any other line.
  static size_t remarkArrow(std::string_view t) {
    if (t.size() < 6 || (t[0] != 'R' && t[0] != 'r')) return 0;  // most lines: a GOTO
    if (toUpper(std::string(t.substr(0, 6))) != "REMARK") return 0;
    if (t.size() > 6 && !std::isspace(static_cast<unsigned char>(t[6])) && t[6] != '/') return 0;
    size_t k = 6;
    while (k < t.size() && std::isspace(static_cast<unsigned char>(t[k]))) ++k;
    return t.substr(k, 2) == "->" ? k + 2 : std::string_view::npos;
  }

  // Collects a statement from line i on, following `$` continuations; strips `$$` comments.
  // Into lg_, whose storage the statements share (no allocation per statement).
  const Logical& gather(size_t& i, size_t skip, bool pseudo) {
    Logical& lg = lg_;
    lg.text.clear();
    lg.pos.clear();
    const size_t first = i;
    while (true) {
      if (line(i) == nullptr)
        fail(static_cast<int>(first) + 1, 0, "", "statement continues past the end of the file");
      std::string_view raw = *line(i);
      size_t from = (i == first) ? skip : 0;
      std::string_view body = raw.substr(std::min(from, raw.size()));
      if (!pseudo || i != first) {
        const size_t c = body.find("$$");
        if (c != std::string_view::npos) body = body.substr(0, c);
      }
      // Trailing `$` (after trimming) continues the statement on the next line.
      size_t end = body.size();
      while (end > 0 && std::isspace(static_cast<unsigned char>(body[end - 1]))) --end;
      const bool cont = end > 0 && body[end - 1] == '$';
      if (cont) --end;
      lg.text.append(body.substr(0, end));
      for (size_t k = 0; k < end; ++k)
        lg.pos.emplace_back(static_cast<int>(i) + 1,
                            static_cast<int>(k + (body.data() - raw.data())) + 1);
      ++i;
      if (!cont) break;
      lg.text += ' ';
      lg.pos.emplace_back(static_cast<int>(i), static_cast<int>(raw.size()) + 1);
    }
    return lg;
  }

  size_t catiaFrame(size_t i) {
    // $$*CATIA0, an optional name line, then three rows "$$*  r1 r2 r3 t".
    const int head = static_cast<int>(i) + 1;
    ++i;
    std::vector<double> m;
    while (line(i) != nullptr && m.size() < 12) {
      std::string_view t = trim(*line(i));
      if (t.rfind("$$", 0) != 0) break;
      t.remove_prefix(2);
      if (!t.empty() && t[0] == '*') t.remove_prefix(1);
      std::vector<double> row;
      bool numeric = true;
      size_t p = 0;
      std::string s(t);
      for (char& c : s)
        if (c == ',') c = ' ';
      while (p < s.size()) {
        while (p < s.size() && std::isspace(static_cast<unsigned char>(s[p]))) ++p;
        size_t q = p;
        while (q < s.size() && !std::isspace(static_cast<unsigned char>(s[q]))) ++q;
        if (q > p) {
          auto v = parseNumber(std::string_view(s).substr(p, q - p));
          if (!v)
            numeric = false;
          else
            row.push_back(*v);
        }
        p = q;
      }
      ++i;
      if (!numeric || row.empty()) {
        if (!m.empty()) fail(static_cast<int>(i), 0, "$$*CATIA0", "malformed matrix row");
        continue;  // the name line
      }
      if (row.size() != 4)
        fail(static_cast<int>(i), 0, "$$*CATIA0", "a matrix row needs 4 numbers");
      m.insert(m.end(), row.begin(), row.end());
    }
    if (m.size() != 12) fail(head, 0, "$$*CATIA0", "expected three matrix rows of 4 numbers");
    setFrameFromRows(m, head, "$$*CATIA0");
    return i;
  }

  void setFrameFromRows(const std::vector<double>& m, int line, const std::string& field) {
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) R(r, c) = m[4 * r + c];
      t[r] = m[4 * r + 3];
    }
    if ((R.transpose() * R - Eigen::Matrix3d::Identity()).norm() > 1e-4 || R.determinant() < 0)
      fail(line, 0, field, "the rotation part is not a proper orthonormal matrix");
    ClFrame f = prog_.frames.back();
    f.T.linear() = R;
    f.T.translation() = t;
    pushFrame(f);
  }

  void pushFrame(const ClFrame& f) {
    prog_.frames.push_back(f);
    frame_ = static_cast<int>(prog_.frames.size()) - 1;
  }

  // Into args_, whose strings the statements share.
  const std::vector<Arg>& splitArgs(const Logical& lg, size_t from) {
    std::vector<Arg>& args = args_;
    size_t n = 0;
    size_t p = from;
    while (true) {
      size_t q = lg.text.find(',', p);
      if (q == std::string::npos) q = lg.text.size();
      size_t b = p, e = q;
      while (b < e && std::isspace(static_cast<unsigned char>(lg.text[b]))) ++b;
      while (e > b && std::isspace(static_cast<unsigned char>(lg.text[e - 1]))) --e;
      if (n == args.size()) args.emplace_back();
      Arg& a = args[n++];
      a.text.assign(lg.text, b, e - b);
      a.line = a.column = 0;
      const size_t at = b < lg.pos.size() ? b : (lg.pos.empty() ? 0 : lg.pos.size() - 1);
      if (!lg.pos.empty()) {
        a.line = lg.pos[at].first;
        a.column = lg.pos[at].second + (b >= lg.pos.size() ? 1 : 0);
      }
      if (q == lg.text.size()) break;
      p = q + 1;
    }
    if (n == 1 && args[0].text.empty()) n = 0;
    args.resize(n);
    return args;
  }

  // The common statement, GOTO/x,y,z[,i,j,k] on one line of plain numbers, read without the
  // general path's buffers. Anything else, and anything the general path would refuse, is left
  // to it (false): it reads the same values the same way (tests/apt_reader_test.cpp).
  bool plainGoto(std::string_view t, int line, AptStatement& st) {
    if (t.size() < 6 || t.compare(0, 5, "GOTO/") != 0 || t.find('$') != std::string_view::npos)
      return false;
    double v[6];
    int n = 0;
    for (size_t p = 5;;) {
      if (n == 6) return false;
      size_t q = t.find(',', p);
      if (q == std::string_view::npos) q = t.size();
      const std::string_view token = trim(t.substr(p, q - p));
      if (!looksNumeric(token)) return false;
      const std::optional<double> x = parseNumber(token);
      if (!x || std::abs(*x) > 1e9) return false;
      v[n++] = *x;
      if (q == t.size()) break;
      p = q + 1;
    }
    if (n != 3 && n != 6) return false;
    if (n == 6) {
      const Eigen::Vector3d u(v[3], v[4], v[5]);
      if (u.norm() < 1e-9) return false;
      axis_local_ = u.normalized();
      prog_.multiax = true;
    }
    const Eigen::Vector3d p(v[0], v[1], v[2]);
    if (cycle_.active)
      cycleMotion(p, line, st);
    else
      addMotion(p, line, st);
    return true;
  }

  static bool looksNumeric(std::string_view s) {
    return !s.empty() && (std::isdigit(static_cast<unsigned char>(s[0])) || s[0] == '.' ||
                          s[0] == '-' || s[0] == '+');
  }

  // All arguments as numbers; words are allowed only where `words_ok`, and are skipped.
  std::vector<double> numbers(const std::vector<Arg>& args, const std::string& field, bool words_ok,
                              std::vector<std::string>* words = nullptr) {
    std::vector<double> v;
    numbers(args, field, words_ok, words, &v);
    return v;
  }
  // The same into *out (its storage reused).
  void numbers(const std::vector<Arg>& args, const std::string& field, bool words_ok,
               std::vector<std::string>* words, std::vector<double>* out) {
    std::vector<double>& v = *out;
    v.clear();
    for (const Arg& a : args) {
      if (a.text.empty()) fail(a.line, a.column, field, "missing value");
      if (looksNumeric(a.text)) {
        auto x = parseNumber(a.text);
        if (!x) fail(a.line, a.column, field, "malformed number '" + a.text + "'");
        if (std::abs(*x) > 1e9)
          fail(a.line, a.column, field, "value out of range '" + a.text + "'");
        v.push_back(*x);
      } else if (words_ok) {
        if (words) words->push_back(toUpper(a.text));
      } else {
        fail(a.line, a.column, field, "expected a number, found '" + a.text + "'");
      }
    }
  }

  // Parses and applies one logical statement; returns its major word.
  std::string statement(const Logical& lg, bool pseudo, AptStatement& st) {
    const size_t slash = lg.text.find('/');
    std::string major;
    {
      std::string m = toUpper(trim(std::string_view(lg.text).substr(0, slash)));
      // Collapse inner spaces ("TOOL  PATH" -> "TOOL PATH").
      for (char c : m) {
        if (std::isspace(static_cast<unsigned char>(c))) {
          if (!major.empty() && major.back() != ' ') major += ' ';
        } else {
          major += c;
        }
      }
    }
    const int line = lg.pos.empty() ? 0 : lg.pos.front().first;
    static const std::vector<Arg> none;
    const std::vector<Arg>& args = slash == std::string::npos ? none : splitArgs(lg, slash + 1);
    if (pseudo) {
      if (major == "CUTTER" || major == "CSYS" || major == "FEATNO") apply(major, args, line, st);
      return major;  // other Creo pseudo-comments are comments
    }
    apply(major, args, line, st);
    return major;
  }

  // One statement: its major word decides what it does to the path, the frames, the tools or
  // the notes; an unknown word is counted and named.
  void apply(const std::string& major, const std::vector<Arg>& args, int line, AptStatement& st) {
    if (major == "GOTO" || major == "FROM") {
      goTo(major, args, line, st);
    } else if (major == "GOHOME") {
      goHome(line);
    } else if (major == "CYCLE") {
      cycleStatement(args, line);
    } else if (major == "CUTCOM") {
      cutcom(args, line);
    } else if (major == "GODLTA") {
      goDelta(args, line, st);
    } else if (major == "TLAXIS") {
      toolAxis(args, line);
    } else if (major == "MULTAX") {
      prog_.multiax = args.empty() || toUpper(args[0].text) != "OFF";
    } else if (major == "CIRCLE" || major == "MOVARC") {
      circle(major, args, line);
    } else if (major == "UNITS" || major == "UNIT") {
      units(major, args, line);
    } else if (major == "FEDRAT") {
      std::vector<std::string> words;
      const std::vector<double> v = numbers(args, major, true, &words);
      if (v.empty()) fail(line, 0, major, "no feed rate value");
      feedRate(v[0], words);
    } else if (major == "SPINDL") {
      // SPINDL/rpm[,RPM|SFM|SMM][,CLW|CCLW]: the speed turns per-revolution feeds into mm/min.
      std::vector<std::string> words;
      const std::vector<double> v = numbers(args, major, true, &words);
      const bool surface = std::find(words.begin(), words.end(), "SFM") != words.end() ||
                           std::find(words.begin(), words.end(), "SMM") != words.end();
      if (!v.empty()) spindle_rpm_ = surface ? NAN : std::abs(v[0]);
    } else if (major == "RAPID") {
      rapid_next_ = true;
    } else if (major == "CUTTER") {
      cutter(args, line);
    } else if (major == "TLDATA") {
      toolData(args, line);
    } else if (major == "TRNTYP") {
      trntyp_world_ = !args.empty() && toUpper(args[0].text) == "WORLD";
    } else if (major == "CSYS") {
      csys(args, line);
    } else if (major == "MSYS") {
      msys(args, line);
    } else if (major == "TOOL PATH" || major == "OPERATION") {  // NX: TOOL PATH/name,TOOL,...
      if (!args.empty()) {
        std::string name(trim(args[0].text));
        name.erase(std::remove(name.begin(), name.end(), '\''), name.end());
        operation(line, name);
      }
    } else if (major == "FEATNO") {  // Creo: the NC sequence's feature number
      if (!args.empty()) operation(line, "feature " + std::string(trim(args[0].text)));
    } else if (major == "PPRINT") {
      std::string text;
      for (const Arg& a : args) text += a.text + " ";
      operation(line, operationName(text));
    } else if (major == "PARTNO") {
      prog_.part_name = args.empty() ? "" : args[0].text;
    } else if (major == "NURBS" || major == "KNOT" || major == "CNTRL") {
      fail(line, 0, major,
           "NURBS motion is not supported; post the operation with linear (GOTO) output "
           "(in NX: Output Contour Type = Linear)");
    } else if (major == "COPY" || ((major == "TRACUT" || major == "REFSYS") &&
                                   !(args.size() == 1 && toUpper(args[0].text) == "NOMORE"))) {
      // APT's source-level repetition and transformation (ISO 4343: COPY repeats the CL data since
      // its INDEX, TRACUT and REFSYS transform the points that follow until .../NOMORE), which
      // the APT processor expands before it writes CL data: left in a CL file, the copies would
      // be missing and the points untransformed.
      fail(line, 0, major,
           major + " (APT's " +
               (major == "COPY" ? std::string("repetition of the CL data since its INDEX")
                                : std::string("transformation of the points that follow")) +
               ") is not carried out: write the CL data with it expanded");
    } else if ((major == "MODE" || major == "SET") && incrementalMode(args)) {
      fail(line, 0, major,
           major +
               "/...INCR: incremental coordinates are not supported: write the CL data "
               "absolute");
    } else if (major == "FINI" || noOpStatements().count(major) || major.rfind("CSI_", 0) == 0) {
      // recognised; nothing to do for the tool positions
    } else {
      unknownStatement(major);
    }
  }

  // A CAM operation named from this line on.
  void operation(int line, std::string name) {
    if (name.empty()) return;
    if (!prog_.operations.empty() && prog_.operations.back().name == name) return;
    prog_.operations.push_back({line, std::move(name)});
  }

  // GOTO/x,y,z[,i,j,k] (a move, or a cycle's hole) and FROM (the start position).
  void goTo(const std::string& major, const std::vector<Arg>& args, int line, AptStatement& st) {
    std::vector<double>& v = values_;
    numbers(args, major, false, nullptr, &v);
    if (v.size() != 3 && v.size() != 6)
      fail(line, 0, major,
           "takes 3 values (x,y,z) or 6 (x,y,z,i,j,k), found " + std::to_string(v.size()));
    Eigen::Vector3d p(v[0], v[1], v[2]);
    if (v.size() == 6) {
      setAxis(Eigen::Vector3d(v[3], v[4], v[5]), line, args[3].column, major);
      prog_.multiax = true;
    }
    if (major == "FROM") {
      // APT: FROM names where the tool already is (the start, NX's tool change position in
      // the MCS); it is not a move, and the machine's home need not lie in the part's MCS.
      const ClFrame& f = prog_.frames[frame_];
      from_w_ = f.scale * (f.T * p);
      from_line_ = line;
      last_local_ = p;
      have_point_ = true;
      if (!from_noted_) {
        from_noted_ = true;
        prog_.notes.push_back("FROM at line " + std::to_string(line) +
                              " is the start position, not a move: not a point of the path");
      }
    } else if (cycle_.active) {
      cycleMotion(p, line, st);
    } else {
      addMotion(p, line, st);
    }
  }

  // GOHOME: a return to the start position; posts make it the machine's home move (G28, G53).
  void goHome(int line) {
    if (!gohome_noted_) {
      gohome_noted_ = true;
      prog_.notes.push_back("GOHOME at line " + std::to_string(line) +
                            " returns to the start position, which the post makes a home "
                            "move: not a point of the path");
    }
  }

  // CUTCOM/LEFT|RIGHT: noted, the points stay the tool centre.
  void cutcom(const std::vector<Arg>& args, int line) {
    // The points stay the tool centre; a post that writes the part contour for the control's
    // own radius compensation (G41/G42 with the full radius) would be off by the radius.
    const std::string side = args.empty() ? "" : toUpper(args[0].text);
    if ((side == "LEFT" || side == "RIGHT") && !cutcom_noted_) {
      cutcom_noted_ = true;
      prog_.notes.push_back("CUTCOM/" + side + " at line " + std::to_string(line) +
                            ": the points are read as the tool centre (the control adds only "
                            "wear); if the CAM wrote the part contour for the control's radius "
                            "compensation, the path there is off by the tool radius");
    }
  }

  // GODLTA/dx,dy,dz or GODLTA/d (along the tool axis): an incremental move.
  void goDelta(const std::vector<Arg>& args, int line, AptStatement& st) {
    const auto v = numbers(args, "GODLTA", false);
    if (!have_point_) fail(line, 0, "GODLTA", "incremental move before any position");
    Eigen::Vector3d p = last_local_;
    if (v.size() == 3)
      p += Eigen::Vector3d(v[0], v[1], v[2]);
    else if (v.size() == 1)
      p += v[0] * axis_local_;
    else
      fail(line, 0, "GODLTA", "takes 1 or 3 values, found " + std::to_string(v.size()));
    addMotion(p, line, st);
  }

  // TLAXIS/i,j,k.
  void toolAxis(const std::vector<Arg>& args, int line) {
    std::vector<std::string> words;
    const auto v = numbers(args, "TLAXIS", true, &words);
    if (v.size() < 3) fail(line, 0, "TLAXIS", "only TLAXIS/i,j,k is supported");
    setAxis(Eigen::Vector3d(v[0], v[1], v[2]), line, args.empty() ? 0 : args[0].column, "TLAXIS");
  }

  // CIRCLE/MOVARC: the centre and axis of the arc the next GOTO ends (TIMES,n: full turns first).
  void circle(const std::string& major, const std::vector<Arg>& args, int line) {
    std::vector<std::string> words;
    const auto v = numbers(args, major, true, &words);
    if (v.size() < 6)
      fail(line, 0, major,
           "needs the centre and axis (6 values), found " + std::to_string(v.size()));
    if (!have_point_) fail(line, 0, major, "arc before any position");
    const ClFrame& f = prog_.frames[frame_];
    Eigen::Vector3d axis(v[3], v[4], v[5]);
    if (axis.norm() < 1e-12) fail(line, 0, major, "zero-length circle axis");
    // NX: CIRCLE/...,TIMES,n: n full turns before the end point (a helical ramp).
    arc_turns_ = 0;
    for (size_t k = 0; k + 1 < args.size(); ++k)
      if (toUpper(args[k].text) == "TIMES") {
        const auto n = parseNumber(args[k + 1].text);
        if (!n || *n < 0 || *n > 1000 || *n != std::round(*n))
          fail(args[k + 1].line, args[k + 1].column, major, "TIMES takes a whole number of turns");
        arc_turns_ = static_cast<int>(*n);
        if (!times_noted_) {
          times_noted_ = true;
          prog_.notes.push_back("CIRCLE ... TIMES,n (line " + std::to_string(line) +
                                ") read as n full turns before the end point");
        }
      }
    arc_centre_w_ = f.scale * (f.T * Eigen::Vector3d(v[0], v[1], v[2]));
    arc_axis_w_ = f.T.linear() * axis.normalized();
    arc_line_ = line;
    arc_pending_ = true;
  }

  // UNITS/MM|INCHES: the scale of the points that follow.
  void units(const std::string& major, const std::vector<Arg>& args, int line) {
    const std::string u = args.empty() ? "" : toUpper(args[0].text);
    double scale;
    if (u == "MM" || u == "MILLIMETERS" || u == "MILLIMETRES") {
      scale = 1.0;
      prog_.units = "MM";
    } else if (u == "INCH" || u == "INCHES" || u == "IN") {
      scale = 25.4;
      prog_.units = "INCH";
    } else {
      fail(line, args.empty() ? 0 : args[0].column, major,
           "unknown unit '" + (args.empty() ? std::string() : args[0].text) +
               "' (expected MM or INCHES)");
    }
    if (prog_.units_line == 0) prog_.units_line = line;
    prog_.units_declared = true;
    if (opt_.unit_given) {
      const std::string given = opt_.unit_mm == 25.4 ? "INCH" : "MM";
      if (given != prog_.units && prog_.units_in_file.empty()) prog_.units_in_file = prog_.units;
      prog_.units = given;
      scale = opt_.unit_mm;
    }
    ClFrame f = prog_.frames[frame_];
    f.scale = scale;
    pushFrame(f);
  }

  // CUTTER/d,r,e,f,alpha,beta,h: the APT cutter, lengths in the current unit.
  void cutter(const std::vector<Arg>& args, int line) {
    const auto v = numbers(args, "CUTTER", false);
    if (v.empty() || v.size() > 7)
      fail(line, 0, "CUTTER", "takes 1 to 7 values, found " + std::to_string(v.size()));
    CutterSpec c{"CUTTER", "", v, line};
    const double s = prog_.frames[frame_].scale;
    for (size_t k = 0; k < c.values.size(); ++k)
      if (k != 4 && k != 5) c.values[k] *= s;  // alpha, beta are angles
    prog_.cutters.push_back(c);
  }

  // TLDATA/type,values: the tool as CATIA and Creo describe it.
  void toolData(const std::vector<Arg>& args, int line) {
    std::vector<std::string> words;
    const auto v = numbers(args, "TLDATA", true, &words);
    CutterSpec c{"TLDATA", words.empty() ? "" : words[0], v, line};
    const double s = prog_.frames[frame_].scale;
    for (size_t k = 0; k < c.values.size() && k < 3; ++k) c.values[k] *= s;
    // NX's TLDATA/DRILL,MILL,d,r,length,point angle,flute length (the HumMan samples' 63 mm
    // insert drill: 178 deg): swept as the flat end of its diameter, said with the height its
    // point leaves at a hole's bottom (its fourth value is no taper, as TLDATA/MILL's is).
    if (c.kind == "DRILL" && c.values.size() >= 4) {
      const double point_deg = c.values[3];
      c.values.resize(3);
      if (point_deg > 0 && point_deg < 180)
        prog_.notes.push_back(
            "TLDATA/DRILL at line " + std::to_string(line) + ": the drill's point (" +
            formatNumber(point_deg) +
            " deg) is swept as a flat end, so the bottoms of its holes read as gouges up to the "
            "point's height, " +
            formatWith("%.3g", 0.5 * c.values[0] / std::tan(0.5 * degToRad(point_deg))) + " mm");
    }
    prog_.cutters.push_back(c);
  }

  // CSYS/12 values: the frame of the points that follow (rows of [R | t]).
  void csys(const std::vector<Arg>& args, int line) {
    const auto v = numbers(args, "CSYS", false);
    if (v.size() != 12) fail(line, 0, "CSYS", "takes 12 values, found " + std::to_string(v.size()));
    if (trntyp_world_) {
      // SolidWorks CAM: after TRNTYP/WORLD the points stay in world coordinates and CSYS only
      // names the tool plane (a 3+2 orientation); recorded, not applied.
      ++prog_.tool_planes;
      return;
    }
    setFrameFromRows(v, line, "CSYS");
  }

  // MSYS/origin, x axis, y axis: NX's machine coordinate system of the points that follow.
  void msys(const std::vector<Arg>& args, int line) {
    const auto v = numbers(args, "MSYS", false);
    if (v.size() != 9) fail(line, 0, "MSYS", "takes 9 values, found " + std::to_string(v.size()));
    Eigen::Vector3d x(v[3], v[4], v[5]), y(v[6], v[7], v[8]);
    if (x.norm() < 1e-9 || y.norm() < 1e-9 || std::abs(x.normalized().dot(y.normalized())) > 1e-4)
      fail(line, 0, "MSYS", "the x and y axes must be non-zero and perpendicular");
    x.normalize();
    y = (y - x * x.dot(y)).normalized();
    Eigen::Isometry3d abs_T_mcs = Eigen::Isometry3d::Identity();
    abs_T_mcs.linear() << x, y, x.cross(y);
    abs_T_mcs.translation() << v[0], v[1], v[2];
    // NX writes the GOTOs in the MCS the MSYS names. The part frame is the program's first
    // (main) MCS: a later MSYS is a 3+2 set-up relative to it (opt_.absolute_msys: the CAD's
    // absolute frame instead, for a part fixtured in it).
    if (!main_mcs_) main_mcs_ = abs_T_mcs;
    const Eigen::Isometry3d w_T_mcs =
        opt_.absolute_msys ? abs_T_mcs : main_mcs_->inverse() * abs_T_mcs;
    std::vector<double> rows;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) rows.push_back(w_T_mcs.linear()(r, c));
      rows.push_back(w_T_mcs.translation()[r]);
    }
    setFrameFromRows(rows, line, "MSYS");
    if (!opt_.absolute_msys && !first_msys_noted_) {
      first_msys_noted_ = true;
      if ((abs_T_mcs.linear() - Eigen::Matrix3d::Identity()).norm() > 1e-9 ||
          abs_T_mcs.translation().norm() > 1e-9)
        prog_.notes.push_back("MSYS at line " + std::to_string(line) +
                              " is the main MCS: the part frame (--absolute-msys reads the "
                              "points in the CAD's absolute frame instead)");
    }
  }

  // MODE/INCR, SET/MODE,INCR: incremental coordinates from here on.
  static bool incrementalMode(const std::vector<Arg>& args) {
    for (const Arg& a : args)
      if (toUpper(a.text) == "INCR") return true;
    return false;
  }

  // A statement tolver does not know: counted and named in the notes.
  void unknownStatement(const std::string& major) {
    ++prog_.unknown_count;
    const std::string name = major.empty() ? "(blank)" : major;
    if (std::find(prog_.unknown_names.begin(), prog_.unknown_names.end(), name) ==
        prog_.unknown_names.end())
      prog_.unknown_names.push_back(name);
  }

  // CYCLE/<type>, then pairs of a word and its value: FEDTO or DEPTH (depth below the GOTO
  // point, the hole's top), RAPTO or CLEAR (clearance above it, reached in rapid), RTRCTO
  // (retract above it; AUTO or absent: the clearance), peck, dwell and feed words (the motion
  // stays on the hole's axis: STEP, INCR, 1STPECK, SUBPECK, DWELL, MMPM, IPM, MMPR, IPR, REV...).
  // CYCLE/OFF ends it; CYCLE/INIT, /ON and /AUTO set nothing. A bare CYCLE/CLEAR (SolidWorks
  // CAM writes it before a cycle's definition; aamorim1913/AptPostProcessor's clsplit, a post for
  // that CAM's output, moves nothing for it) clears the cycle state: it ends a cycle in force, as
  // OFF does, and says so, since a post that read it as nothing would drill on. The types are
  // those NX, Creo, CATIA and SolidWorks CAM write; another is an error naming it, never skipped.
  void cycleStatement(const std::vector<Arg>& args, int line) {
    if (args.empty()) fail(line, 0, "CYCLE", "CYCLE needs a type or OFF");
    const std::string type = toUpper(args[0].text);
    if (type == "OFF") {
      cycle_.active = false;
      return;
    }
    if (type == "INIT" || type == "ON" || type == "AUTO") return;
    if (type == "CLEAR" && args.size() == 1) {
      if (cycle_.active)
        prog_.notes.push_back("CYCLE/CLEAR at line " + std::to_string(line) + " ended the " +
                              cycle_.type + " cycle of line " + std::to_string(cycle_.line) +
                              " (read as CYCLE/OFF: the GOTOs after it are not holes)");
      cycle_.active = false;
      return;
    }
    static const std::set<std::string> types = {"DRILL",  "DEEP",  "DEEP2", "BRKCHP", "TAP",
                                                "RGDTAP", "BORE",  "BORE1", "BORE2",  "REAM",
                                                "FACE",   "CSINK", "SPOT",  "THRU",   "MILL"};
    if (!types.count(type))
      fail(args[0].line, args[0].column, "CYCLE",
           "the drilling cycle '" + args[0].text +
               "' is not known to tolver (DRILL, DEEP, "
               "DEEP2, BRKCHP, TAP, BORE, REAM are expanded): post it as motion");
    Cycle c;
    c.active = true;
    c.type = type;
    c.line = line;
    bool depth = false, clear = false, retract = false;
    static const std::set<std::string> skipped = {
        "STEP",    "INCR", "1STPECK", "SUBPECK", "DWELL", "MMPM",  "IPM",
        "MMPR",    "IPR",  "FPM",     "FPR",     "REV",   "RPM",   "PECK",
        "MINPECK", "CHIP", "OFFSET",  "ORIENT",  "QUILL", "SHIFT", "TIMES"};
    const double s = 1.0;  // distances in file units; the frame scales them with the point
    for (size_t k = 1; k < args.size(); ++k) {
      const std::string w = toUpper(args[k].text);
      if (looksNumeric(w)) continue;  // a value already taken, or DRILL,DEEP's order
      auto value = [&](double* out) {
        if (k + 1 >= args.size()) fail(args[k].line, args[k].column, "CYCLE", w + " needs a value");
        const std::string vt = toUpper(args[k + 1].text);
        if (vt == "AUTO") {
          ++k;
          return false;
        }
        const auto x = parseNumber(vt);
        if (!x || std::abs(*x) > 1e6)
          fail(args[k + 1].line, args[k + 1].column, "CYCLE",
               w + ": expected a number, found '" + args[k + 1].text + "'");
        *out = *x * s;
        ++k;
        return true;
      };
      if (w == "FEDTO" || w == "DEPTH")
        depth = value(&c.depth);
      else if (w == "RAPTO" || w == "CLEAR")
        clear = value(&c.clearance);
      else if (w == "RTRCTO")
        retract = value(&c.retract);
      else if (skipped.count(w)) {
        if (k + 1 < args.size() && looksNumeric(args[k + 1].text)) ++k;
      } else if (types.count(w)) {
        // DRILL,DEEP: the variant after the type
      } else {
        fail(args[k].line, args[k].column, "CYCLE",
             "unknown cycle parameter '" + args[k].text + "'");
      }
    }
    if (!depth) fail(line, 0, "CYCLE", "the cycle gives no depth (FEDTO or DEPTH)");
    c.depth = std::abs(c.depth);
    if (!clear) c.clearance = 0.0;
    if (!retract) c.retract = c.clearance;
    cycle_ = c;
    ++prog_.cycles;
  }

  // The motions the control makes at a hole while a cycle is in force: to the retract level
  // and the clearance above the GOTO point in rapid, in to the depth along the tool axis, out to
  // the retract level in rapid.
  void cycleMotion(const Eigen::Vector3d& top, int line, AptStatement& st) {
    const Eigen::Vector3d& u = axis_local_;
    const int first = static_cast<int>(prog_.path.size());
    const double up = std::max(cycle_.retract, cycle_.clearance);
    rapid_next_ = true;
    addMotion(top + up * u, line, st);
    if (cycle_.clearance < up) {
      rapid_next_ = true;
      addMotion(top + cycle_.clearance * u, line, st);
    }
    addMotion(top - cycle_.depth * u, line, st);
    rapid_next_ = true;
    addMotion(top + cycle_.retract * u, line, st);
    st.first_point = first;
    st.point_count = static_cast<int>(prog_.path.size()) - first;
    st.cycle = true;
    ++prog_.cycle_holes;
  }

  void setAxis(const Eigen::Vector3d& u, int line, int column, const std::string& field) {
    if (u.norm() < 1e-9) fail(line, column, field, "zero-length tool axis");
    axis_local_ = u.normalized();
  }

  void addMotion(const Eigen::Vector3d& p_file, int line, AptStatement& st) {
    const ClFrame& f = prog_.frames[frame_];
    ClPoint cl;
    cl.p_w = f.scale * (f.T * p_file);
    cl.u_w = f.T.linear() * axis_local_;
    cl.line = line;
    cl.rapid = rapid_next_;
    cl.feed_mm_min = static_cast<float>(feed_mm_min_);
    rapid_next_ = false;
    st.first_point = static_cast<int>(prog_.path.size());
    if (arc_pending_) {
      std::vector<Eigen::Vector3d> pts;
      const ClPoint* before = lastPoint();
      const Eigen::Vector3d start = before ? before->p_w : from_w_;
      const int start_line = before ? before->line : from_line_;
      const double r =
          ((start - arc_centre_w_) - arc_axis_w_ * arc_axis_w_.dot(start - arc_centre_w_)).norm();
      // Bounded work: a full turn's points, before anything is expanded.
      if (!(arcPointsPerTurn(r, opt_.chordal_tolerance_mm) * (arc_turns_ + 1) <= kMaxArcPoints))
        fail(arc_line_, 0, "CIRCLE",
             "an arc of radius " + formatNumber(r) +
                 " mm would expand into more than a million "
                 "points at chordal tolerance " +
                 formatNumber(opt_.chordal_tolerance_mm) +
                 " mm (raise --chordal-tol, or check the radius)");
      if (!interpolateArc(start, cl.p_w, arc_centre_w_, arc_axis_w_, opt_.chordal_tolerance_mm,
                          std::max(0.005, 1e-4 * r), pts, arc_turns_))
        fail(arc_line_, 0, "CIRCLE",
             "the arc's start and end points (lines " + std::to_string(start_line) + " and " +
                 std::to_string(line) + ") are not on one circle about its centre");
      for (size_t k = 0; k + 1 < pts.size(); ++k) {
        ClPoint a = cl;
        a.p_w = pts[k];
        prog_.path.push_back(a);
        prog_.point_frame.push_back(frame_);
      }
      arc_pending_ = false;
      ++prog_.arcs_expanded;
    }
    prog_.path.push_back(cl);
    prog_.point_frame.push_back(frame_);
    st.point_count = static_cast<int>(prog_.path.size()) - st.first_point;
    last_local_ = p_file;
    have_point_ = true;
  }

  const AptReadOptions& opt_;
  LineSource& source_;
  const ProgramBlocks* blocks_;  // or nullptr: the whole program at once
  Logical lg_;                   // the statement being read (gather)
  std::vector<Arg> args_;        // its arguments (splitArgs)
  std::vector<double> values_;   // a GOTO's numbers
  ClPoint last_passed_;          // the last point passed on
  bool passed_any_ = false;
  size_t down_ = 0, down_counted_ = 0, read_ = 0;  // points down, counted, read
  std::deque<std::string> window_;                 // lines read but not yet in prog_.lines
  std::vector<std::string> spare_;                 // strings of lines passed on, for reuse
  size_t window_first_ = 0;                        // the 0-based number of window_.front()
  bool at_end_ = false;
  ClProgram prog_;
  int frame_ = 0;
  Eigen::Vector3d axis_local_ = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d last_local_ = Eigen::Vector3d::Zero();
  bool have_point_ = false;
  bool rapid_next_ = false;
  double feed_mm_min_ = NAN, spindle_rpm_ = NAN;

  // FEDRAT/f[,MMPM|IPM|MMPR|IPR] (the unit before or after the value): per minute in the file's
  // unit when none is given; per revolution through the last SPINDL speed; INVERS (inverse time)
  // and per revolution without a speed leave the feed unknown.
  void feedRate(double f, const std::vector<std::string>& words) {
    const double unit = prog_.frames[frame_].scale;
    feed_mm_min_ = std::abs(f) * unit;
    for (const std::string& w : words) {
      if (w == "MMPM") feed_mm_min_ = std::abs(f);
      if (w == "IPM") feed_mm_min_ = std::abs(f) * 25.4;
      if (w == "MMPR") feed_mm_min_ = std::abs(f) * spindle_rpm_;
      if (w == "IPR") feed_mm_min_ = std::abs(f) * 25.4 * spindle_rpm_;
      if (w == "INVERS") feed_mm_min_ = NAN;
    }
    if (!(feed_mm_min_ > 0)) feed_mm_min_ = NAN;
  }
  bool trntyp_world_ = false;
  bool arc_pending_ = false;
  int arc_turns_ = 0;
  std::optional<Eigen::Isometry3d> main_mcs_;  // the first MSYS: the part frame
  bool first_msys_noted_ = false, times_noted_ = false, from_noted_ = false, gohome_noted_ = false;
  bool cutcom_noted_ = false;
  Eigen::Vector3d from_w_ = Eigen::Vector3d::Zero();
  int from_line_ = 0;  // FROM's line: an arc's start when no point precedes it
  // A CL drilling cycle in force (CYCLE/<type>,... until CYCLE/OFF): its type and distances
  // along the tool axis from each GOTO point (the hole's top), mm in file units.
  struct Cycle {
    bool active = false;
    std::string type;
    double depth = 0.0, clearance = 0.0, retract = 0.0;
    int line = 0;
  } cycle_;
  int arc_line_ = 0;
  Eigen::Vector3d arc_centre_w_, arc_axis_w_;
};

}  // namespace

const std::string& operationAt(const std::vector<ProgramOperation>& operations, int line) {
  static const std::string none;
  auto it = std::upper_bound(operations.begin(), operations.end(), line,
                             [](int l, const ProgramOperation& o) { return l < o.line; });
  return it == operations.begin() ? none : std::prev(it)->name;
}

std::vector<int> ClProgram::toolOfPoints() const {
  std::vector<int> tool;
  if (cutters.size() <= 1) return tool;
  tool.resize(path.size());
  size_t t = 0;
  for (size_t i = 0; i < path.size(); ++i) {
    while (t + 1 < cutters.size() && cutters[t + 1].line < path[i].line) ++t;
    tool[i] = static_cast<int>(t);
  }
  return tool;
}

ClProgram readApt(LineSource& source, const std::string& file_name, const AptReadOptions& options) {
  return Parser(source, file_name, options, nullptr).run();
}

ClProgram readApt(LineSource& source, const std::string& file_name, const AptReadOptions& options,
                  const ProgramBlocks& blocks) {
  return Parser(source, file_name, options, &blocks).run();
}

ClProgram parseApt(const std::string& text, const std::string& file_name,
                   const AptReadOptions& options) {
  LineSource source(text);
  return readApt(source, file_name, options);
}

ClProgram readAptFile(const std::string& path, const AptReadOptions& options) {
  LineSource source = LineSource::file(path);
  return readApt(source, path, options);
}

}  // namespace tolver
