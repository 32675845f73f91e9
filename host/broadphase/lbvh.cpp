#include "host/broadphase/lbvh.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "host/scan.h"
#include "kernels/bvh/lbvh_build_fused.h"
#include "kernels/bvh/lbvh_pair_cache.h"
#include "kernels/bvh/lbvh_refit.h"
#include "kernels/bvh/lbvh_traverse.h"

namespace impact::host {
namespace {

constexpr uint64_t kMaxPairs = 0xffffffffull;  // kernels index pairs with uint32

}  // namespace

uint32_t choose_morton_bits(const kernels::BoundsSummary& s, uint32_t n) {
  if (n > (1u << 24)) return 63;
  double max_extent = 0.0;
  for (int k = 0; k < 3; ++k)
    max_extent = std::max(max_extent, static_cast<double>(s.hi[k]) - static_cast<double>(s.lo[k]));
  if (!(max_extent > 0.0)) return 30;
  const double cell30 = max_extent / 1024.0;
  return cell30 > 4.0 * static_cast<double>(s.max_edge) ? 63 : 30;
}

kernels::LbvhView LbvhBroadPhase::view() const {
  return kernels::LbvhView{nodes_.data(),
                           internal_parent_.data(),
                           leaf_parent_.data(),
                           leaves_.data(),
                           filtered_ ? layer_.data() : nullptr,
                           filtered_ ? mask_.data() : nullptr,
                           filtered_ ? static_.data() : nullptr,
                           info_.leaves,
                           lanes_.data(),
                           kernels::lbvh_lane_stride(info_.leaves),
                           leaf_index_.data()};
}

Status LbvhBroadPhase::rebuild(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                               uint32_t n, const kernels::BoundsSummary* summary) {
  info_ = LbvhInfo{};
  info_.rebuilt = true;
  built_ = false;
  cache_valid_ = false;
  exact_leaves_valid_ = false;
  if (n > kernels::kLbvhMaxLeaves)
    return Status(StatusCode::kInvalidArgument, "LBVH broad phase: " + std::to_string(n) +
                                                    " boxes exceed the limit of " +
                                                    std::to_string(kernels::kLbvhMaxLeaves));
  info_.leaves = n;
  built_ = true;
  if (n == 0) return Status();

  // 1. Scene bounds and code width.
  const kernels::BoundsSummary sum = summary ? *summary : summarize_bounds(exec, boxes, n, partial_bounds_);
  const uint32_t bits = options_.morton_bits == 30 || options_.morton_bits == 63
                            ? options_.morton_bits
                            : choose_morton_bits(sum, n);
  info_.morton_bits = bits;
  const kernels::MortonParams mp = kernels::morton_params(sum.lo, sum.hi, bits == 30 ? 10 : 21);

  // 2. Keys, sorted. 30-bit: code << 32 | index, sorted on [32, 62). 63-bit: code with
  //    the index as value, sorted on [0, 63). Either way the sorted codes are in keys_
  //    and the build reads them as keys_ >> shift.
  //    Outside the pair cache's mode the same pass packs the boxes' records for the
  //    build's gather (one read of the bounds).
  uint64_t* keys = scratch(keys_, n);
  uint32_t* index = scratch(leaf_index_, n);
  kernels::SortedBox* packed_boxes = cache_mode() ? nullptr : scratch(packed_, n);
  uint32_t shift = 0;
  if (bits == 30) {
    exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      if (packed_boxes) kernels::morton_keys30_packed(mp, boxes, keys, packed_boxes, {b, e});
      else kernels::morton_keys30(mp, boxes, keys, {b, e});
    });
    sorter_.sort(exec, keys, n, 32, 62);
    exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::morton_split_keys(keys, index, {b, e});
    });
    shift = 32;
  } else {
    exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      if (packed_boxes) kernels::morton_keys63_packed(mp, boxes, keys, index, packed_boxes, {b, e});
      else kernels::morton_keys63(mp, boxes, keys, index, {b, e});
    });
    sorter_.sort_kv(exec, keys, index, n, 0, 63);
  }

  // 3. Hierarchy and bounds in one pass (lbvh_build_fused.h): chunks in parallel, then
  //    the chunk seams in order.
  filtered_ = filter.layer != nullptr;
  const kernels::SortedBox* packed = packed_boxes;  // null in the pair cache's mode
  if (cache_mode()) {  // the tree over the fat boxes (lbvh_pair_cache.h)
    margin_ = fat_margin(sum);
    kernels::SortedBox* fat = scratch(fat_, n);
    exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      kernels::lbvh_pack_fat(boxes, margin_, fat, {b, e});
    });
    packed = fat;
  }
  const kernels::LbvhFusedIn in{keys, shift, index, packed};
  const kernels::LbvhFusedOut out{
      {n >= 2 ? scratch(nodes_, n - 1) : nullptr, n >= 2 ? scratch(internal_parent_, n - 1) : nullptr,
       scratch(leaf_parent_, n)},
      {n >= 2 ? nodes_.data() : nullptr, scratch(leaves_, n), filtered_ ? scratch(layer_, n) : nullptr,
       filtered_ ? scratch(mask_, n) : nullptr, filtered_ ? scratch(static_, n) : nullptr, lanes(n)},
      n >= 2 ? scratch(slot_, n) : nullptr};
  kernels::LbvhBlocked* blocked = scratch(blocked_, chunk_count(n, kNodeGrain));
  exec.for_each_chunk(n, kNodeGrain, [&](uint32_t b, uint32_t e, uint32_t c) {
    kernels::lbvh_build_fused(boxes, filter, in, out, n, {b, e}, &blocked[c]);
  });
  for (uint32_t c = 1, b = kNodeGrain; b < n; ++c, b += kNodeGrain)
    kernels::lbvh_build_fused_seam(in, out, n, {b, std::min(n, b + kNodeGrain)}, blocked[c]);
  return Status();
}

