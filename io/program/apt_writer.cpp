#include "io/program/apt_writer.h"

#include <cassert>
#include <cstdio>

#include "io/common/text_util.h"

namespace tolver {

std::string formatPredictedApt(const ClProgram& program, const std::vector<ClPoint>& predicted,
                               const std::vector<std::string>& header) {
  TextOut out;
  writePredictedApt(out, program, predicted, header);
  return out.take();
}

void writePredictedApt(TextOut& out, const ClProgram& program,
                       const std::vector<ClPoint>& predicted,
                       const std::vector<std::string>& header) {
  assert(predicted.size() == program.path.size());
  writePredictedAptStart(out, program, header);
  writePredictedAptStatements(out, program, predicted);
  writePredictedAptEnd(out, program);
}

void writePredictedAptStart(TextOut& out, const ClProgram& program,
                            const std::vector<std::string>& header) {
  for (const std::string& h : header) out += "$$ " + h + "\n";
  if (program.dialect == "G-code") {
    // A G-code program becomes plain CL data in mm, in the part frame: one GOTO per point,
    // RAPID before positioning moves, the source line in a comment.
    out += "UNITS/MM\nMULTAX/ON\n";
    return;
  }
  // A program read in inches without a UNITS statement (--cl-units inch) says so, or the
  // written inches would read back as millimetres.
  if (program.units == "INCH" && !program.units_declared) out += "UNITS/INCHES\n";
  // The user's unit over the file's UNITS (--cl-units): the statement is copied as it stands
  // and the numbers stay as written, so the file reads back only with the same option.
  if (!program.units_in_file.empty())
    out += "$$ the numbers are in " + std::string(program.units == "INCH" ? "inches" : "mm") +
           ", not as UNITS at line " + std::to_string(program.units_line) +
           " declares: read this file with --cl-units " +
           (program.units == "INCH" ? "inch" : "mm") + "\n";
  if (!program.multiax) out += "MULTAX/ON\n";
}

void writePredictedAptEnd(TextOut& out, const ClProgram& program) {
  if (program.dialect == "G-code") out += "FINI\n";
}

void writePredictedAptStatements(TextOut& out, const ClProgram& program,
                                 const std::vector<ClPoint>& predicted) {
  LineBuilder line;
  // GOTO/x,y,z,i,j,k: the point with `decimals`, the unit axis with 9.
  auto gotoLine = [&](const char* word, const Eigen::Vector3d& p, const Eigen::Vector3d& u,
                      int decimals) {
    line.clear();
    line.text(word).character('/').fixed(p.x(), decimals).character(',');
    line.fixed(p.y(), decimals).character(',').fixed(p.z(), decimals).character(',');
    line.fixed(u.x(), 9).character(',').fixed(u.y(), 9).character(',').fixed(u.z(), 9);
    line.character('\n');
    out += line.view();
  };
  if (program.dialect == "G-code") {
    for (const AptStatement& st : program.statements) {
      if (st.point_count <= 0) continue;
      line.clear();
      line.text("$$ line ").integer(st.first_line).character('\n');
      out += line.view();
      for (int k = st.first_point; k < st.first_point + st.point_count; ++k) {
        if (program.path[k].rapid) out += "RAPID\n";
        const Eigen::Vector3d& p = predicted[k].p_w;
        const Eigen::Vector3d u = predicted[k].u_w.normalized();
        gotoLine("GOTO", p, u, 6);
      }
    }
    return;
  }
  const bool inch = program.units == "INCH";
  for (const AptStatement& st : program.statements) {
    if (st.point_count > 0) {
      const char* word = st.major == "FROM" ? "FROM" : "GOTO";
      for (int k = st.first_point; k < st.first_point + st.point_count; ++k) {
        // A drilling cycle's hole becomes its motions: RAPID before each positioning one.
        if (st.point_count > 1 && program.path[k].rapid) out += "RAPID\n";
        const ClFrame& f = program.frames[program.point_frame[k]];
        const Eigen::Vector3d p = f.T.inverse(Eigen::Isometry) * (predicted[k].p_w / f.scale);
        const Eigen::Vector3d u = f.T.linear().transpose() * predicted[k].u_w.normalized();
        gotoLine(word, p, u, inch ? 8 : 6);
      }
      continue;
    }
    // A motion statement without points lies outside the lines predicted (--lines): left out.
    if (st.major == "GOTO" && st.point_count == 0) continue;
    if (st.major == "CIRCLE" || st.major == "MOVARC" || st.major == "CYCLE") {
      out += "$$ tolver: " + st.major + " of line " + std::to_string(st.first_line) +
             " expanded into the GOTO points that follow\n";
      continue;
    }
    for (int l = st.first_line; l <= st.last_line; ++l) {
      out += program.lines[l - 1];
      out += '\n';
    }
  }
}

}  // namespace tolver
