#pragma once
// What every command's library function shares: its verdict and its progress callback.
//
// A command is one function, `XxxRun runXxx(const XxxInputs&, ...)` (pipeline/<command>.h):
// typed, validated inputs in (plain values in the units their names give; an invalid one throws
// FieldError naming the input's field, a bad file InputError naming the file, line and field), a
// typed result out (figures, written paths, a Verdict), no printing. The CLI (app/) maps options
// to fields, prints the result, and turns the verdict into the exit code in one place.
#include <functional>
#include <string>

namespace tolver {

enum class Verdict {
  Ok,         // done; verify: in tolerance; setup: one set-up reaches the whole program
  NotMet,     // verify: out of tolerance or incomplete; setup: no single set-up reaches the
              // program; calibrate: the fit did not converge
  Undecided,  // verify on a calibrated machine: a zone limit lies within the prediction's band
  BadInput,   // verify --batch: a job's inputs were refused (the others ran)
};

// "ok", "not met", "undecided", "bad input".
const char* verdictName(Verdict v);
// The exit code of a verdict: 0 ok, 1 not met, 2 bad input, 4 undecided (3 is an internal
// error, no verdict). The one mapping: the CLI exits with it, verify's report.json states it.
int exitCode(Verdict v);
// The worse of two verdicts (a batch's): bad input, then not met, then undecided, then ok.
Verdict worse(Verdict a, Verdict b);

// Progress of long work: the phase and the fraction of it done (0..1).
using Progress = std::function<void(const std::string& phase, double fraction)>;

}  // namespace tolver

namespace tolver {

// The name a user knows an input by, in messages that name another input ("give {units} inch"):
// the CLI registers its options (app/common.cpp) so that the library never spells one; without
// a registration an input is named by its field ("units"). Register once, before the command
// runs (not thread-safe against a running command).
using InputNamer = std::function<std::string(const std::string& field)>;
void setInputNamer(InputNamer namer);
std::string inputName(const std::string& field);

}  // namespace tolver