kernels::LbvhLanes LbvhBroadPhase::lanes(uint32_t n) {
  const size_t stride = kernels::lbvh_lane_stride(n);
  const kernels::LbvhLanes l{scratch(lanes_, 6 * stride), stride};
  kernels::lbvh_lane_padding(l, n);
  return l;
}

const kernels::SortedBox* LbvhBroadPhase::pack(const Executor& exec, kernels::AabbSoA boxes, uint32_t n) {
  kernels::SortedBox* packed = scratch(packed_, n);
  exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::lbvh_pack_boxes(boxes, packed, {b, e});
  });
  return packed;
}

void LbvhBroadPhase::refit_bounds(const Executor& exec, kernels::AabbSoA boxes,
                                  kernels::PairFilter filter) {
  const uint32_t n = info_.leaves;
  filtered_ = filter.layer != nullptr;
  const kernels::LbvhRefitIn in{leaf_index_.data(), n >= 2 ? internal_parent_.data() : nullptr,
                                leaf_parent_.data(), pack(exec, boxes, n)};
  const kernels::LbvhRefitOut out{n >= 2 ? nodes_.data() : nullptr,
                                  leaves_.data(),
                                  filtered_ ? scratch(layer_, n) : nullptr,
                                  filtered_ ? scratch(mask_, n) : nullptr,
                                  filtered_ ? scratch(static_, n) : nullptr,
                                  lanes(n)};
  exec.for_each_chunk(n, kNodeGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    kernels::lbvh_refit(boxes, filter, in, out, n, {b, e});
  });
  // Nodes across chunk seams, chunk by chunk in order (O(depth) each).
  for (uint32_t b = kNodeGrain; b < n; b += kNodeGrain)
    kernels::lbvh_refit_seam(in, out, n, {b, std::min(n, b + kNodeGrain)});
}

