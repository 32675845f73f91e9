// The thread counts the Google Benchmark tools register (impact_microbench,
// impact_narrowbench, impact_raybench): 1 and 2 by default (the CI-class machine has 2
// cores), or the list in the environment variable IMPACT_BENCH_THREADS, e.g.
//   IMPACT_BENCH_THREADS=1,2,4,8,16 impact_microbench --benchmark_filter='/1000000/'
// for a scaling table on a bigger machine. A malformed list (not comma-separated
// integers in 1..1024) stops the tool with a message rather than running something
// other than what was asked for.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace impact::bench {

inline const std::vector<int64_t>& bench_thread_counts() {
  static const std::vector<int64_t> counts = [] {
    const char* env = std::getenv("IMPACT_BENCH_THREADS");
    if (env == nullptr || *env == '\0') return std::vector<int64_t>{1, 2};
    std::vector<int64_t> out;
    const std::string s(env);
    size_t pos = 0;
    while (pos <= s.size()) {
      const size_t comma = std::min(s.find(',', pos), s.size());
      const std::string item = s.substr(pos, comma - pos);
      char* end = nullptr;
      const long v = item.empty() ? 0 : std::strtol(item.c_str(), &end, 10);
      if (item.empty() || end == nullptr || *end != '\0' || v < 1 || v > 1024) {
        std::fprintf(stderr, "IMPACT_BENCH_THREADS='%s': expected comma-separated thread counts in 1..1024\n", env);
        std::exit(2);
      }
      out.push_back(v);
      pos = comma + 1;
    }
    return out;
  }();
  return counts;
}

}  // namespace impact::bench
