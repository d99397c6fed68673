// The pagmo module (libtolver_pagmo.so, core/numerics/lazy_module.h): NSGA-II by pagmo 2 with its
// thread batch evaluator (core/allocation/nsga2.h).
#include <pagmo/algorithms/nsga2.hpp>
#include <pagmo/batch_evaluators/thread_bfe.hpp>
#include <pagmo/bfe.hpp>
#include <pagmo/population.hpp>
#include <pagmo/problem.hpp>
#include <string>
#include <type_traits>

#include "core/allocation/nsga2.h"
#include "core/numerics/lazy_module.h"

namespace tolver::pagmo_module {
namespace {

struct Problem {
  const Nsga2Fitness* objectives = nullptr;
  std::vector<double> lb, ub;
  pagmo::vector_double fitness(const pagmo::vector_double& x) const {
    const std::array<double, 2> f = (*objectives)(x);
    return {f[0], f[1]};
  }
  std::pair<pagmo::vector_double, pagmo::vector_double> get_bounds() const { return {lb, ub}; }
  pagmo::vector_double::size_type get_nobj() const { return 2; }
  std::string get_name() const { return "tolver tolerance allocation"; }
};

}  // namespace

std::vector<std::vector<double>> nsga2(const Nsga2Fitness& fitness, const std::vector<double>& lb,
                                       const std::vector<double>& ub, const Nsga2Run& run) {
  Problem udp;
  udp.objectives = &fitness;
  udp.lb = lb;
  udp.ub = ub;
  pagmo::problem prob{udp};
  pagmo::population pop{prob, static_cast<pagmo::population::size_type>(run.population), run.seed};
  pagmo::nsga2 algo{static_cast<unsigned>(run.generations),
                    run.crossover_probability,
                    run.crossover_distribution,
                    run.mutation_probability,
                    run.mutation_distribution,
                    run.seed};
  // The population's fitness in parallel (the fitness shares nothing mutable). The same seed
  // gives the same front.
  algo.set_bfe(pagmo::bfe{pagmo::thread_bfe{}});
  pop = algo.evolve(pop);
  return pop.get_x();
}
static_assert(std::is_same_v<decltype(nsga2), decltype(tolver::nsga2)>);

}  // namespace tolver::pagmo_module

TOLVER_MODULE_EXPORTS({"nsga2", reinterpret_cast<void*>(&tolver::pagmo_module::nsga2)})
