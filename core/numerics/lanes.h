#pragma once
// Lanes: the same arithmetic on one double or on several at once, so that a hot kernel is
// written once as a template over its number type L and instantiated for each:
//   - L = double: the scalar path (one point at a time, any branch);
//   - L = Lane4: four points side by side (GCC/Clang vector extensions: SSE2 pairs on the
//     portable x86-64 build, one AVX register in a function cloned for AVX2);
//   - L = Lane8: eight points side by side, in a function compiled for AVX-512 (one register)
//     and called only where the processor runs it (wideLanes()).
// Each lane performs exactly the IEEE operations of the scalar instantiation, in the same
// order (no fused multiply-add: the AVX2 clones target "avx2", not "fma", and the project is
// built with -ffp-contract=off, so the AVX-512 functions, whose target implies FMA, contract
// nothing either), so a point gives the same bits whichever path computed it. Comparisons give
// a mask (bool, or all-ones lanes); select(m, a, b) takes a where m holds. Functions without a
// lane form (std::sin, atan2) are left to the scalar instantiation: a lane that needs one is
// flagged and recomputed by it.
#include <cmath>
#include <cstddef>
#include <cstring>

// Lane4 values are passed between inlined functions only; GCC's note on the AVX calling
// convention does not apply.
#pragma GCC diagnostic ignored "-Wpsabi"
// Masks are combined with & and |, also in the scalar instantiation (bool): on purpose.
#if defined(__clang__)
#pragma clang diagnostic ignored "-Wbitwise-instead-of-logical"
#endif

// Every function taking or returning a Lane4 is inlined into its caller, so that a kernel
// cloned for AVX2 never calls a default-target function across the two calling conventions
// (GCC passes a 32-byte vector in memory without AVX and in a register with it).
#define TOLVER_LANE_INLINE __attribute__((always_inline)) inline
#define TOLVER_LANE_LAMBDA __attribute__((always_inline))

// A function over lanes is cloned for AVX2 (one register per Lane4), beside the portable
// default (SSE2 pairs), and the loader picks the clone the processor runs (GCC on x86-64).
// TOLVER_LANE_WIDE marks the Lane8 form of a kernel, compiled for AVX-512 (GCC on x86-64;
// elsewhere TOLVER_HAS_WIDE_LANES is 0, the Lane8 forms are not compiled and wideLanes() is
// false).
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && !defined(TOLVER_NO_CLONES)
#define TOLVER_LANE_CLONES __attribute__((target_clones("avx2", "default")))
#define TOLVER_LANE_WIDE __attribute__((target("avx512f,avx512dq,avx512vl,avx512bw")))
#define TOLVER_HAS_WIDE_LANES 1
#else
#define TOLVER_LANE_CLONES
#define TOLVER_LANE_WIDE
#define TOLVER_HAS_WIDE_LANES 0
#endif

