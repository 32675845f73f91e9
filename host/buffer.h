// Host-owned storage: 64-byte aligned vectors for SoA arrays and scratch.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace impact::host {

/// 0 .. 62, turning with each call (AlignedAllocator's staggered blocks).
inline uint32_t next_slot() {
  static std::atomic<uint32_t> counter{0};
  return counter.fetch_add(1, std::memory_order_relaxed) % 63u;
}

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
  /// Blocks of at least this size start 1 to 63 cache lines past their alignment, the
  /// count turning with each such allocation: the arrays of one SoA, allocated one
  /// after another, then hold element i in different L1 sets. Aligned alike they would
  /// all start at one offset modulo 4096, and a loop streaming ~10 of them (the
  /// solver's contact arrays, a body store) would keep evicting its own lines (see
  /// SoaArrays below). The shift sits in the 8 bytes before the block.
  static constexpr std::size_t kStagger = std::size_t{1} << 16;
  T* allocate(std::size_t n) {
    if (n > (~std::size_t{0} - 2 * kHugePage) / sizeof(T)) throw std::bad_alloc();
    const std::size_t raw = n * sizeof(T);
    const bool huge = raw >= kHugePage;
    const std::size_t align = huge ? kHugePage : kAlign;
    const std::size_t shift = raw >= kStagger ? kAlign * (1 + next_slot()) : 0;
    const std::size_t bytes = ((raw + shift + align - 1) / align) * align;
    auto* p = static_cast<std::byte*>(std::aligned_alloc(align, bytes == 0 ? kAlign : bytes));
    if (!p) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (huge) madvise(p, bytes, MADV_HUGEPAGE);  // advisory: failure only costs speed
#endif
    if (shift != 0) std::memcpy(p + shift - sizeof(std::size_t), &shift, sizeof(std::size_t));
    return reinterpret_cast<T*>(p + shift);
  }
  void deallocate(T* p, std::size_t n) {
    auto* b = reinterpret_cast<std::byte*>(p);
    std::size_t shift = 0;
    if (n * sizeof(T) >= kStagger) std::memcpy(&shift, b - sizeof(std::size_t), sizeof(std::size_t));
    std::free(b - shift);
  }
  template <class U>
  bool operator==(const AlignedAllocator<U>&) const { return true; }
};

/// Aligned std::vector. Growth keeps capacity, so per-frame scratch resized to
/// the same size does not reallocate.
template <class T>
using Buffer = std::vector<T, AlignedAllocator<T>>;

/// Storage for the arrays of one SoA (a kernel's inputs or outputs): `arrays` arrays of n
/// elements of at most 4 bytes in one allocation, array i starting at byte (phase + i) * 64
/// modulo 4096. So a streaming kernel's arrays, lane k of each, sit in different L1 sets
/// and different 4 KiB page offsets: arrays at one offset (page-aligned ones, all of a
/// kind) share the L1 set of lane k (8 ways, ~20 streams), and arrays 16 bytes apart
/// (back-to-back heap blocks of a power-of-two size) make a load wait for an unrelated
/// store whose address matches in bits 11:0 (4K aliasing); docs/narrowphase.md has the
/// measurements. Give the inputs and the outputs of one kernel different phases (e.g. 0,
/// 22, 44). Contents are not kept when resize grows the storage.
class SoaArrays {
 public:
  void resize(uint32_t arrays, std::size_t n, uint32_t phase) {
    constexpr std::size_t kPage = 4096;
    stride_ = (n * 4 + kPage - 1) / kPage * kPage + 64;
    first_ = (phase % 64) * 64;
    const std::size_t bytes = first_ + arrays * stride_ + kPage;
    if (raw_.size() < bytes) raw_.resize(bytes);
    const auto at = reinterpret_cast<std::uintptr_t>(raw_.data());
    start_ = raw_.data() + (kPage - at % kPage) % kPage;
    arrays_ = arrays;
  }
  /// Array i (< arrays) as T (sizeof(T) <= 4).
  template <class T>
  T* get(uint32_t i) const {
    static_assert(sizeof(T) <= 4);
    return reinterpret_cast<T*>(start_ + first_ + i * stride_);
  }
  uint32_t arrays() const { return arrays_; }

 private:
  Buffer<std::byte> raw_;
  std::byte* start_ = nullptr;
  std::size_t stride_ = 0, first_ = 0;
  uint32_t arrays_ = 0;
};

/// Resizes without caring about contents (scratch); never shrinks capacity.
template <class T>
inline T* scratch(Buffer<T>& b, std::size_t n) {
  if (b.size() < n) b.resize(n);
  return b.data();
}

}  // namespace impact::host
