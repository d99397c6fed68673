// tolver: will this five-axis machine make this part within tolerance?
// Exit codes (app/common.h, exitCode): 0 success, 1 not met (out of tolerance, no set-up, no
// convergence), 2 bad input or usage, 3 internal error, 4 undecided (verify).
#include <malloc.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <limits>

#include "app/commands.h"
#include "app/common.h"
#include "io/common/io_error.h"

int main(int argc, char** argv) {
  // glibc's allocator: blocks up to 32 MB from the heap, and freed memory kept there for the next
  // (not mapped and unmapped block by block, each page faulted in afresh): verify at a million
  // samples made 330 000 page faults, 215 000 with these; the memory goes back at exit.
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, std::numeric_limits<int>::max());
  mallopt(M_TOP_PAD, 256 << 20);
  CLI::App app{
      "tolver: predicts how a five-axis machine tool with geometric errors will really move "
      "along a part program."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "tolver 0.1.0");
  tolver::Verdict verdict = tolver::Verdict::Ok;
  tolver::app::useOptionNames();
  tolver::app::registerPredict(app, &verdict);
  tolver::app::registerAnalyze(app, &verdict);
  tolver::app::registerBallbar(app, &verdict);
  tolver::app::registerAllocate(app, &verdict);
  tolver::app::registerVerify(app, &verdict);
  tolver::app::registerDiagnose(app, &verdict);
  tolver::app::registerSetup(app, &verdict);
  tolver::app::registerCompensate(app, &verdict);
  tolver::app::registerMeasure(app, &verdict);
  tolver::app::useFileNumberRule(&app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "tolver: error: %s\n", e.what());
    return 2;
  } catch (const tolver::FieldError& e) {
    // An input the library names by its field: the option the user typed.
    std::fprintf(stderr, "tolver: error: %s: %s\n", tolver::app::optionForField(e.field()).c_str(),
                 e.message().c_str());
    return 2;
  } catch (const tolver::InputError& e) {
    std::fprintf(stderr, "tolver: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tolver: internal error: %s\n", e.what());
    return 3;
  }
  return tolver::exitCode(verdict);
}
