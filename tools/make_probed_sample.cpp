// Writes samples/matsuura_probed.csv: touches of a probe (the set-up's gauge length) on the cone
// sample's part, on the measured Matsuura (samples/machines/matsuura_mc760vx_measured.xml) with the
// cone's set-up: at 12 of the program's poses, the point where that machine really puts the
// probe tip (the part sits there), with the joint values the control recorded; and a spindle
// tram (that machine's tool axis against its table) at the first touch's place.
// Usage: make_probed_sample <source dir>
#include <cstdio>
#include <string>

#include "core/path/tool_path_prediction.h"
#include "io/common/io_error.h"
#include "io/machine/machine_file.h"
#include "io/program/apt_reader.h"
#include "io/program/probe_file.h"
#include "io/program/setup_file.h"

using namespace tolver;

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_probed_sample <source dir>\n");
    return 2;
  }
  const std::string src = argv[1];
  Machine truth = readMachineFile(src + "/samples/machines/matsuura_mc760vx_measured.xml");
  truth.model.setup = readSetupFile(src + "/samples/matsuura_setup.txt", truth.model.setup);
  const ClProgram program = readAptFile(src + "/samples/nas979_cone.apt");
  const PredictionResult pr = predictToolPath(truth.model, truth.params, program.path);
  if (!pr.ok()) return 1;
  std::vector<ProbedPoint> probes;
  for (size_t i = 0; i < pr.points.size(); i += pr.points.size() / 12) {
    ProbedPoint p;
    p.q = pr.points[i].q;
    p.p_w = pr.points[i].p_pred_w;
    p.probe_length = truth.model.setup.gauge_length;
    probes.push_back(p);
  }
  // A spindle tram at the first touch's place, rotaries at zero: that machine's tool axis
  // against its table.
  JointVector q = probes.front().q;
  q.tail<2>().setZero();
  probes.push_back(simulatedTram(truth, q));
  writeFileAtomically(
      src + "/samples/matsuura_probed.csv",
      "# touches on the cone sample's part (samples/nas979_cone.apt, matsuura_setup.txt)\n"
      "# made by tools/make_probed_sample from the measured Matsuura: the part point\n"
      "# the probe tip touched (part frame) and the joint values recorded; the last\n"
      "# row is a spindle tram: the tool axis against the table at its joints (urad)\n" +
          formatProbeCsv(truth.model, probes));
  return 0;
}
