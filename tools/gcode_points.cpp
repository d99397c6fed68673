// Prints the points tolver's G-code reader makes of a program, one per line: the source line,
// then the joint values (mm, deg; the machine file's axes in its order). For checking the reader
// against a control's own interpreter (LinuxCNC's rs274 prints its canonical moves the same way:
// tests/interp/*/expected). Not part of the tolver program.
//   gcode_points MACHINE.xml PROGRAM.ngc
#include <cmath>
#include <cstdio>
#include <exception>

#include "io/common/io_error.h"
#include "io/machine/machine_file.h"
#include "io/program/gcode_reader.h"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: gcode_points MACHINE.xml PROGRAM\n");
    return 2;
  }
  try {
    const tolver::Machine m = tolver::readMachineFile(argv[1]);
    const tolver::ClProgram p = tolver::readGcodeFile(argv[2], m.model);
    for (size_t i = 0; i < p.path.size(); ++i) {
      std::printf("%d", p.path[i].line);
      for (size_t a = 0; a < m.model.axes.size(); ++a) {
        const double q = p.joints[i][static_cast<int>(a)];
        std::printf(" %.6f", m.model.axes[a].isRotary() ? q * 180.0 / M_PI : q);
      }
      std::printf("\n");
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  return 0;
}
