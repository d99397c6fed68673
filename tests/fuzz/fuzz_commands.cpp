// libFuzzer harness for the commands themselves (pipeline/<command>.h), past the readers: the
// bytes choose a valid-but-extreme machine (2 to 9 axes; prismatic and rotary; parallel, oblique,
// tiny and zero directions; zero, huge and ordinary travels; link offsets and errors from the
// ordinary to the absurd), a program (APT or G-code: numbers at the limits and with exponents,
// arcs, helices, drilling cycles, tool axes near zero), a tolerance or zone file at its limits,
// and a command (predict, compensate, verify in CL-only mode, analyze, plan-ballbar then
// simulate-ballbar then calibrate, setup), and run it in-process under the sanitizers. An
// InputError (a FieldError included) is the expected answer to what tolver cannot do; any other
// exception, a crash, a sanitizer report, a hang past libFuzzer's -timeout (tests/fuzz/run.sh
// gives this harness 30 s: about 1 s of a released build) or memory past -rss_limit_mb (2 GB) is
// a defect. Run it with tests/fuzz/run.sh (name "commands").
#include <fuzzer/FuzzedDataProvider.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "io/common/io_error.h"
#include "pipeline/analyze.h"
#include "pipeline/ballbar.h"
#include "pipeline/calibrate.h"
#include "pipeline/compensate.h"
#include "pipeline/predict.h"
#include "pipeline/setup.h"
#include "pipeline/verify.h"

