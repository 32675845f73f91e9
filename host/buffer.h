// Host-owned storage: 64-byte aligned vectors for SoA arrays and scratch.
#pragma once

#include <cstddef>
#include <cstdlib>
#include <new>
#include <vector>

namespace impact::host {

template <class T>
struct AlignedAllocator {
  using value_type = T;
  static constexpr std::size_t kAlign = 64;
  AlignedAllocator() = default;
  template <class U>
  AlignedAllocator(const AlignedAllocator<U>&) {}
  T* allocate(std::size_t n) {
    const std::size_t bytes = ((n * sizeof(T) + kAlign - 1) / kAlign) * kAlign;
    void* p = std::aligned_alloc(kAlign, bytes == 0 ? kAlign : bytes);
    if (!p) throw std::bad_alloc();
    return static_cast<T*>(p);
  }
  void deallocate(T* p, std::size_t) { std::free(p); }
  template <class U>
  bool operator==(const AlignedAllocator<U>&) const { return true; }
};

/// Aligned std::vector. Growth keeps capacity, so per-frame scratch resized to
/// the same size does not reallocate.
template <class T>
using Buffer = std::vector<T, AlignedAllocator<T>>;

/// Resizes without caring about contents (scratch); never shrinks capacity.
template <class T>
inline T* scratch(Buffer<T>& b, std::size_t n) {
  if (b.size() < n) b.resize(n);
  return b.data();
}

}  // namespace impact::host
