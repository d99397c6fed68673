// libFuzzer harnesses for tolver's readers (one binary per reader, chosen by TOLVER_FUZZ_TARGET at
// compile time; built by the sanitizer build with TOLVER_FUZZ=ON, run by tests/fuzz/run.sh). Each
// feeds the bytes to a reader as a file's text: an InputError is the expected answer to bad input;
// anything else (a crash, a sanitizer report, another exception, a hang) is a defect.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "io/common/io_error.h"
#include "io/machine/ballbar_file.h"
#include "io/machine/machine_file.h"
#include "io/machine/tolerance_file.h"
#include "io/machine/zone_file.h"
#include "io/mesh/mesh_file.h"
#include "io/program/apt_reader.h"
#include "io/program/gcode_reader.h"
#include "io/program/jobs_file.h"
#include "io/program/measured_points.h"
#include "io/program/probe_file.h"
#include "io/program/process_file.h"
#include "io/program/setup_file.h"

namespace {

const tolver::Machine& machine() {
  static const tolver::Machine m = [] {
    tolver::Machine x = tolver::readMachineFile(std::string(TOLVER_SOURCE_DIR) +
                                                "/resources/machines/linuxcnc_xyzac_trt.xml");
    x.model.setup.gauge_length = 50;
    return x;
  }();
  return m;
}

// The test a ball-positions file is matched to: the sample plan's set-ups.
const tolver::BallbarTest& samplePlan() {
  static const tolver::BallbarTest t =
      tolver::readBallbarFile(std::string(TOLVER_SOURCE_DIR) + "/samples/ballbar/plan.csv",
                              tolver::readMachineFile(std::string(TOLVER_SOURCE_DIR) +
                                                      "/resources/machines/matsuura_mc760vx.xml")
                                  .model,
                              false)
          .test;
  return t;
}

const tolver::Machine& isoVmc() {
  static const tolver::Machine m = tolver::readMachineFile(std::string(TOLVER_SOURCE_DIR) +
                                                           "/resources/machines/vmc_3axis_iso.xml");
  return m;
}

const tolver::Machine& sinumerik() {
  static const tolver::Machine m = tolver::readMachineFile(
      std::string(TOLVER_SOURCE_DIR) + "/resources/machines/sinumerik_bc_table.xml");
  return m;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
#if TOLVER_FUZZ_TARGET == 1
    tolver::parseApt(text, "fuzz.apt");
#elif TOLVER_FUZZ_TARGET == 2
    // Each text as a LinuxCNC program (O-words), an ISO one and a Sinumerik 840D one (DEF,
    // assignments, frames, cycles: issue 32). Loops bounded lower than a user's (a loop that
    // moves on for the million passes a program may run took 6 s released, minutes here, where
    // an input has 10 s); the bounds themselves are tested (GcodeReader tests).
    tolver::GcodeReadOptions bounded;
    bounded.max_loop_passes = 5000;
    bounded.max_flow_lines = 50000;
    try {
      tolver::parseGcode(text, "fuzz.nc", machine().model, bounded);
    } catch (const tolver::InputError&) {
    }
    try {
      tolver::parseGcode(text, "fuzz.nc", isoVmc().model, bounded);  // M98/M97 subprograms, G92
    } catch (const tolver::InputError&) {
    }
    tolver::parseGcode(text, "fuzz.mpf", sinumerik().model, bounded);
#elif TOLVER_FUZZ_TARGET == 3
    tolver::parseMachineXml(text, "fuzz.xml");
#elif TOLVER_FUZZ_TARGET == 4
    tolver::parseSetup(text, "fuzz.txt", machine().model.setup);
#elif TOLVER_FUZZ_TARGET == 5
    tolver::parseBallbarCsv(text, "fuzz.csv", machine().model, false);
#elif TOLVER_FUZZ_TARGET == 6
    tolver::parseZoneCsv(text, "fuzz.csv");
#elif TOLVER_FUZZ_TARGET == 7
    tolver::parseToleranceCsv(text, "fuzz.csv", machine().model);
#elif TOLVER_FUZZ_TARGET == 8
    tolver::parseProbeCsv(text, "fuzz.csv", machine().model);
#elif TOLVER_FUZZ_TARGET == 9
    tolver::parseJobsCsv(text, "fuzz/jobs.csv");
#elif TOLVER_FUZZ_TARGET == 10
    // The mesh loader reads a path (assimp picks the format by extension and content): the first
    // byte chooses STL, OBJ, PLY or OFF, the rest is the file; then units and repair as verify
    // runs.
    if (size < 1) return 0;
    static const char* ext[4] = {".stl", ".obj", ".ply", ".off"};
    const std::string path = "/tmp/tolver-fuzz-" + std::to_string(::getpid()) + ext[data[0] % 4];
    if (std::FILE* f = std::fopen(path.c_str(), "wb")) {
      std::fwrite(data + 1, 1, size - 1, f);
      std::fclose(f);
    }
    tolver::PartImportOptions o;
    o.units = data[0] & 4 ? "inch" : "mm";
    tolver::readPartMesh(path, o);
#elif TOLVER_FUZZ_TARGET == 11
    // The scene formats of the same loader: the first byte chooses glTF binary, glTF text or 3MF
    // (a zip), the rest is the file (tests/fuzz/scene_corpus: a cube exported by assimp).
    if (size < 1) return 0;
    static const char* ext[3] = {".glb", ".gltf", ".3mf"};
    const std::string path = "/tmp/tolver-fuzz-" + std::to_string(::getpid()) + ext[data[0] % 3];
    if (std::FILE* f = std::fopen(path.c_str(), "wb")) {
      std::fwrite(data + 1, 1, size - 1, f);
      std::fclose(f);
    }
    tolver::readPartMesh(path, tolver::PartImportOptions{});
#elif TOLVER_FUZZ_TARGET == 12
    // The ball positions calibrate writes and simulate-ballbar --balls reads.
    tolver::parseBallPositionsCsv(text, "fuzz_balls.csv", samplePlan());
#elif TOLVER_FUZZ_TARGET == 13
    // A measured part's points (CSV or ASC) and the process corrections measure writes.
    try {
      tolver::parseMeasuredPoints(text, "fuzz_points.csv");
    } catch (const tolver::InputError&) {
    }
    tolver::parseProcessFile(text, "fuzz_process.txt");
#endif
  } catch (const tolver::InputError&) {
  }
  return 0;
}
