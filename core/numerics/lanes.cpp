#include "core/numerics/lanes.h"

#include <atomic>

namespace tolver::lanes {

namespace {

bool processorRunsWideLanes() {
#if TOLVER_HAS_WIDE_LANES
  // libgcc's check includes the operating system's support of the AVX-512 registers.
  return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
         __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512bw");
#else
  return false;
#endif
}

std::atomic<bool>& wideFlag() {
  static std::atomic<bool> on{processorRunsWideLanes()};
  return on;
}

}  // namespace

bool wideLanes() { return wideFlag().load(std::memory_order_relaxed); }

void setWideLanes(bool on) { wideFlag().store(on && processorRunsWideLanes()); }

}  // namespace tolver::lanes
