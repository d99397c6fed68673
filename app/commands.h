#pragma once
// Each tolver command registers its options and its action on the CLI11 application.
#include <CLI/CLI.hpp>

#include "pipeline/command.h"

namespace tolver::app {

// The command sets *verdict when it finishes (Verdict::Ok by default); main maps it to the exit
// code.
void registerPredict(CLI::App& app, Verdict* verdict);
void registerAnalyze(CLI::App& app, Verdict* verdict);
void registerBallbar(CLI::App& app, Verdict* verdict);
void registerAllocate(CLI::App& app, Verdict* verdict);
void registerVerify(CLI::App& app, Verdict* verdict);
void registerDiagnose(CLI::App& app, Verdict* verdict);
void registerSetup(CLI::App& app, Verdict* verdict);
void registerCompensate(CLI::App& app, Verdict* verdict);
void registerMeasure(CLI::App& app, Verdict* verdict);

}  // namespace tolver::app
