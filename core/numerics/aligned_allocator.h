#pragma once
// An allocator for std::vector whose storage starts on a 64-byte boundary (a cache line, one
// AVX-512 register) and whose elements are default-initialised: resize() leaves new doubles
// unwritten, for arrays that the caller fills completely (no zero-filling pass over a long
// result before it is written).
#include <cstddef>
#include <new>
#include <utility>

namespace tolver {

template <typename T>
struct AlignedAllocator {
  using value_type = T;
  static constexpr std::size_t kAlignment = 64;
  AlignedAllocator() = default;
  template <typename U>
  AlignedAllocator(const AlignedAllocator<U>&) {}
  T* allocate(std::size_t n) {
    return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t(kAlignment)));
  }
  void deallocate(T* p, std::size_t) { ::operator delete(p, std::align_val_t(kAlignment)); }
  template <typename U>
  void construct(U* p) noexcept {  // default-initialised: no value written
    ::new (static_cast<void*>(p)) U;
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
  template <typename U>
  bool operator==(const AlignedAllocator<U>&) const {
    return true;
  }
};

}  // namespace tolver
