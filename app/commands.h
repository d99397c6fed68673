#pragma once
// Each tolver command registers its options and its action on the CLI11 application.
#include <CLI/CLI.hpp>

namespace tolver::app {

// The command sets *exit_code when it finishes (0 by default).
void registerPredict(CLI::App& app, int* exit_code);
void registerAnalyze(CLI::App& app, int* exit_code);
void registerBallbar(CLI::App& app, int* exit_code);
void registerAllocate(CLI::App& app, int* exit_code);
void registerVerify(CLI::App& app, int* exit_code);
void registerDiagnose(CLI::App& app, int* exit_code);
void registerSetup(CLI::App& app, int* exit_code);
void registerCompensate(CLI::App& app, int* exit_code);

}  // namespace tolver::app
