// Host-owned storage: 64-byte aligned vectors for SoA arrays and scratch.
#pragma once

#include <cstddef>
#include <cstdlib>
#include <new>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace impact::host {

template <class T>
struct AlignedAllocator {
  using value_type = T;
  static constexpr std::size_t kAlign = 64;
  AlignedAllocator() = default;
  template <class U>
  AlignedAllocator(const AlignedAllocator<U>&) {}
  /// Blocks of at least this size are 2 MiB aligned and, on Linux, advised to use
  /// transparent huge pages: the random-access passes (grid gather and pair
  /// tests, solver scatters) otherwise miss the TLB on almost every access.
  static constexpr std::size_t kHugePage = std::size_t{1} << 21;
  T* allocate(std::size_t n) {
    if (n > (~std::size_t{0} - kHugePage) / sizeof(T)) throw std::bad_alloc();
    const std::size_t raw = n * sizeof(T);
    const bool huge = raw >= kHugePage;
    const std::size_t align = huge ? kHugePage : kAlign;
    const std::size_t bytes = ((raw + align - 1) / align) * align;
    void* p = std::aligned_alloc(align, bytes == 0 ? kAlign : bytes);
    if (!p) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (huge) madvise(p, bytes, MADV_HUGEPAGE);  // advisory: failure only costs speed
#endif
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
