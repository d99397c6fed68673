// tolver analyze: identifiability of a machine's error model ([AM01] 3.6, 4.7; Tables 3.2-3.4,
// 4.1-4.3), and of a ball-bar plan's identification Jacobian.
#include <cmath>
#include <cstdio>
#include <memory>

#include "app/commands.h"
#include "app/common.h"
#include "pipeline/analyze.h"

namespace tolver::app {
namespace {

std::string cond(double c) {
  if (std::isinf(c)) return "inf";
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", c);
  return b;
}

void printAnalysis(const AnalysisRun& run, const AnalyzeInputs& o) {
  const MachineModel& m = run.model;
  const MinimalSet& ms = run.minimal;
  const std::vector<int>& cols = run.columns;
  const int poses = run.poses;
  std::printf("tolver analyze: %s, %s model", m.name.c_str(), o.model.c_str());
  if (o.model == "motion") std::printf(" (Chebyshev degree %d)", m.blocks[cols.front()].degree);
  std::printf(": %zu parameters, %d random poses (seed %u)\n", cols.size(), poses, o.seed);
  std::printf("  sensitivity Jacobian %d x %d: rank %d, condition %s column-scaled\n",
              ms.initial.rows, ms.initial.cols, ms.initial.rank,
              cond(ms.initial.condition).c_str());
  std::printf(
      "  (columns scaled to unit norm; a singular value counts when above %.0e of the largest)\n",
      kRankTolerance);
  if (!ms.steps.empty()) {
    std::printf(
        "\n  confounded groups and removals (strategies: I keep set-up, II keep recognised link\n"
        "  errors, III smallest condition number)\n");
    std::printf("  %4s  %-12s %-10s %5s %5s %10s  %s\n", "step", "removed", "strategy", "size",
                "rank", "condition", "group (largest weight first)");
    for (size_t k = 0; k < ms.steps.size(); ++k) {
      const ReductionStep& s = ms.steps[k];
      std::string group;
      for (size_t g = 0; g < s.group.size() && g < 8; ++g)
        group += (g ? " " : "") + m.parameters[s.group[g]].iso_code;
      if (s.group.size() > 8) group += " ...";
      std::printf("  %4zu  %-12s %-10s %5d %5d %10s  %s\n", k + 1,
                  m.parameters[s.removed].iso_code.c_str(), s.strategy.c_str(), s.size_after,
                  s.rank_after, cond(s.condition_after).c_str(), group.c_str());
    }
  }
  std::printf(
      "\n  minimal-complete set: %zu parameters, condition %s column-scaled, %s unscaled (mm, "
      "rad)\n",
      ms.kept.size(), cond(ms.reduced.condition).c_str(),
      cond(ms.reduced.condition_unscaled).c_str());
  std::string machine_part, setup_part;
  for (int p : ms.kept) {
    const BlockKind k = m.blocks[m.parameters[p].block].kind;
    std::string& dst =
        (k == BlockKind::WorkpieceSetup || k == BlockKind::ToolSetup) ? setup_part : machine_part;
    dst += " " + m.parameters[p].iso_code + " (" + m.parameters[p].thesis_name + ")";
  }
  std::printf("    machine:%s\n    set-up:%s\n", machine_part.c_str(), setup_part.c_str());

  if (run.with_plan) {
    const PlanIdentifiability& p = run.plan;
    std::printf(
        "\n  ball-bar plan %s: %zu readings, %zu set-ups, %d unknowns (%d machine + 6 per "
        "set-up)\n",
        p.file.c_str(), p.readings, p.setups, p.unknowns, p.machine_unknowns);
    std::printf("  identification Jacobian: rank %d, condition %s column-scaled\n",
                p.minimal.initial.rank, cond(p.minimal.initial.condition).c_str());
    if (p.unobservable.empty()) {
      std::printf("  every unknown is observable\n");
    } else {
      std::string names;
      for (const std::string& c : p.unobservable) names += " " + c;
      std::printf("  unobservable with this plan (%zu):%s\n", p.unobservable.size(), names.c_str());
    }
  }
}

}  // namespace

void registerAnalyze(CLI::App& app, Verdict* verdict) {
  auto o = std::make_shared<AnalyzeInputs>();
  CLI::App* cmd = app.add_subcommand(
      "analyze",
      "Identifiability of the machine's error model: rank, condition number, confounded groups "
      "and the minimal-complete parameter set; with --plan, of a ball-bar plan.");
  addMachineOptions(cmd, o->machine, "machine file (XML)");
  cmd->add_option("--model", o->model,
                  "link (link errors, thesis ch. 3) or motion (Chebyshev motion errors, ch. 4)")
      ->check(CLI::IsMember({"link", "motion"}));
  cmd->add_option("--degree", o->degree,
                  "Chebyshev degree of every motion error (default: the file's)")
      ->check(CLI::Range(0, 20));
  cmd->add_option("--poses", o->poses, "random poses (default 30 for link, 600 for motion)")
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--seed", o->seed, "random seed (default 1)");
  cmd->add_option("--plan", o->plan, "ball-bar plan or readings (CSV) to analyse as well");
  cmd->callback([o, verdict] {
    const AnalysisRun run = analyze(*o);
    printAnalysis(run, *o);
    *verdict = run.verdict;
  });
}

}  // namespace tolver::app
