#pragma once
// NSGA-II (Deb et al. 2002) as pagmo 2 implements it, for the tolerance allocation ([Cai] 4.2):
// the final population of a two-objective minimisation within box bounds. pagmo lives in the
// tolver_pagmo module (core/allocation/nsga2_pagmo.cpp, opened on first use:
// core/numerics/lazy_module.h), so that no other command loads it.
#include <array>
#include <functional>
#include <vector>

namespace tolver {

// The objectives of a candidate, both minimised; called from several threads at once (pagmo's
// thread batch evaluator): it must share nothing mutable.
using Nsga2Fitness = std::function<std::array<double, 2>(const std::vector<double>&)>;

struct Nsga2Run {
  int population = 100;  // a multiple of 4, at least 8
  int generations = 250;
  double crossover_probability = 0.95, crossover_distribution = 10.0;
  double mutation_probability = 0.1, mutation_distribution = 50.0;
  unsigned seed = 1;  // the same seed gives the same population
};

// The final population's decision vectors (each within [lb, ub]).
std::vector<std::vector<double>> nsga2(const Nsga2Fitness& fitness, const std::vector<double>& lb,
                                       const std::vector<double>& ub, const Nsga2Run& run);

}  // namespace tolver
