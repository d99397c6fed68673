#pragma once
// Writer of a predicted CL file: the source program with every tool position replaced by its
// predicted one, in the source's units and coordinate system, so that this reader and a CAM
// system read it back. Arcs (CIRCLE, MOVARC) become the points they were expanded into.
#include <string>
#include <vector>

#include "io/common/io_error.h"
#include "io/program/apt_reader.h"

namespace tolver {

// predicted: one point per program.path entry (positions and unit axes in w, mm).
// header: comment lines (without the leading "$$ ") written at the top.
std::string formatPredictedApt(const ClProgram& program, const std::vector<ClPoint>& predicted,
                               const std::vector<std::string>& header);
// The same, written in pieces (into a file as it is made).
void writePredictedApt(TextOut& out, const ClProgram& program,
                       const std::vector<ClPoint>& predicted,
                       const std::vector<std::string>& header);
// The same in three parts, for a program read in blocks (io/program/apt_reader.h, ProgramBlocks):
// the start with the first block, the statements of each block (predicted: one per block point),
// the end with the last.
void writePredictedAptStart(TextOut& out, const ClProgram& program,
                            const std::vector<std::string>& header);
void writePredictedAptStatements(TextOut& out, const ClProgram& program,
                                 const std::vector<ClPoint>& predicted);
void writePredictedAptEnd(TextOut& out, const ClProgram& program);

}  // namespace tolver
