#include "kernels/bvh/lbvh_pair_cache.h"

#include <algorithm>

#include "kernels/bvh/lbvh_bounds.h"

namespace impact::kernels {
namespace {

IMPACT_INLINE SortedBox exact_record(AabbSoA boxes, uint32_t i) {
  return SortedBox{boxes.min_x[i], boxes.min_y[i], boxes.min_z[i], i,
                   boxes.max_x[i], boxes.max_y[i], boxes.max_z[i], 0u};
}

IMPACT_INLINE SortedBox fat_record(const SortedBox& e, LbvhFatMargin margin) {
  const float edge = std::max(std::max(e.max_x - e.min_x, e.max_y - e.min_y), e.max_z - e.min_z);
  const float m = margin.fraction * std::max(edge, margin.floor);
  return SortedBox{e.min_x - m, e.min_y - m, e.min_z - m, e.index, e.max_x + m, e.max_y + m, e.max_z + m, 0u};
}

// a inside b (boundaries included).
template <class A, class B>
IMPACT_INLINE bool inside(const A& a, const B& b) {
  return b.min_x <= a.min_x && b.min_y <= a.min_y && b.min_z <= a.min_z && a.max_x <= b.max_x &&
         a.max_y <= b.max_y && a.max_z <= b.max_z;
}

}  // namespace

void lbvh_pack_fat(AabbSoA boxes, LbvhFatMargin margin, SortedBox* IMPACT_RESTRICT fat, Range r) {
  for (uint32_t i = r.begin; i < r.end; ++i) fat[i] = fat_record(exact_record(boxes, i), margin);
}

uint32_t lbvh_cache_check(AabbSoA boxes, LbvhFatMargin margin, SortedBox* IMPACT_RESTRICT fat,
                          SortedBox* IMPACT_RESTRICT exact, uint8_t* IMPACT_RESTRICT moved, Range r) {
  uint32_t count = 0;
  for (uint32_t i = r.begin; i < r.end; ++i) {
    const SortedBox e = exact_record(boxes, i);
    exact[i] = e;
    const bool out = !inside(e, fat[i]);
    moved[i] = static_cast<uint8_t>(out);
    count += static_cast<uint32_t>(out);
    if (out) fat[i] = fat_record(e, margin);
  }
  return count;
}

uint32_t lbvh_cache_movers(const uint8_t* IMPACT_RESTRICT moved, const uint32_t* IMPACT_RESTRICT leaf_index,
                           uint32_t* IMPACT_RESTRICT out, Range r) {
  uint32_t k = 0;
  for (uint32_t s = r.begin; s < r.end; ++s) {
    const uint32_t i = leaf_index[s];
    if (moved[i]) out[k++] = i;
  }
  return k;
}

void lbvh_cache_grow(const LbvhGrowView& t, const SortedBox* fat, const uint32_t* movers, uint32_t count) {
  using lbvh_detail::bounds_of;
  for (uint32_t k = 0; k < count; ++k) {
    const uint32_t i = movers[k];
    const SortedBox& f = fat[i];
    const uint32_t s = t.leaf_pos[i];
    t.leaves[s] = f;
    t.lanes.store(s, f);
    const lbvh_detail::Bounds b = bounds_of(f);
    for (uint32_t p = t.leaf_parent[s]; p != kInvalidBody; p = t.internal_parent[p]) {
      LbvhNode& node = t.nodes[p];
      if (inside(f, node)) break;  // so do all its ancestors
      lbvh_detail::store_bounds(node, lbvh_detail::unite(bounds_of(node), b));
    }
  }
}

uint64_t lbvh_cache_query(const LbvhView& t, const uint32_t* leaf_pos, const SortedBox* fat,
                          const uint8_t* moved, const uint32_t* movers, uint32_t key_shift,
                          uint64_t* IMPACT_RESTRICT out, uint64_t capacity, Range r) {
  uint64_t k = 0;
  uint64_t spare = 0;
  uint32_t stack[kLbvhMaxDepth + 1];
  for (uint32_t p = r.begin; p < r.end; ++p) {
    const uint32_t i = movers[p];
    const SortedBox& q = fat[i];
    const uint32_t qs = leaf_pos[i];
    uint32_t lq = 0, mq = 0;
    uint8_t sq = 0;
    if (t.layer) {
      lq = t.layer[qs];
      mq = t.mask[qs];
      sq = t.is_static[qs];
    }
    auto leaf = [&](uint32_t u) {
      const SortedBox& b = t.leaves[u];
      const uint32_t j = b.index;
      bool keep = records_overlap(q, b) && j != i && (j > i || moved[j] == 0);
      if (t.layer) keep = keep && pair_allowed(lq, mq, sq, t.layer[u], t.mask[u], t.is_static[u]);
      uint64_t* dst = k < capacity ? out + k : &spare;
      *dst = i < j ? (static_cast<uint64_t>(i) << key_shift) | j : (static_cast<uint64_t>(j) << key_shift) | i;
      k += static_cast<uint64_t>(keep);
    };
    if (!records_overlap(q, t.nodes[0])) continue;
    uint32_t top = 0;
    // A pushed node's children are tested when it is popped: fetch them now.
    auto push = [&](uint32_t h) {
      stack[top++] = h;
      const uint32_t split = t.nodes[h].split, c = split & kLbvhSplitMask;
      __builtin_prefetch((split & kLbvhLeftLeaf) ? static_cast<const void*>(&t.leaves[c]) : &t.nodes[c]);
      __builtin_prefetch((split & kLbvhRightLeaf) ? static_cast<const void*>(&t.leaves[c + 1]) : &t.nodes[c + 1]);
    };
    stack[top++] = 0;
    while (top > 0) {
      const LbvhNode& m = t.nodes[stack[--top]];
      const uint32_t h = m.split & kLbvhSplitMask;
      if (m.split & kLbvhLeftLeaf) leaf(h);
      else if (records_overlap(q, t.nodes[h])) push(h);
      if (m.split & kLbvhRightLeaf) leaf(h + 1);
      else if (records_overlap(q, t.nodes[h + 1])) push(h + 1);
      // At most one pending sibling per level below the root plus the two just pushed
      // (lbvh_build.h's depth bound; growing bounds does not change the topology).
      IMPACT_ASSERT(top <= kLbvhMaxDepth + 1);
    }
  }
  return k;
}

uint64_t lbvh_cache_merge(const uint64_t* old_keys, uint64_t old_count, const uint64_t* new_keys,
                          uint64_t new_count, const uint8_t* moved, uint32_t key_shift,
                          uint64_t* IMPACT_RESTRICT out) {
  const uint64_t low = (uint64_t{1} << key_shift) - 1;
  uint64_t i = 0, j = 0, k = 0;
  while (i < old_count) {
    const uint64_t key = old_keys[i];
    if (moved[key >> key_shift] | moved[key & low]) {
      ++i;
      continue;
    }
    while (j < new_count && new_keys[j] < key) out[k++] = new_keys[j++];
    out[k++] = key;
    ++i;
  }
  while (j < new_count) out[k++] = new_keys[j++];
  return k;
}

uint64_t lbvh_cache_pairs(const uint64_t* keys, uint64_t count, const SortedBox* exact, uint32_t key_shift,
                          Pair* IMPACT_RESTRICT out, uint64_t capacity) {
  // The hi side is a random read (a cache miss at 1M boxes): prefetch it ahead.
  constexpr uint64_t kAhead = 48;
  const uint64_t low = (uint64_t{1} << key_shift) - 1;
  uint64_t k = 0;
  Pair spare{};
  for (uint64_t p = 0; p < count; ++p) {
    if (p + kAhead < count) __builtin_prefetch(&exact[keys[p + kAhead] & low]);
    const uint32_t a = static_cast<uint32_t>(keys[p] >> key_shift);
    const uint32_t b = static_cast<uint32_t>(keys[p] & low);
    const bool keep = records_overlap(exact[a], exact[b]);
    Pair* dst = k < capacity ? out + k : &spare;
    *dst = Pair{a, b};
    k += static_cast<uint64_t>(keep);
  }
  return k;
}

}  // namespace impact::kernels
