// tolver allocate: tolerance allocation for machine builders (Cai, Li, Cheng, Sun, Wang: "A method
// to optimize geometric errors of machine tool based on SNR quality loss function and correlation
// analysis").
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "app/commands.h"
#include "app/common.h"
#include "io/machine/tolerance_file.h"
#include "io/report/allocation_report.h"
#include "pipeline/allocate.h"

namespace tolver::app {
namespace {

struct AllocateOptions {
  AllocateInputs in;
  std::string combination = "worst";
  std::string loss_distribution = "uniform";
};

void printAllocation(const AllocationRun& run, const AllocateOptions& o) {
  const MachineModel& m = run.machine.model;
  const std::vector<ToleranceTerm>& terms = run.terms;
  const AllocationModel& a = run.model;
  const AllocationResult& r = run.result;
  const AccuracyModel& acc = run.accuracy;
  const CorrelationAnalysis& corr = run.correlation;
  std::printf("tolver allocate: %s, %zu terms, %zu workspace poses, tool gauge length %.1f mm\n",
              m.name.c_str(), terms.size(), acc.poses.size(), m.setup.gauge_length);
  std::printf("  limits     |dx| %.4f  |dy| %.4f  |dz| %.4f mm, errors combined %s\n", a.limits[0],
              a.limits[1], a.limits[2], a.rss ? "root-sum-square" : "worst case over their signs");
  const AllocationSolution* c = r.chosen >= 0 ? &r.front[r.chosen] : nullptr;
  std::printf("  %-7s %-24s %-5s %10s %10s %10s\n", "term", "category", "unit", "standard",
              "optimised", "paper");
  for (size_t i = 0; i < terms.size(); ++i) {
    const auto& t = terms[i];
    std::printf("  %-7s %-24s %-5s %10.5g %10s %10s\n", t.name.c_str(), categoryName(t.category),
                displayUnit(m, t), displayValue(m, t, t.standard),
                c ? std::to_string(displayValue(m, t, c->T[i])).substr(0, 9).c_str() : "-",
                std::isnan(t.reference)
                    ? ""
                    : std::to_string(displayValue(m, t, t.reference)).substr(0, 9).c_str());
  }
  std::printf("  standard   cost %.5g, worst |dx| %.4f |dy| %.4f |dz| %.4f mm%s\n", r.standard.cost,
              r.standard.worst_exact[0], r.standard.worst_exact[1], r.standard.worst_exact[2],
              r.standard_feasible ? "" : "  (breaks the limits)");
  if (run.reference_complete)
    std::printf(
        "  reference  cost %.5g, worst |dx| %.4f |dy| %.4f |dz| %.4f mm%s\n", run.reference_cost,
        run.reference_worst[0], run.reference_worst[1], run.reference_worst[2],
        (run.reference_worst.array() <= a.limits.array()).all() ? "" : "  (breaks the limits)");
  std::printf("  groups    ");
  for (const auto& g : corr.members) {
    std::printf(" {");
    for (size_t k = 0; k < g.size(); ++k)
      std::printf("%s%s", k ? " " : "", terms[g[k]].name.c_str());
    std::printf("}");
  }
  std::printf("\n");
  int max_ref = 0;
  for (const auto& t : terms) max_ref = std::max(max_ref, t.reference_group);
  if (max_ref > 0) {
    std::printf("  published ");
    for (int g = 1; g <= max_ref; ++g) {
      std::printf(" {");
      bool first = true;
      for (const auto& t : terms)
        if (t.reference_group == g) {
          std::printf("%s%s", first ? "" : " ", t.name.c_str());
          first = false;
        }
      std::printf("}");
    }
    std::printf("\n");
  }
  if (c) {
    std::printf(
        "  optimised  cost %.5g (%+.1f %% against the standard), worst |dx| %.4f |dy| %.4f |dz| "
        "%.4f mm"
        " (nonlinear check); Pareto front of %zu\n",
        c->cost, -100.0 * (1.0 - c->cost / r.standard.cost), c->worst_exact[0], c->worst_exact[1],
        c->worst_exact[2], r.front.size());
  } else {
    std::fprintf(
        stderr,
        "tolver: no allocation within the bounds meets the limits; allow tighter tolerances "
        "(--lower-factor) or loosen --limits\n");
  }
  std::printf("  wrote      %s/report.html, report.json, allocation.csv, pareto.csv, pareto.png\n",
              o.in.report_dir.c_str());
}

}  // namespace

void registerAllocate(CLI::App& app, Verdict* verdict) {
  auto o = std::make_shared<AllocateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "allocate",
      "Allocate geometric-error tolerances at least cost under an accuracy limit (NSGA-II over "
      "cost + quality loss and tolerance spread).");
  addMachineOptions(cmd, o->in.machine, "machine file (XML)");
  cmd->add_option("--tolerances", o->in.tolerances, "tolerance file (CSV)")->required();
  cmd->add_option("--report-dir", o->in.report_dir, "directory for the reports")->required();
  cmd->add_option("--limits", o->in.limits_mm,
                  "allowed |dx|,|dy|,|dz| of the tool tip, mm (default 0.015,0.015,0.010)")
      ->delimiter(',')
      ->expected(3);
  cmd->add_option("--cost", o->in.cost, "h_p,h_a,h_d,r of the cost model (default 3,4,5,2)")
      ->delimiter(',')
      ->expected(4);
  cmd->add_option("--combination", o->combination, "worst (default) or rss")
      ->check(CLI::IsMember({"worst", "rss"}));
  cmd->add_option("--loss-weight", o->in.loss_weight,
                  "weight of the quality loss in M1 (default 1)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--loss-distribution", o->loss_distribution,
                  "uniform (default) or normal (t = 3 sigma)")
      ->check(CLI::IsMember({"uniform", "normal"}));
  cmd->add_option("--lower-factor", o->in.lower_factor,
                  "lower bounds = factor x standard (default: the file's, or 1)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--upper-factor", o->in.upper_factor,
                  "upper bounds = factor x standard (default: the file's, or 3)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--grid", o->in.grid, "values per linear axis in the workspace grid (default 3)")
      ->check(CLI::Range(1, 20));
  cmd->add_option("--rotary-grid", o->in.rotary_grid, "values per rotary axis (default 5)")
      ->check(CLI::Range(1, 72));
  cmd->add_option("--groups", o->in.groups, "correlation groups (default 4)")
      ->check(CLI::Range(1, 100));
  cmd->add_option("--population", o->in.opt.population,
                  "NSGA-II population, a multiple of 4 (default 100)")
      ->check(CLI::Range(8, 100000));
  cmd->add_option("--generations", o->in.opt.generations, "NSGA-II generations (default 250)")
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--seed", o->in.opt.seed, "random seed (default 1)");
  cmd->callback([o, verdict] {
    o->in.rss = o->combination == "rss";
    o->in.loss_normal = o->loss_distribution == "normal";
    const AllocationRun run = allocate(o->in);
    printAllocation(run, *o);
    *verdict = run.verdict;
  });
}

}  // namespace tolver::app