Status LbvhBroadPhase::traverse(const Executor& exec, Buffer<kernels::Pair>* out) {
  const uint32_t n = info_.leaves;
  if (n < 2) {
    out->clear();
    return Status();
  }
  const kernels::LbvhView v = view();
  return chunked_output<kernels::Pair>(
      exec, n, kPairGrain, chunk_pairs_, chunk_offsets_, kMaxPairs, "LBVH broad phase pairs",
      [&](uint32_t b, uint32_t e, kernels::Pair* dst, uint64_t capacity) {
        return kernels::lbvh_find_pairs(v, dst, capacity, {b, e});
      },
      out);
}

double LbvhBroadPhase::sah_cost(const Executor& exec) {
  const uint32_t n = info_.leaves;
  if (n == 0) return 0.0;
  const kernels::LbvhView v = view();
  const uint64_t nodes = 2ull * n - 1;
  const uint32_t chunks = chunk_count(nodes, kNodeGrain);
  double* partial = scratch(partial_area_, chunks);
  exec.for_each_chunk(nodes, kNodeGrain, [&](uint32_t b, uint32_t e, uint32_t c) {
    partial[c] = kernels::lbvh_area_sum(v, {b, e});
  });
  double total = 0.0;
  for (uint32_t c = 0; c < chunks; ++c) total += partial[c];
  const double root = kernels::lbvh_area_sum(v, {0, 1});
  return root > 0.0 ? total / root : static_cast<double>(n);
}

Status LbvhBroadPhase::build(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                             uint32_t n, const kernels::BoundsSummary* summary) {
  const Status s = rebuild(exec, boxes, filter, n, summary);
  if (!s.ok()) return s;
  if (options_.update == LbvhUpdate::kAuto) info_.built_sah = info_.last_sah = sah_cost(exec);
  if (cache_mode() && n >= 2) {
    if (Status c = cache_build(exec, boxes, filter); !c.ok()) {
      built_ = false;
      return c;
    }
  }
  return Status();
}

kernels::LbvhFatMargin LbvhBroadPhase::fat_margin(const kernels::BoundsSummary& s) const {
  return kernels::LbvhFatMargin{options_.fat_margin, s.max_edge / 1024.0f};
}

bool LbvhBroadPhase::same_filter(kernels::PairFilter filter) const {
  if ((filter.layer != nullptr) != cache_filtered_) return false;
  if (!cache_filtered_) return true;
  const size_t n = info_.leaves;
  return std::memcmp(filter.layer, filter_layer_.data(), n * sizeof(uint32_t)) == 0 &&
         std::memcmp(filter.mask, filter_mask_.data(), n * sizeof(uint32_t)) == 0 &&
         std::memcmp(filter.is_static, filter_static_.data(), n) == 0;
}

Status LbvhBroadPhase::cache_build(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter) {
  const uint32_t n = info_.leaves;
  pack(exec, boxes, n);  // exact records, for the exact filter
  uint32_t* pos = scratch(leaf_pos_, n);
  const uint32_t* index = leaf_index_.data();
  exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    for (uint32_t s = b; s < e; ++s) pos[index[s]] = s;
  });
  cache_filtered_ = filter.layer != nullptr;
  if (cache_filtered_) {
    std::memcpy(scratch(filter_layer_, n), filter.layer, n * sizeof(uint32_t));
    std::memcpy(scratch(filter_mask_, n), filter.mask, n * sizeof(uint32_t));
    std::memcpy(scratch(filter_static_, n), filter.is_static, n);
  }
  // Every fat pair (a traversal of the fat tree), as keys (lo << w) | hi, sorted.
  if (Status s = traverse(exec, &fat_pairs_); !s.ok()) return s;
  key_shift_ = std::max(1u, bits_for(n - 1));
  const uint64_t m = fat_pairs_.size();
  const uint32_t w = key_shift_;
  const uint64_t* keys = sorted_keys(exec, fat_pairs_.data(), m, w);
  // One buffer per kLbvhCacheGrain lo indices.
  const uint32_t chunks = chunk_count(n, kernels::kLbvhCacheGrain);
  cur_ = 0;
  cache_[0].resize(std::max<size_t>(cache_[0].size(), chunks));
  cache_count_[0].assign(chunks, 0);
  exec.for_each_chunk(n, kernels::kLbvhCacheGrain, [&](uint32_t b, uint32_t e, uint32_t c) {
    const uint64_t* lo = std::lower_bound(keys, keys + m, static_cast<uint64_t>(b) << w);
    const uint64_t* hi = std::lower_bound(lo, keys + m, static_cast<uint64_t>(e) << w);
    const size_t count = static_cast<size_t>(hi - lo);
    if (count > 0) std::memcpy(scratch(cache_[0][c], count), lo, count * sizeof(uint64_t));
    cache_count_[0][c] = count;
  });
  info_.cached_pairs = m;
  info_.movers_since_build = 0;
  cache_valid_ = true;
  return Status();
}