namespace tolver::lanes {

using Lane4 = double __attribute__((vector_size(32)));
using Mask4 = decltype(Lane4{} < Lane4{});  // all-ones or zero 64-bit lanes
using Lane8 = double __attribute__((vector_size(64)));
using Mask8 = decltype(Lane8{} < Lane8{});
// The lanes of a number type or of its mask: 1 for double and bool.
template <typename V>
constexpr int widthOf() {
  if constexpr (sizeof(V) <= sizeof(double))
    return 1;
  else
    return static_cast<int>(sizeof(V) / sizeof(double));
}

// The Lane8 forms run (an AVX-512 processor and a build with them); setWideLanes(false) keeps
// a process on the Lane4 forms (tests compare the two).
bool wideLanes();
void setWideLanes(bool on);

// Copies, each of bytes (a multiple of 64) from src to dst, both 64-byte aligned, with
// non-temporal full-line stores (dst's lines are not read into the caches first: long outputs),
// and one store fence after the last.
struct StreamCopy {
  void* dst;
  const void* src;
  size_t bytes;
};
void streamLines(const StreamCopy* copies, int count);

TOLVER_LANE_INLINE double select(bool m, double a, double b) { return m ? a : b; }
template <typename M>
TOLVER_LANE_INLINE Lane4 select(M m, Lane4 a, Lane4 b) {
  const Mask4 mm = (Mask4)m;
  return (Lane4)((mm & (Mask4)a) | (~mm & (Mask4)b));
}
template <typename M>
TOLVER_LANE_INLINE Lane8 select(M m, Lane8 a, Lane8 b) {
  const Mask8 mm = (Mask8)m;
  return (Lane8)((mm & (Mask8)a) | (~mm & (Mask8)b));
}

TOLVER_LANE_INLINE double sqrtL(double x) { return std::sqrt(x); }
template <typename V, typename = decltype(V{}[0])>
TOLVER_LANE_INLINE V sqrtL(V x) {
  V r;
  for (int i = 0; i < widthOf<V>(); ++i) r[i] = std::sqrt(x[i]);
  return r;
}
TOLVER_LANE_INLINE double absL(double x) { return std::abs(x); }
template <typename V, typename = decltype(V{}[0])>
TOLVER_LANE_INLINE V absL(V x) {
  using M = decltype(V{} < V{});
  V minus_zero;
  for (int i = 0; i < widthOf<V>(); ++i) minus_zero[i] = -0.0;
  return (V)((M)x & ~(M)minus_zero);
}
TOLVER_LANE_INLINE double maxL(double a, double b) { return std::max(a, b); }
template <typename V, typename = decltype(V{}[0])>
TOLVER_LANE_INLINE V maxL(V a, V b) {  // std::max(a, b): a unless a < b
  return select(a < b, b, a);
}

// A comparison's mask as a value to keep (to store, or to combine with others): GCC lowers a
// 512-bit comparison whose mask is used other than by a selection to one comparison per
// lane, and this selection keeps it one instruction. (No-op for bool.)
TOLVER_LANE_INLINE bool maskOf(bool m) { return m; }
TOLVER_LANE_INLINE Mask4 maskOf(Mask4 m) { return m; }
TOLVER_LANE_INLINE Mask8 maskOf(Mask8 m) {
#if TOLVER_HAS_WIDE_LANES
  Mask8 ones = ~Mask8{};
  asm("" : "+v"(ones));  // (opaque: the selection is not folded back into the comparison)
  return m ? ones : Mask8{};
#else
  return m;
#endif
}

TOLVER_LANE_INLINE bool any(bool m) { return m; }
template <typename M>
TOLVER_LANE_INLINE bool any(M m) {
  for (int i = 0; i < widthOf<M>(); ++i)
    if (m[i]) return true;
  return false;
}
TOLVER_LANE_INLINE bool any(Mask8 m) {  // a reduction: no lane-by-lane branches
  m = maskOf(m);
  const Mask4 h =
      __builtin_shufflevector(m, m, 0, 1, 2, 3) | __builtin_shufflevector(m, m, 4, 5, 6, 7);
  return (h[0] | h[1] | h[2] | h[3]) != 0;
}
TOLVER_LANE_INLINE bool all(bool m) { return m; }
template <typename M>
TOLVER_LANE_INLINE bool all(M m) {
  for (int i = 0; i < widthOf<M>(); ++i)
    if (!m[i]) return false;
  return true;
}
TOLVER_LANE_INLINE bool all(Mask8 m) {
  m = maskOf(m);
  const Mask4 h =
      __builtin_shufflevector(m, m, 0, 1, 2, 3) & __builtin_shufflevector(m, m, 4, 5, 6, 7);
  return (h[0] & h[1] & h[2] & h[3]) != 0;
}
template <typename M>
TOLVER_LANE_INLINE bool lane(M m, int i) {
  return m[i] != 0;
}
TOLVER_LANE_INLINE bool lane(bool m, int) { return m; }

// Loads and stores for L = double (one value) or lanes (widthOf<L>() values), and a mask
// stored as 0 or all ones.
template <typename L>
TOLVER_LANE_INLINE L loadL(const double* p) {
  if constexpr (sizeof(L) == sizeof(double)) {
    return p[0];
  } else {
    L v;
    std::memcpy(&v, p, sizeof v);
    return v;
  }
}
template <typename L>
TOLVER_LANE_INLINE void storeL(double* p, L v) {
  if constexpr (sizeof(L) == sizeof(double))
    p[0] = v;
  else
    std::memcpy(p, &v, sizeof v);
}
template <typename M>
TOLVER_LANE_INLINE void storeMask(long long* p, M m) {
  if constexpr (sizeof(M) == sizeof(bool))
    p[0] = m ? -1 : 0;
  else
    std::memcpy(p, &m, sizeof m);
}
template <typename M>
TOLVER_LANE_INLINE M loadMask(const long long* p) {
  if constexpr (sizeof(M) == sizeof(bool)) {
    return p[0] != 0;
  } else {
    M m;
    std::memcpy(&m, p, sizeof m);
    return m;
  }
}
// The mask's complement (for bool, !m: ~ on a bool would give a non-zero int).
TOLVER_LANE_INLINE bool notMask(bool m) { return !m; }
template <typename M>
TOLVER_LANE_INLINE M notMask(M m) {
  return ~m;
}
// A constant as L: the double itself, or in every lane.
template <typename L>
TOLVER_LANE_INLINE L splat(double x) {
  if constexpr (sizeof(L) == sizeof(double)) {
    return x;
  } else {
    L v;
    for (int i = 0; i < widthOf<L>(); ++i) v[i] = x;
    return v;
  }
}

}  // namespace tolver::lanes