namespace {

namespace fs = std::filesystem;

// A number from a list of the ordinary and the extreme, or any double the bytes make.
double extreme(FuzzedDataProvider& in, double ordinary) {
  static const double picks[] = {0.0,   -0.0, 1e-300, 1e-12,  1e-6,   0.5,     1.0,  -1.0,
                                 89.99, 90.0, 180.0,  -180.0, 359.99, 1e4,     1e5,  -1e5,
                                 1e6,   1e9,  1e15,   -1e300, 1e300,  123.456, 25.4, 1e-3};
  // Mostly the ordinary value, so that most inputs pass the readers and reach the command.
  switch (in.ConsumeIntegralInRange<int>(0, 7)) {
    case 0:
    case 1:
    case 2:
    case 3:
    case 4:
      return ordinary;
    case 5:
      return picks[in.ConsumeIntegralInRange<size_t>(0, std::size(picks) - 1)];
    case 6:
      return in.ConsumeFloatingPointInRange<double>(-1e3, 1e3);
    default:
      return in.ConsumeFloatingPoint<double>();  // may be inf or nan: the writer prints them
  }
}

// Written with %.17g so the file holds the double the harness chose (nan and inf as text, which
// the readers must refuse).
std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string direction(FuzzedDataProvider& in, int axis_index) {
  static const char* dirs[] = {"1 0 0",  "0 1 0",    "0 0 1",      "-1 0 0",
                               "0 0 -1", "1 1 0",    "0.6 0 0.8",  "1e-12 0 1",
                               "0 0 0",  "1 1e-9 0", "1e-300 0 0", "0.7071 0.7071 0"};
  if (in.ConsumeBool()) return dirs[axis_index % 3];  // the usual X Y Z
  if (in.ConsumeBool()) return dirs[in.ConsumeIntegralInRange<size_t>(0, std::size(dirs) - 1)];
  return num(extreme(in, 1)) + " " + num(extreme(in, 0)) + " " + num(extreme(in, 0));
}

// A machine file: three prismatic axes on the tool side and up to six more axes anywhere (or
// fewer), with travels, link offsets and a few errors chosen by the bytes.
std::string machineXml(FuzzedDataProvider& in) {
  const int n = in.ConsumeIntegralInRange<int>(2, 9);
  static const char* names[] = {"X", "Y", "Z", "A", "B", "C", "U", "V", "W"};
  std::string xml =
      "<?xml version=\"1.0\"?>\n<machine name=\"fuzz\" length_unit=\"mm\" angle_unit=\"deg\">\n";
  for (int a = 0; a < n; ++a) {
    const bool rotary = a >= 3 ? !in.ConsumeBool() || a < 5 : in.ConsumeIntegralInRange(0, 7) == 0;
    const bool tool = a < 3 ? in.ConsumeIntegralInRange(0, 5) != 0 : in.ConsumeBool();
    const double lo = extreme(in, rotary ? -120.0 : -500.0);
    const double hi =
        in.ConsumeIntegralInRange(0, 7) == 0 ? lo : extreme(in, rotary ? 120.0 : 500.0);
    xml += std::string("  <axis name=\"") + names[a] + "\" type=\"" +
           (rotary ? "rotary" : "prismatic") + "\" branch=\"" + (tool ? "tool" : "workpiece") +
           "\" direction=\"" + direction(in, a) + "\" min=\"" + num(std::min(lo, hi)) +
           "\" max=\"" + num(std::max(lo, hi)) + "\" nc_sign=\"" + (in.ConsumeBool() ? "1" : "-1") +
           "\"" + (rotary && in.ConsumeIntegralInRange(0, 5) == 0 ? " endless=\"true\"" : "");
    if (in.ConsumeBool()) {
      xml += ">\n    <link translation=\"" + num(extreme(in, 0)) + " " + num(extreme(in, 20)) +
             " " + num(extreme(in, 10)) + "\" rotation=\"0 0 " + num(extreme(in, 0)) +
             "\"/>\n  </axis>\n";
    } else {
      xml += "/>\n";
    }
  }
  xml += "  <table translation=\"0 0 " + num(extreme(in, 0)) + "\" rotation=\"0 0 0\"/>\n";
  xml += "  <spindle translation=\"0 0 0\" rotation=\"0 0 0\"/>\n";
  xml += "  <control name=\"fuzz\" default_units=\"mm\" dialect=\"linuxcnc\">\n";
  xml += "    <tcp on=\"M428\" off=\"M429\"/>\n  </control>\n";
  xml += "  <errors source=\"simulated\" length_unit=\"um\" angle_unit=\"urad\" default_degree=\"" +
         std::to_string(in.ConsumeIntegralInRange(0, 2)) + "\">\n";
  static const char* comps[] = {"ex", "ey", "ez", "gx", "gy", "gz"};
  for (int e = in.ConsumeIntegralInRange(0, 4); e > 0; --e) {
    const char* axis = names[in.ConsumeIntegralInRange(0, n - 1)];
    const char* comp = comps[in.ConsumeIntegralInRange(0, 5)];
    if (in.ConsumeBool())
      xml += std::string("    <link axis=\"") + axis + "\" component=\"" + comp + "\" value=\"" +
             num(extreme(in, 10)) + "\"/>\n";
    else
      xml += std::string("    <motion axis=\"") + axis + "\" component=\"" + comp +
             "\" coefficients=\"0 " + num(extreme(in, 5)) + " " + num(extreme(in, -2)) + "\"/>\n";
  }
  xml += "  </errors>\n</machine>\n";
  return xml;
}

std::string aptProgram(FuzzedDataProvider& in) {
  std::string p = in.ConsumeBool() ? "UNITS/MM\n" : "UNITS/INCHES\n";
  p += "MULTAX/ON\n";
  for (int k = in.ConsumeIntegralInRange(1, 24); k > 0; --k) {
    switch (in.ConsumeIntegralInRange(0, 7)) {
      case 0:
      case 1:
      case 2:
        p += "GOTO/" + num(extreme(in, 10)) + "," + num(extreme(in, 5)) + "," +
             num(extreme(in, 2)) + "," + num(extreme(in, 0)) + "," + num(extreme(in, 0.2)) + "," +
             num(extreme(in, 1)) + "\n";
        break;
      case 3:
        p += "RAPID\nGOTO/" + num(extreme(in, 0)) + "," + num(extreme(in, 0)) + "," +
             num(extreme(in, 50)) + "\n";
        break;
      case 4:
        p += "CIRCLE/" + num(extreme(in, 0)) + "," + num(extreme(in, 0)) + "," +
             num(extreme(in, 0)) + ",0,0,1," + num(extreme(in, 5)) + "\n";
        break;
      case 5:
        p += "CYCLE/DRILL,FEDTO," + num(extreme(in, 5)) + ",RAPTO," + num(extreme(in, 2)) +
             ",MMPM,100\n";
        break;
      case 6:
        p += "CYCLE/OFF\n";
        break;
      default:
        p += "TLAXIS/" + num(extreme(in, 0)) + "," + num(extreme(in, 0)) + "," +
             num(extreme(in, 1)) + "\n";
        break;
    }
  }
  return p + "FINI\n";
}

std::string gcodeProgram(FuzzedDataProvider& in) {
  std::string p = in.ConsumeBool() ? "G21 G90 G17\n" : "G20 G91\n";
  if (in.ConsumeBool()) p += "M428\n";  // the TCP words of the harness's control
  if (in.ConsumeBool()) p += "G43 H1\n";
  static const char* motion[] = {"G0", "G1", "G2", "G3", "G81", "G83", "G80", "G54"};
  static const char letters[] = {'X', 'Y', 'Z', 'A', 'B', 'C', 'I', 'J', 'K', 'R', 'Q'};
  for (int k = in.ConsumeIntegralInRange(1, 24); k > 0; --k) {
    p += motion[in.ConsumeIntegralInRange<size_t>(0, std::size(motion) - 1)];
    for (int w = in.ConsumeIntegralInRange(0, 5); w > 0; --w) {
      const char l = letters[in.ConsumeIntegralInRange<size_t>(0, std::size(letters) - 1)];
      const double v = extreme(in, 10);
      char buf[48];
      std::snprintf(buf, sizeof buf, in.ConsumeBool() ? " %c%.6f" : " %c%.4g", l, v);
      p += buf;  // %.4g writes exponents (1e+05): the reader must refuse the E word
    }
    p += "\n";
  }
  return p + "M2\n";
}

void write(const std::string& path, const std::string& text) {
  if (std::FILE* f = std::fopen(path.c_str(), "wb")) {
    std::fwrite(text.data(), 1, text.size(), f);
    std::fclose(f);
  }
}

void runCommand(FuzzedDataProvider& in, const std::string& dir) {
  const std::string machine_path = dir + "/m.xml";
  write(machine_path, machineXml(in));
  tolver::MachineOptions machine;
  machine.machine = machine_path;
  if (in.ConsumeBool()) machine.gauge_length = extreme(in, 100);
  if (in.ConsumeBool()) machine.part_zero = {extreme(in, 0), extreme(in, 0), extreme(in, 50)};
  if (in.ConsumeBool()) machine.part_rotation_deg = extreme(in, 0);
  tolver::ProgramOptions program;
  const bool gcode = in.ConsumeBool();
  program.cl = dir + (gcode ? "/p.ngc" : "/p.apt");
  write(program.cl, gcode ? gcodeProgram(in) : aptProgram(in));
  program.chordal_tolerance = in.ConsumeBool() ? 0.001 : extreme(in, 0.01);
  const int command = in.ConsumeIntegralInRange(0, 6);
  if (std::getenv("TOLVER_FUZZ_VERBOSE")) {
    std::fprintf(stderr, "command %d on %s (kept in %s.last)\n", command, machine_path.c_str(),
                 machine_path.c_str());
    fs::copy_file(machine_path, machine_path + ".last", fs::copy_options::overwrite_existing);
    fs::copy_file(program.cl, program.cl + ".last", fs::copy_options::overwrite_existing);
  }
  switch (command) {
    case 0: {
      tolver::PredictInputs p;
      p.machine = machine;
      p.program = program;
      p.output = dir + "/out.apt";
      p.max_rotary_step_deg = extreme(in, 10);
      tolver::predict(p);
      break;
    }
    case 1: {
      tolver::CompensateInputs c;
      c.machine = machine;
      c.program = program;
      c.output = dir + (gcode ? "/out.ngc" : "/out.apt");
      c.max_condition = extreme(in, 1e6);
      tolver::compensateProgram(c);
      break;
    }
    case 2: {
      tolver::VerifyInputs v;
      v.machine = machine;
      v.program = program;
      if (in.ConsumeBool()) {
        v.tolerance_mm = extreme(in, 0.03);
      } else {
        // A zone file: a bilateral zone, an ISO UZ or an ASME U offset, at the limits.
        const double uz = extreme(in, 0.005);
        v.zones_file = dir + "/zones.csv";
        write(v.zones_file, "region,tolerance,uz,u\n*," + num(extreme(in, 0.05)) + "," +
                                (in.ConsumeBool() ? num(uz) + "," : "," + num(uz)) + "\n");
      }
      v.tolerance_confirmed = in.ConsumeBool();
      v.report_dir = dir + "/report";
      v.images = false;
      tolver::verifyPart(v);
      break;
    }
    case 3: {
      tolver::AnalyzeInputs a;
      a.machine = machine;
      a.model = in.ConsumeBool() ? "link" : "motion";
      // Sizes within what the instrumented build analyses inside the 30 s budget (a 7-axis
      // degree-4 analysis takes 5 s released, 65 s under ASan and coverage: the minimal-set
      // search is cubic in the parameters, issue 36): the harness explores shapes, not sizes.
      a.degree = in.ConsumeIntegralInRange(0, 2);
      a.poses = in.ConsumeIntegralInRange(1, 40);
      tolver::analyze(a);
      break;
    }
    case 4: {
      // The metrologist's chain: a small plan, its simulated readings, their calibration.
      tolver::PlanBallbarInputs plan;
      plan.machine = machine;
      plan.plan.setups = in.ConsumeIntegralInRange(1, 3);
      plan.plan.poses = in.ConsumeIntegralInRange(1, 40);
      plan.lengths_mm = {extreme(in, 100)};
      plan.output = dir + "/plan.csv";
      tolver::planBallbar(plan);
      tolver::SimulateBallbarInputs sim;
      sim.machine = machine;
      sim.plan = plan.output;
      sim.output = dir + "/readings.csv";
      sim.noise_um = in.ConsumeFloatingPointInRange<double>(0, 5);
      tolver::simulateBallbar(sim);
      tolver::CalibrateInputs cal;
      cal.machine = machine;
      cal.readings = sim.output;
      cal.output = dir + "/identified.xml";
      cal.prior = in.ConsumeBool() ? "auto" : "none";
      tolver::calibrateMachine(cal);
      break;
    }
    default: {
      tolver::SetupInputs s;
      s.machine = machine;
      s.program = program;
      s.rotation_step_deg = in.ConsumeBool() ? 0.0 : 90.0;  // a few rotations: the time budget
      tolver::proposeSetup(s);
      break;
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzedDataProvider in(data, size);
  static const std::string dir = [] {
    const std::string d = "/tmp/tolver-fuzz-commands-" + std::to_string(::getpid());
    fs::create_directories(d);
    return d;
  }();
  try {
    runCommand(in, dir);
    static const bool verbose = std::getenv("TOLVER_FUZZ_VERBOSE") != nullptr;
    if (verbose) std::fprintf(stderr, "ran\n");
  } catch (const tolver::InputError& e) {
    // the expected answer: exit 2 naming what is wrong (TOLVER_FUZZ_VERBOSE: printed, to see how
    // deep the inputs go)
    static const bool verbose = std::getenv("TOLVER_FUZZ_VERBOSE") != nullptr;
    if (verbose) std::fprintf(stderr, "refused: %s\n", e.what());
  } catch (const std::exception& e) {
    // exit 3 (internal error) for a user: a defect
    std::fprintf(stderr, "fuzz_commands: internal error: %s\n", e.what());
    std::abort();
  }
  return 0;
}
