#include "core/numerics/lanes.h"

#include <atomic>
#include <cstring>
#if defined(__x86_64__)
#include <immintrin.h>
#endif

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

namespace {

#if TOLVER_HAS_WIDE_LANES
__attribute__((target("avx512f"))) void streamLines512(void* dst, const void* src, size_t bytes) {
  auto* d = static_cast<__m512i*>(dst);
  const auto* s = static_cast<const __m512i*>(src);
  for (size_t i = 0; i < bytes / 64; ++i) _mm512_stream_si512(d + i, _mm512_load_si512(s + i));
}
#endif

}  // namespace

void streamLines(const StreamCopy* copies, int count) {
#if defined(__x86_64__)
#if TOLVER_HAS_WIDE_LANES
  if (wideLanes()) {
    for (int k = 0; k < count; ++k) streamLines512(copies[k].dst, copies[k].src, copies[k].bytes);
    _mm_sfence();  // the stores are seen before what follows
    return;
  }
#endif
  for (int k = 0; k < count; ++k) {
    auto* d = static_cast<__m128i*>(copies[k].dst);
    const auto* s = static_cast<const __m128i*>(copies[k].src);
    for (size_t i = 0; i < copies[k].bytes / 16; ++i)
      _mm_stream_si128(d + i, _mm_load_si128(s + i));
  }
  _mm_sfence();
#else
  for (int k = 0; k < count; ++k) std::memcpy(copies[k].dst, copies[k].src, copies[k].bytes);
#endif
}

}  // namespace tolver::lanes
