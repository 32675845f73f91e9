// Uniform-grid broad phase over axis-aligned boxes. Building sorts the boxes by
// bucket (below) in three passes, a two-level counting sort whose second level
// writes the bucket ranges as it goes:
//
//   grid_bucket_count per box: bucket of its min corner's cell; per chunk, how many
//                  boxes fall in each "block" (the bucket id's high bits, at most
//                  kGridMaxBlocks blocks of 2^low_bits buckets)
//   (exclusive scan, block-major then chunk: where each chunk writes each block)
//   grid_scatter_blocks per box: the box packed as a 32-byte SortedBox (bucket in
//                  its pad word) written at its chunk's next slot of its block:
//                  a stable partition by block. Reads stream; writes go to at most
//                  kGridMaxBlocks sequential streams, never to random slots
//   grid_sort_blocks per block: a stable counting sort of the block's records
//                  (about n / 256 for big grids: cache resident) on the low bucket
//                  bits, using the block's own slice of bucket_start as the
//                  counters, so it leaves bucket -> first slot behind; writes each
//                  record (and, hashed grids only, its cell) in sorted-slot order
//   grid_find_pairs per sorted slot s: test the boxes later in s's own cell, then
//                  every box of the 13 "forward" neighbour cells (half of the 26,
//                  so each pair is met once). The host gives each chunk of slots
//                  its own output buffer, then concatenates them in chunk order
//                  at exclusive-scanned offsets.
// The sorted order is (bucket, input position), the order a stable sort of keys
// bucket << 32 | i gives, for any chunking of the passes. Each box moves twice in
// sequence, never once at random, and no separate segment-starts pass is needed
// (the radix sort + gather it replaced: docs/broadphase.md).
// Build cost: O(n + bucket_count + chunks * blocks), three streaming reads of the
// boxes' data and two writes of the 32-byte records.
//
// Correctness: the cell edge exceeds the largest box edge, so the min corners of
// two overlapping boxes are less than one cell apart on every axis and their
// cells differ by at most one per axis. Cell coordinates are computed in double
// from float inputs, so rounding cannot push them two cells apart.
// Buckets: cells are grouped in x-rows. "Dense" grids (few enough cells) use the
// row-major cell index as the bucket; hashed grids put cell x of row (y, z) in
// bucket (hash(y, z) + x) mod 2^table_bits. Either way the cells x-1..x+1 of a
// row are consecutive buckets (modulo the table), so a query scans 5 slot
// ranges, and the sorted order keeps x-neighbours together. In hashed tables
// slots whose cell is not the visited one are skipped, so collisions cost time
// but never produce a duplicate or a wrong pair (table size >= 4, so the three
// cells of a row never share a bucket).
// Pair order: by query slot (bucket, then index); then the own row (own cell
// after s, then cell x+1) and rows (dy, dz) = (1,0), (-1,1), (0,1), (1,1) over
// x-1..x+1, each in slot order (a hashed row that wraps the table end: the
// buckets up to the end first, then from bucket 0). Each pair holds (lo, hi)
// box indices. Overlap includes touching (min <= max). Inputs finite.
// Method: the spatial-hash grid of Teschner et al. 2003 ("Optimized Spatial
// Hashing for Collision Detection of Deformable Objects") and GPU sorted grids
// (Le Grand, GPU Gems 3 ch. 32), with a half neighbourhood.
#pragma once

#include <cstdint>

#include "kernels/broadphase/bounds.h"
#include "kernels/common/kernel.h"
#include "kernels/common/pair.h"
#include "kernels/common/sorted_box.h"

