// tolver: will this five-axis machine make this part within tolerance?
// Exit codes: 0 success, 1 out of tolerance (verify), 2 bad input or usage.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>

#include "app/commands.h"
#include "io/common/io_error.h"

int main(int argc, char** argv) {
  CLI::App app{
      "tolver: predicts how a five-axis machine tool with geometric errors will really move "
      "along a part program."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "tolver 0.1.0");
  int exit_code = 0;
  tolver::app::registerPredict(app, &exit_code);
  tolver::app::registerAnalyze(app, &exit_code);
  tolver::app::registerBallbar(app, &exit_code);
  tolver::app::registerAllocate(app, &exit_code);
  tolver::app::registerVerify(app, &exit_code);
  tolver::app::registerDiagnose(app, &exit_code);
  tolver::app::registerSetup(app, &exit_code);
  tolver::app::registerCompensate(app, &exit_code);
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
  } catch (const tolver::InputError& e) {
    std::fprintf(stderr, "tolver: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tolver: internal error: %s\n", e.what());
    return 3;
  }
  return exit_code;
}