Status LbvhBroadPhase::cache_update(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                                    bool* rebuild, bool* swamped) {
  const uint32_t n = info_.leaves;
  *rebuild = false;
  *swamped = false;
  if (!same_filter(filter)) {
    *rebuild = true;
    return Status();
  }
  exact_leaves_valid_ = false;
  // 1. Exact records; who left their fat box (they get a new one).
  kernels::SortedBox* fat = fat_.data();
  kernels::SortedBox* exact = scratch(packed_, n);
  uint8_t* moved = scratch(moved_, n);
  const uint32_t chunks = chunk_count(n, kKeyGrain);
  uint64_t* off = scratch(mover_offsets_, static_cast<size_t>(chunks) + 1);
  exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t c) {
    off[c] = kernels::lbvh_cache_check(boxes, margin_, fat, exact, moved, {b, e});
  });
  const uint64_t m = exclusive_scan_chunks(off, chunks);
  info_.movers = static_cast<uint32_t>(m);
  if (m == 0) return Status();
  // A re-query per mover costs more than a share of the traversal once many moved; a
  // grow-only tree loosens as movers add up.
  if (m > n / 4) {
    *rebuild = true;
    *swamped = true;
    return Status();
  }
  if (info_.movers_since_build + m > n) {
    *rebuild = true;
    return Status();
  }
  info_.movers_since_build += m;
  const uint32_t* index = leaf_index_.data();
  if (Status s = chunked_output<uint32_t>(
          exec, n, kKeyGrain, mover_chunks_, mover_offsets_, n, "LBVH movers",
          [&](uint32_t b, uint32_t e, uint32_t* dst, uint64_t) {
            return kernels::lbvh_cache_movers(moved, index, dst, {b, e});
          },
          &movers_);
      !s.ok())
    return s;
  const uint32_t* movers = movers_.data();
  // 2. Their leaves and ancestors take the new fat boxes (serial).
  kernels::lbvh_cache_grow({nodes_.data(), leaves_.data(), internal_parent_.data(), leaf_parent_.data(),
                            leaf_pos_.data(), lanes(n)},
                           fat, movers, static_cast<uint32_t>(m));
  // 3. Their pairs, against the grown tree, sorted.
  const kernels::LbvhView v = view();
  const uint32_t w = key_shift_;
  if (Status s = chunked_output<uint64_t>(
          exec, m, kMoverGrain, key_chunks_, key_offsets_, kMaxPairs, "LBVH pair cache",
          [&](uint32_t b, uint32_t e, uint64_t* dst, uint64_t capacity) {
            return kernels::lbvh_cache_query(v, leaf_pos_.data(), fat, moved, movers, w, dst, capacity, {b, e});
          },
          &new_keys_);
      !s.ok())
    return s;
  const uint64_t k = new_keys_.size();
  const uint64_t* nk = new_keys_.data();
  sorter_.sort(exec, new_keys_.data(), static_cast<uint32_t>(k), 0, 2 * w);
  // 4. Per chunk: the old keys without movers, merged with the new ones.
  const uint32_t cc = chunk_count(n, kernels::kLbvhCacheGrain);
  const int nxt = cur_ ^ 1;
  cache_[nxt].resize(std::max<size_t>(cache_[nxt].size(), cc));
  cache_count_[nxt].assign(cc, 0);
  exec.for_each_chunk(n, kernels::kLbvhCacheGrain, [&](uint32_t b, uint32_t e, uint32_t c) {
    const uint64_t* lo = std::lower_bound(nk, nk + k, static_cast<uint64_t>(b) << w);
    const uint64_t* hi = std::lower_bound(lo, nk + k, static_cast<uint64_t>(e) << w);
    const uint64_t old_count = cache_count_[cur_][c];
    const uint64_t room = old_count + static_cast<uint64_t>(hi - lo);
    uint64_t* dst = scratch(cache_[nxt][c], std::max<uint64_t>(room, 1));
    cache_count_[nxt][c] = kernels::lbvh_cache_merge(cache_[cur_][c].data(), old_count, lo,
                                                     static_cast<uint64_t>(hi - lo), moved, w, dst);
  });
  cur_ = nxt;
  uint64_t total = 0;
  for (uint32_t c = 0; c < cc; ++c) total += cache_count_[cur_][c];
  info_.cached_pairs = total;
  return Status();
}