namespace impact::kernels {

inline constexpr uint32_t kGridAxisBits = 21;
inline constexpr uint32_t kGridMaxDim = 1u << kGridAxisBits;  // cells per axis, at most

struct GridParams {
  double origin[3];   ///< min corner of the union of boxes
  double inv_cell;    ///< 1 / cell edge
  uint32_t dims[3];   ///< cells per axis, each in [1, kGridMaxDim]
  uint32_t dense;     ///< 1: bucket = row-major cell index; 0: hashed
  uint32_t table_bits;     ///< hashed mode: log2 of the bucket count
  uint32_t bucket_count;   ///< number of buckets
};

/// Arrays in sorted-slot order, produced by grid_sort_blocks.
struct GridSorted {
  SortedBox* box;
  uint64_t* cell;       // hashed grids only (null when dense: a dense bucket is its cell)
  uint32_t* layer;      // null when unfiltered
  uint32_t* mask;
  uint8_t* is_static;
};

struct GridView {
  GridParams params;
  const SortedBox* box;
  const uint64_t* cell;   // hashed grids only, else null
  const uint32_t* layer;  // null when unfiltered
  const uint32_t* mask;
  const uint8_t* is_static;
  const uint32_t* bucket_start;  // bucket_count + 1 entries
};

/// A box's filter data packed for one read.
struct alignas(16) FilterRecord {
  uint32_t layer;
  uint32_t mask;
  uint32_t is_static;
  uint32_t pad;
};

/// The build's blocks: a bucket id's high bits pick its block, its low `low_bits`
/// bits its place within the block. At most kGridMaxBlocks blocks, so the per-chunk
/// block counts stay small and the block scatter writes few streams.
inline constexpr uint32_t kGridMaxBlockBits = 8;
inline constexpr uint32_t kGridMaxBlocks = 1u << kGridMaxBlockBits;

struct GridBlocks {
  uint32_t low_bits;  ///< buckets per block = 2^low_bits
  uint32_t count;     ///< blocks = ceil(bucket_count / 2^low_bits), in [1, kGridMaxBlocks]
};

/// The smallest low_bits that keeps the blocks of g within kGridMaxBlocks.
GridBlocks grid_blocks(const GridParams& g);

/// out_bucket[i] = bucket of box i for i in r, and out_block_count[k] (blocks.count
/// entries, overwritten) = boxes of r in block k.
void grid_bucket_count(const GridParams& g, GridBlocks blocks, AabbSoA boxes,
                       uint32_t* IMPACT_RESTRICT out_bucket, uint32_t* IMPACT_RESTRICT out_block_count,
                       Range r);

/// Box i of r goes to slot io_offsets[block of bucket[i]]++ of out_box as a
/// SortedBox with index original_index[i] (i when original_index is null: the
/// hierarchical grid builds levels over subsets) and pad = bucket[i]; with
/// out_filter (filtered only, else null), its filter data to the same slot.
/// io_offsets: this chunk's first slot per block (blocks.count entries, advanced).
void grid_scatter_blocks(GridBlocks blocks, AabbSoA boxes, PairFilter filter, const uint32_t* original_index,
                         const uint32_t* IMPACT_RESTRICT bucket, uint32_t* IMPACT_RESTRICT io_offsets,
                         SortedBox* IMPACT_RESTRICT out_box, FilterRecord* IMPACT_RESTRICT out_filter,
                         Range r);

/// For each block k in r (block indices): its slots [block_start[k], block_start[k+1])
/// of in_box (and in_filter when not null), stably sorted on the bucket (pad) into
/// the same slots of out (pad 0, cell of the min corner when out.cell is not null,
/// filter data), and
/// out_bucket_start[b] = first slot of bucket b for the block's buckets; the last
/// block also sets out_bucket_start[bucket_count] = its end. Each block touches
/// only its own slots and buckets. block_start: blocks.count + 1 entries.
void grid_sort_blocks(const GridParams& g, GridBlocks blocks, const uint32_t* IMPACT_RESTRICT block_start,
                      const SortedBox* IMPACT_RESTRICT in_box, const FilterRecord* IMPACT_RESTRICT in_filter,
                      GridSorted out, uint32_t* IMPACT_RESTRICT out_bucket_start, Range r);

/// Writes the pairs whose query slot lies in r to out[0, capacity) in the
/// documented order and returns how many there are; when that exceeds capacity
/// only the first `capacity` are written and the caller reruns with more room.
uint64_t grid_find_pairs(const GridView& g, Pair* IMPACT_RESTRICT out, uint64_t capacity, Range r);

// --- hierarchical levels -----------------------------------------------------------
// Boxes whose sizes span orders of magnitude go to levels by their largest edge e:
// level l holds top/4^(l+1) < e <= top/4^l (the last level everything smaller,
// zero-size boxes included). Each level is its own grid with a cell fitted to its
// boxes; pairs across levels come from each finer box querying every coarser
// grid over the cells that can hold an overlapping box (at most 3 per axis, since
// the finer box is smaller than the coarser cell). Cost stays O(n k) for k
// candidates per box instead of the single grid's O(n^2) when a few huge boxes
// force a huge cell. (Hierarchical hash grids: Mirtich 1996, Eitz & Lixu 2007.)

inline constexpr uint32_t kGridMaxLevels = 6;  // spans 4^5 = 1024x between levels 0 and 5

/// Level of each box in r, and the count per level in r (kGridMaxLevels entries).
void grid_levels(AabbSoA boxes, float top_edge, uint8_t* IMPACT_RESTRICT out_level,
                 uint32_t* IMPACT_RESTRICT out_count, Range r);

/// For each query box in r (SortedBox with its reported index; query_filter in
/// the same order, all null when unfiltered), every box of grid g that overlaps
/// it and passes the filter. Writes up to capacity pairs (lo, hi), returns the
/// count. Order: by query, then rows (z, y) ascending, then slot.
uint64_t grid_query_pairs(const GridView& g, const SortedBox* IMPACT_RESTRICT queries, PairFilter query_filter,
                          Pair* IMPACT_RESTRICT out, uint64_t capacity, Range r);

}  // namespace impact::kernels
