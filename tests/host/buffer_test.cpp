// host/buffer.h: AlignedAllocator's staggered blocks and SoaArrays' layout. Both only
// move where arrays start (for the L1 sets and 4K aliasing, docs/narrowphase.md "Array
// layout"); these tests pin what the kernels rely on: 64-byte alignment, no overlap,
// every element kept, and arrays at distinct 64-byte slots modulo 4096.
#include <gtest/gtest.h>

#include <cstdint>
#include <set>
#include <vector>

#include "host/buffer.h"

namespace impact::host {
namespace {

uint32_t slot(const void* p) { return static_cast<uint32_t>(reinterpret_cast<std::uintptr_t>(p) % 4096u / 64u); }

TEST(Buffer, BlocksAreAlignedAndKeepTheirData) {
  // Small (heap), staggered (>= 64 KiB) and huge (>= 2 MiB) blocks, grown.
  const std::size_t sizes[] = {1, 1000, 16384, 16385, 1u << 20, (1u << 19) + 3};
  std::vector<Buffer<float>> keep;
  for (int round = 0; round < 3; ++round) {
    for (const std::size_t n : sizes) {
      Buffer<float> b(n);
      ASSERT_EQ(reinterpret_cast<std::uintptr_t>(b.data()) % 64u, 0u) << n;
      for (std::size_t i = 0; i < n; ++i) b[i] = static_cast<float>(i);
      b.resize(2 * n + 7);  // regrows into a new block: the old one freed by its shift
      ASSERT_EQ(reinterpret_cast<std::uintptr_t>(b.data()) % 64u, 0u) << n;
      for (std::size_t i = 0; i < n; i += 997) ASSERT_EQ(b[i], static_cast<float>(i)) << n;
      keep.push_back(std::move(b));
    }
  }
  for (std::size_t i = 0; i < keep.size(); ++i) {
    for (std::size_t j = i + 1; j < keep.size(); ++j) {
      const float* a = keep[i].data();
      const float* b = keep[j].data();
      ASSERT_TRUE(a + keep[i].size() <= b || b + keep[j].size() <= a) << i << " " << j;
    }
  }
}

TEST(Buffer, SameSizeBigBlocksStartAtDifferentSlots) {
  // Blocks of one size that the C library maps page- or 2 MiB-aligned: without the
  // stagger all would start at one offset modulo 4096.
  for (const std::size_t n : {std::size_t{100000}, std::size_t{600000}}) {
    std::vector<Buffer<float>> keep;
    std::set<uint32_t> slots;
    for (int i = 0; i < 8; ++i) {
      keep.emplace_back(n);
      slots.insert(slot(keep.back().data()));
    }
    EXPECT_EQ(slots.size(), 8u) << n;
  }
}

TEST(SoaArrays, ArraysSitAtTheirOwnSlotsAndDoNotOverlap) {
  for (const std::size_t n : {std::size_t{1}, std::size_t{512}, std::size_t{1000}, std::size_t{65536}}) {
    for (const uint32_t phase : {0u, 22u, 44u, 63u}) {
      SoaArrays s;
      s.resize(21, n, phase);
      ASSERT_EQ(s.arrays(), 21u);
      std::set<uint32_t> slots;
      for (uint32_t i = 0; i < 21; ++i) {
        float* a = s.get<float>(i);
        ASSERT_EQ(slot(a), (phase + i) % 64u) << n << " " << phase << " " << i;
        slots.insert(slot(a));
        for (std::size_t k = 0; k < n; ++k) a[k] = static_cast<float>(i * 1000003u + k);
      }
      EXPECT_EQ(slots.size(), 21u);
      for (uint32_t i = 0; i < 21; ++i) {  // every array still holds its own values
        const float* a = s.get<float>(i);
        for (std::size_t k = 0; k < n; k += 61) ASSERT_EQ(a[k], static_cast<float>(i * 1000003u + k));
      }
    }
  }
}

}  // namespace
}  // namespace impact::host