Status LbvhBroadPhase::cache_pairs(const Executor& exec, Buffer<kernels::Pair>* out) {
  const uint32_t n = info_.leaves;
  const kernels::SortedBox* exact = packed_.data();
  const uint32_t w = key_shift_;
  return chunked_output<kernels::Pair>(
      exec, n, kernels::kLbvhCacheGrain, cache_out_, chunk_offsets_, kMaxPairs, "LBVH broad phase pairs",
      [&](uint32_t b, uint32_t, kernels::Pair* dst, uint64_t capacity) {
        const uint32_t c = b / kernels::kLbvhCacheGrain;
        return kernels::lbvh_cache_pairs(cache_[cur_][c].data(), cache_count_[cur_][c], exact, w, dst, capacity);
      },
      out);
}

const uint64_t* LbvhBroadPhase::sorted_keys(const Executor& exec, const kernels::Pair* pairs, uint64_t m,
                                            uint32_t w) {
  uint64_t* keys = scratch(new_keys_, m);
  exec.for_each_chunk(m, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    for (uint32_t i = b; i < e; ++i) keys[i] = (static_cast<uint64_t>(pairs[i].a) << w) | pairs[i].b;
  });
  sorter_.sort(exec, keys, static_cast<uint32_t>(m), 0, 2 * w);
  return keys;
}

Status LbvhBroadPhase::sorted_traverse(const Executor& exec, Buffer<kernels::Pair>* out) {
  if (Status s = traverse(exec, out); !s.ok()) return s;
  const uint64_t m = out->size();
  if (m < 2) return Status();
  const uint32_t w = std::max(1u, bits_for(info_.leaves - 1));
  kernels::Pair* p = out->data();
  const uint64_t* keys = sorted_keys(exec, p, m, w);
  const uint64_t low = (uint64_t{1} << w) - 1;
  exec.for_each_chunk(m, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
    for (uint32_t i = b; i < e; ++i)
      p[i] = kernels::Pair{static_cast<uint32_t>(keys[i] >> w), static_cast<uint32_t>(keys[i] & low)};
  });
  return Status();
}

kernels::LbvhView LbvhBroadPhase::query_view(const Executor& exec) {
  kernels::LbvhView v = view();
  if (!(cache_mode() && cache_valid_)) return v;
  const uint32_t n = info_.leaves;
  if (!exact_leaves_valid_) {
    kernels::SortedBox* dst = scratch(exact_leaves_, n);
    const kernels::SortedBox* exact = packed_.data();
    const uint32_t* index = leaf_index_.data();
    exec.for_each_chunk(n, kKeyGrain, [&](uint32_t b, uint32_t e, uint32_t) {
      for (uint32_t s = b; s < e; ++s) dst[s] = exact[index[s]];
    });
    exact_leaves_valid_ = true;
  }
  v.leaves = exact_leaves_.data();
  v.lanes = nullptr;  // they mirror the fat leaves
  return v;
}

