// Small statistics of the bench tools' timings (bench/scenes/throughput.cpp,
// bench/rigid_peers.cpp).
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace impact::bench {

/// The median of v (the mean of the two middle values for an even count; 0 when empty).
inline double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + mid, v.end());
  const double hi = v[mid];
  if (v.size() % 2 == 1) return hi;
  return 0.5 * (hi + *std::max_element(v.begin(), v.begin() + mid));
}

}  // namespace impact::bench
