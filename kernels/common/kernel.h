// Shared vocabulary of kernels/: restrict, inline hints, assertions.
// Kernels include only kernels/ headers and the standard library.
#pragma once

#include <cstdint>

#if defined(__GNUC__) || defined(__clang__)
#define IMPACT_RESTRICT __restrict__
#define IMPACT_INLINE inline __attribute__((always_inline))
// After a lambda's parameter list: GCC otherwise keeps a lambda called many times in a
// kernel out of line, passing its vector arguments through memory.
#define IMPACT_LAMBDA_INLINE __attribute__((always_inline))
#else
#define IMPACT_RESTRICT
#define IMPACT_INLINE inline
#define IMPACT_LAMBDA_INLINE
#endif

#ifndef NDEBUG
#include <cstdio>
#include <cstdlib>
#define IMPACT_ASSERT(cond)                                                              \
  do {                                                                                   \
    if (!(cond)) {                                                                       \
      std::fprintf(stderr, "impact: assertion failed: %s (%s:%d)\n", #cond, __FILE__, \
                   __LINE__);                                                            \
      std::abort();                                                                      \
    }                                                                                    \
  } while (0)
#else
#define IMPACT_ASSERT(cond) ((void)0)
#endif

namespace impact::kernels {

/// Index range [begin, end) a kernel invocation owns. Kernels are correct for any
/// partition of their index space into ranges.
struct Range {
  uint32_t begin;
  uint32_t end;
};

/// The one invalid index value of kernels/.
inline constexpr uint32_t kInvalidBody = 0xffffffffu;

}  // namespace impact::kernels