Status LbvhBroadPhase::update(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                              uint32_t n, const kernels::BoundsSummary* summary) {
  if (cache_mode()) {
    const bool same_tree = built_ && info_.leaves == n && n >= 2 && info_.refits_since_build < options_.max_refits;
    auto refit_instead = [&] {  // exact leaves again; pairs() traverses
      cache_valid_ = false;
      exact_leaves_valid_ = false;
      refit_bounds(exec, boxes, filter);
      info_.rebuilt = false;
      ++info_.refits_since_build;
      info_.cache_backoff = backoff_left_;
      return Status();
    };
    if (same_tree && !cache_valid_ && backoff_left_ > 0) {
      --backoff_left_;
      return refit_instead();
    }
    if (same_tree && cache_valid_) {
      bool rebuild = false, swamped = false;
      if (Status s = cache_update(exec, boxes, filter, &rebuild, &swamped); !s.ok()) {
        built_ = false;
        cache_valid_ = false;
        return s;
      }
      if (!rebuild) {
        backoff_ = 0;
        info_.rebuilt = false;
        info_.cache_backoff = 0;
        ++info_.refits_since_build;
        return Status();
      }
      if (swamped) {
        // Boxes move too far for their margins: a cache rebuild would not last. Refit
        // for a while (1, 2, 4, ... 64 updates), then try the cache again.
        backoff_ = std::min<uint32_t>(kMaxCacheBackoff, std::max<uint32_t>(1, 2 * backoff_));
        backoff_left_ = backoff_;
        return refit_instead();
      }
    }
    return build(exec, boxes, filter, n, summary);
  }
  const bool can_refit = options_.update != LbvhUpdate::kRebuild && built_ && info_.leaves == n &&
                         n >= 2 && info_.refits_since_build < options_.max_refits;
  if (can_refit) {
    refit_bounds(exec, boxes, filter);
    bool keep = true;
    if (options_.update == LbvhUpdate::kAuto) {
      info_.last_sah = sah_cost(exec);
      keep = info_.last_sah <= options_.refit_sah_limit * info_.built_sah;
    }
    if (keep) {
      info_.rebuilt = false;
      ++info_.refits_since_build;
      return Status();
    }
  }
  return build(exec, boxes, filter, n, summary);
}

Status LbvhBroadPhase::pairs(const Executor& exec, Buffer<kernels::Pair>* out) {
  if (!built_) {
    out->clear();
    return Status();
  }
  if (cache_valid_) return cache_pairs(exec, out);
  if (cache_mode()) return sorted_traverse(exec, out);
  return traverse(exec, out);
}

Status LbvhBroadPhase::find_pairs(const Executor& exec, kernels::AabbSoA boxes,
                                  kernels::PairFilter filter, uint32_t n, Buffer<kernels::Pair>* out,
                                  const kernels::BoundsSummary* summary) {
  if (Status s = update(exec, boxes, filter, n, summary); !s.ok()) {
    out->clear();
    return s;
  }
  return pairs(exec, out);
}

Status LbvhBroadPhase::refit(const Executor& exec, kernels::AabbSoA boxes, kernels::PairFilter filter,
                             uint32_t n, Buffer<kernels::Pair>* out) {
  if (!built_ || n != info_.leaves) {
    out->clear();
    return Status(StatusCode::kInvalidArgument,
                  "LBVH refit: " + std::to_string(n) + " boxes, but " +
                      (built_ ? "the tree was built over " + std::to_string(info_.leaves)
                              : std::string("there is no tree yet")) +
                      " (rebuild with find_pairs)");
  }
  if (n == 0) {
    out->clear();
    return Status();
  }
  // Exact leaves again: a kPairCache cache no longer matches the tree (the next
  // update rebuilds it).
  cache_valid_ = false;
  exact_leaves_valid_ = false;
  refit_bounds(exec, boxes, filter);
  info_.rebuilt = false;
  ++info_.refits_since_build;
  return cache_mode() ? sorted_traverse(exec, out) : traverse(exec, out);
}

}  // namespace impact::host
