#include "app/common.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "io/common/text_util.h"

namespace tolver::app {

namespace {
std::map<std::string, std::string>& commandSpellings() {
  static std::map<std::string, std::string> m;
  return m;
}
}  // namespace

std::string optionForField(const std::string& field) {
  const auto own = commandSpellings().find(field);
  if (own != commandSpellings().end()) return own->second;
  // Options whose name is not the field's: units in the option's own words.
  static const std::map<std::string, std::string> spelled = {
      {"output", "-o"},
      {"units", "--cl-units"},
      {"point_table", "--errors"},
      {"zones_file", "--zones"},
      {"tolerance_mm", "--tolerance"},
      {"uz_mm", "--uz"},
      {"asme_u_mm", "--asme-u"},
      {"spacing_mm", "--spacing"},
      {"step_mm", "--step"},
      {"max_hole_mm", "--max-hole"},
      {"limits_mm", "--limits"},
      {"excess_range_mm", "--excess-range"},
      {"gouge_range_mm", "--gouge-range"},
      {"chordal_tolerance", "--chordal-tol"}};
  const auto it = spelled.find(field);
  if (it != spelled.end()) return it->second;
  std::string option = "--" + field;
  for (char& c : option)
    if (c == '_') c = '-';
  return option;
}

void useFileNumberRule(CLI::App* app) {
  static const CLI::Validator number(
      [](std::string& s) -> std::string {
        if (parseNumber(s)) return "";
        return "expected a number (digits with one point, an optional sign and exponent), found '" +
               s + "'";
      },
      "NUMBER");
  for (CLI::Option* o : app->get_options())
    if (o->get_type_name().find("FLOAT") != std::string::npos) o->check(number);
  for (CLI::App* sub : app->get_subcommands([](CLI::App*) { return true; })) useFileNumberRule(sub);
}

void useOptionNames(const std::map<std::string, std::string>& command_spellings) {
  commandSpellings() = command_spellings;
  setInputNamer([](const std::string& field) { return optionForField(field); });
}

void addMachineOptions(CLI::App* cmd, MachineOptions& o, const char* machine_help) {
  cmd->add_option("--machine", o.machine, machine_help)->required();
  cmd->add_option("--setup", o.setup, "set-up file (part zero, part rotation, gauge length)");
  cmd->add_option("--part-zero", o.part_zero, "part zero in the table frame, mm (x,y,z)")
      ->delimiter(',')
      ->expected(3);
  cmd->add_option("--part-rotation-deg", o.part_rotation_deg,
                  "rotation of the part about the table z axis, deg");
  cmd->add_option("--gauge-length", o.gauge_length, "tool gauge length, mm");
}

void addProgramOptions(CLI::App* cmd, ProgramOptions& o) {
  cmd->add_option("--cl", o.cl,
                  "CL program (APT/CLDATA: .apt, .cls, .clsf, .ncl); posted "
                  "G-code is detected");
  cmd->add_option("--nc", o.nc, "posted G-code program (ISO 6983: .nc, .ngc, .tap, .gcode)");
  cmd->add_option("--cl-units", o.units,
                  "unit of the program's numbers: mm or inch (default: the file's UNITS, G20 "
                  "or G21, else mm or the control's default); on a CL it overrides a UNITS "
                  "statement, said in a note; G-code's G20/G21 stand, as on the control")
      ->check(CLI::IsMember({"mm", "inch"}));
  cmd->add_option("--chordal-tol", o.chordal_tolerance,
                  "chordal tolerance for expanding arcs, mm (default 0.001)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--lines", o.lines,
                  "only the tool positions of these program lines, 'first-last' (a piece that "
                  "tolver setup split off)");
  cmd->add_option("--cutter-comp", o.cutter_comp,
                  "G-code under G41/G42: 'wear' reads the path as written, as the tool centre "
                  "(the CAM's wear or reverse-wear compensation, the D registers holding only "
                  "wear, taken as 0); without it G41/G42 are refused, since a path posted for the "
                  "control's full radius compensation is the part's contour")
      ->check(CLI::IsMember({"wear"}));
  cmd->add_option("--tool-table", o.tool_table,
                  "LinuxCNC's tool table (T1 P1 D6 ...; the machine's units): the diameters "
                  "G41/G42 compensate by; G41.1/G42.1 carry theirs in the program");
  cmd->add_flag("--absolute-msys", o.absolute_msys,
                "NX CLSF: read every MSYS in the CAD's absolute frame (default: the first MSYS "
                "is the part frame and later ones are 3+2 set-ups relative to it)");
}

void addProbedOption(CLI::App* cmd, std::string& path) {
  cmd->add_option("--probed", path,
                  "probed points (CSV: part_x_mm,part_y_mm,part_z_mm, the joint values at each "
                  "touch, optional part_nx,part_ny,part_nz and probe_length_mm; rows with "
                  "tram_x_urad,tram_y_urad and joints only are spindle trams): the part's set-up "
                  "(and with a tram the spindle's tilt) is fitted to them on the machine with its "
                  "errors, the tool taken as preset");
}

void printWarnings(const std::vector<std::string>& warnings) {
  for (const std::string& w : warnings) std::fprintf(stderr, "tolver: warning: %s\n", w.c_str());
}

void printNotes(const std::vector<std::string>& notes) {
  for (const std::string& n : notes) std::fprintf(stderr, "tolver: note: %s\n", n.c_str());
}

ProgressBar::ProgressBar(bool enabled) : enabled_(enabled), tty_(isatty(2) != 0) {
  if (const char* e = std::getenv("TOLVER_PROGRESS_SECONDS")) {
    char* end = nullptr;
    const double v = std::strtod(e, &end);
    if (end != e && *end == '\0' && std::isfinite(v) && v >= 0.0) line_seconds_ = v;
  }
}

ProgressBar::~ProgressBar() { endPhase(); }

void ProgressBar::endPhase() {
  if (!open_) return;
  open_ = false;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  if (tty_) {
    if (drawn_) std::fprintf(stderr, "\n");
  } else if (seconds >= line_seconds_) {
    std::fprintf(stderr, "tolver: %s: %.1f s\n", phase_.c_str(), seconds);
  }
  drawn_ = false;
  std::fflush(stderr);
}

void ProgressBar::operator()(const std::string& what, double f) {
  if (!enabled_) return;
  if (!open_ || what != phase_) {
    endPhase();
    phase_ = what;
    start_ = std::chrono::steady_clock::now();
    open_ = true;
  }
  f = std::clamp(std::isfinite(f) ? f : 0.0, 0.0, 1.0);
  if (tty_) {
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    char left[32] = "";
    if (f > 0.02 && f < 1.0 && seconds > 1.0)
      std::snprintf(left, sizeof left, ", ~%.0f s left", seconds * (1.0 - f) / f);
    const int width = 40, filled = static_cast<int>(f * width + 0.5);
    std::fprintf(stderr, "\r  %-24s [%s%s] %3d%%%-18s", what.c_str(),
                 std::string(filled, '#').c_str(), std::string(width - filled, '.').c_str(),
                 static_cast<int>(f * 100 + 0.5), left);
    drawn_ = true;
    std::fflush(stderr);
  }
  if (f >= 1.0) endPhase();
}

std::shared_ptr<bool> addQuietFlag(CLI::App* cmd) {
  auto quiet = std::make_shared<bool>(false);
  cmd->add_flag("--quiet", *quiet, "no progress bar");
  return quiet;
}

Progress progressOf(ProgressBar& bar) {
  return [&bar](const std::string& phase, double f) { bar(phase, f); };
}

}  // namespace tolver::app
