// The library's count -> scan -> write helpers over for_each_chunk (host/parallel.h):
// a pass that emits a variable number of outputs counts per chunk, turns the counts
// into exclusive offsets in chunk order, then writes each chunk's outputs at its
// offset, so the output order is the input order for any backend and thread count.
//   exclusive_scan_chunks  per-chunk counts -> offsets (serial: chunks are few)
//   count_and_scan         count per chunk + that scan; the caller then writes
//   chunked_output         find into per-chunk buffers (grown and rerun on overflow),
//                          scan, concatenate: one traversal in the common case
// Cost: one parallel pass per count, O(chunks) serial for the scan.
#pragma once

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "host/buffer.h"
#include "host/parallel.h"
#include "impact/status.h"

namespace impact::host {

/// Turns per-chunk counts off[0, chunks) into exclusive offsets, sets
/// off[chunks] to the total and returns it (serial: chunks are few).
inline uint64_t exclusive_scan_chunks(uint64_t* off, uint32_t chunks) {
  uint64_t total = 0;
  for (uint32_t c = 0; c < chunks; ++c) {
    const uint64_t k = off[c];
    off[c] = total;
    total += k;
  }
  off[chunks] = total;
  return total;
}

/// Runs count(begin, end) per chunk and turns the counts into exclusive offsets
/// (offsets[c] = first output of chunk c, offsets[chunks] = total). Returns total.
template <class Count>
uint64_t count_and_scan(const Executor& exec, uint64_t n, uint32_t grain, Buffer<uint64_t>& offsets,
                        Count&& count) {
  const uint32_t chunks = chunk_count(n, grain);
  uint64_t* off = scratch(offsets, static_cast<size_t>(chunks) + 1);
  exec.for_each_chunk(n, grain, [&](uint32_t b, uint32_t e, uint32_t c) { off[c] = count(b, e); });
  return exclusive_scan_chunks(off, chunks);
}

/// Runs find(begin, end, dst, capacity) -> count per chunk, each chunk into its
/// own buffer (grown and rerun when the count exceeds its capacity, so nothing is
/// dropped), then concatenates the chunks in chunk order into *out. One traversal
/// in the common case, and the output order does not depend on the thread count.
template <class T, class Find>
Status chunked_output(const Executor& exec, uint64_t n, uint32_t grain, std::vector<Buffer<T>>& bufs,
                      Buffer<uint64_t>& offsets, uint64_t max_total, const char* what, Find&& find,
                      Buffer<T>* out) {
  const uint32_t chunks = chunk_count(n, grain);
  if (bufs.size() < chunks) bufs.resize(chunks);
  uint64_t* off = scratch(offsets, static_cast<size_t>(chunks) + 1);
  exec.for_each_chunk(n, grain, [&](uint32_t b, uint32_t e, uint32_t c) {
    Buffer<T>& buf = bufs[c];
    if (buf.empty()) buf.resize(4ull * grain);
    uint64_t count = find(b, e, buf.data(), static_cast<uint64_t>(buf.size()));
    if (count > buf.size()) {
      buf.resize(count + count / 4);
      count = find(b, e, buf.data(), static_cast<uint64_t>(buf.size()));
    }
    off[c] = count;
  });
  const uint64_t total = exclusive_scan_chunks(off, chunks);
  if (total > max_total) {
    out->clear();
    return Status(StatusCode::kCapacityExceeded, std::string(what) + ": " + std::to_string(total) +
                                                     " outputs exceed the limit of " +
                                                     std::to_string(max_total));
  }
  out->resize(total);
  if (total == 0) return Status();
  T* dst = out->data();
  exec.for_each_chunk(n, grain, [&](uint32_t, uint32_t, uint32_t c) {
    if (off[c + 1] > off[c]) std::memcpy(dst + off[c], bufs[c].data(), sizeof(T) * (off[c + 1] - off[c]));
  });
  return Status();
}

}  // namespace impact::host
