#pragma once
// Lanes: the same arithmetic on one double or on four at once, so that a hot kernel is written
// once as a template over its number type L and instantiated for both:
//   - L = double: the scalar path (one point at a time, any branch);
//   - L = Lane4: four points side by side (GCC/Clang vector extensions: SSE2 pairs on the
//     portable x86-64 build, one AVX register in a function cloned for AVX2).
// Each lane performs exactly the IEEE operations of the scalar instantiation, in the same
// order (no fused multiply-add: the clones target "avx2", not "fma"), so a point gives the
// same bits whichever path computed it. Comparisons give a Mask (bool, or all-ones lanes);
// select(m, a, b) takes a where m holds. Functions without a lane form (std::sin, atan2) are
// left to the scalar instantiation: a lane that needs one is flagged and recomputed by it.
#include <cmath>
#include <cstring>

// Lane4 values are passed between inlined functions only; GCC's note on the AVX calling
// convention does not apply.
#pragma GCC diagnostic ignored "-Wpsabi"

// Every function taking or returning a Lane4 is inlined into its caller, so that a kernel
// cloned for AVX2 never calls a default-target function across the two calling conventions
// (GCC passes a 32-byte vector in memory without AVX and in a register with it).
#define TOLVER_LANE_INLINE __attribute__((always_inline)) inline
#define TOLVER_LANE_LAMBDA __attribute__((always_inline))

// A function over lanes is cloned for AVX2 (one register per Lane4), beside the portable
// default (SSE2 pairs), and the loader picks the clone the processor runs (GCC on x86-64).
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && !defined(TOLVER_NO_CLONES)
#define TOLVER_LANE_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define TOLVER_LANE_CLONES
#endif

namespace tolver::lanes {

using Lane4 = double __attribute__((vector_size(32)));
using Mask4 = decltype(Lane4{} < Lane4{});  // all-ones or zero 64-bit lanes
constexpr int kWidth = 4;

TOLVER_LANE_INLINE double select(bool m, double a, double b) { return m ? a : b; }
template <typename M>
TOLVER_LANE_INLINE Lane4 select(M m, Lane4 a, Lane4 b) {
  const Mask4 mm = (Mask4)m;
  return (Lane4)((mm & (Mask4)a) | (~mm & (Mask4)b));
}

TOLVER_LANE_INLINE double sqrtL(double x) { return std::sqrt(x); }
TOLVER_LANE_INLINE Lane4 sqrtL(Lane4 x) {
  Lane4 r;
  for (int i = 0; i < kWidth; ++i) r[i] = std::sqrt(x[i]);
  return r;
}
TOLVER_LANE_INLINE double absL(double x) { return std::abs(x); }
TOLVER_LANE_INLINE Lane4 absL(Lane4 x) {
  const Lane4 minus_zero{-0.0, -0.0, -0.0, -0.0};
  return (Lane4)((Mask4)x & ~(Mask4)minus_zero);
}
TOLVER_LANE_INLINE double maxL(double a, double b) { return std::max(a, b); }
TOLVER_LANE_INLINE Lane4 maxL(Lane4 a, Lane4 b) {  // std::max(a, b): a unless a < b
  return select(a < b, b, a);
}

TOLVER_LANE_INLINE bool any(bool m) { return m; }
template <typename M>
TOLVER_LANE_INLINE bool any(M m) {
  for (int i = 0; i < kWidth; ++i)
    if (m[i]) return true;
  return false;
}
TOLVER_LANE_INLINE bool all(bool m) { return m; }
template <typename M>
TOLVER_LANE_INLINE bool all(M m) {
  for (int i = 0; i < kWidth; ++i)
    if (!m[i]) return false;
  return true;
}
template <typename M>
TOLVER_LANE_INLINE bool lane(M m, int i) { return m[i] != 0; }
TOLVER_LANE_INLINE bool lane(bool m, int) { return m; }

// Loads and stores of kWidth consecutive doubles.
TOLVER_LANE_INLINE Lane4 load4(const double* p) {
  Lane4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
TOLVER_LANE_INLINE void store4(double* p, Lane4 v) { std::memcpy(p, &v, sizeof v); }
TOLVER_LANE_INLINE Lane4 broadcast4(double x) { return Lane4{x, x, x, x}; }
// The same for L = double (one value) or Lane4 (four), and a mask stored as 0 or all ones.
template <typename L>
TOLVER_LANE_INLINE L loadL(const double* p) {
  if constexpr (sizeof(L) == sizeof(double)) return p[0];
  else return load4(p);
}
template <typename L>
TOLVER_LANE_INLINE void storeL(double* p, L v) {
  if constexpr (sizeof(L) == sizeof(double)) p[0] = v;
  else store4(p, v);
}
template <typename M>
TOLVER_LANE_INLINE void storeMask(long long* p, M m) {
  if constexpr (sizeof(M) == sizeof(bool)) p[0] = m ? -1 : 0;
  else std::memcpy(p, &m, sizeof m);
}
// A constant as L: the double itself, or in every lane.
template <typename L>
TOLVER_LANE_INLINE L splat(double x) {
  if constexpr (sizeof(L) == sizeof(double)) return x;
  else return broadcast4(x);
}

}  // namespace tolver::lanes
