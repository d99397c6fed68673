// NSGA-II through the tolver_pagmo module: see core/allocation/nsga2.h.
#include "core/allocation/nsga2.h"

#include "core/numerics/lazy_module.h"

namespace tolver {

std::vector<std::vector<double>> nsga2(const Nsga2Fitness& fitness, const std::vector<double>& lb,
                                       const std::vector<double>& ub, const Nsga2Run& run) {
  return moduleFunction<decltype(nsga2)>("tolver_pagmo", "nsga2")(fitness, lb, ub, run);
}

}  // namespace tolver
