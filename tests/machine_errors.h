#pragma once
// A copy of a machine file with random errors, for tests that need a machine to compensate:
// every coefficient but the set-up's drawn from N(0, (5 um / 4)^2) or N(0, (20 urad / 4)^2).
// Needs tolver::io.
#include <random>
#include <string>

#include "io/common/io_error.h"
#include "io/machine/machine_file.h"

namespace tolver::test {

inline void writeMachineWithErrors(const std::string& machine, unsigned seed,
                                   const std::string& out) {
  Machine m = readMachineFile(machine);
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < m.model.parameterCount(); ++i) {
    const BlockKind kind = m.model.blocks[m.model.parameters[i].block].kind;
    if (kind != BlockKind::WorkpieceSetup && kind != BlockKind::ToolSetup)
      m.params[i] = n(rng) * (m.model.parameters[i].angular ? 20e-6 : 0.005) / 4;
  }
  writeFileAtomically(out, formatMachineXml(m, "random errors for a test"));
}

}  // namespace tolver::test
