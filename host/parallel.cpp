#include "host/parallel.h"

#include <algorithm>
#include <thread>

#if IMPACT_HAVE_TBB
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>
#include <tbb/task_arena.h>
#endif
#if IMPACT_HAVE_OPENMP
#include <omp.h>
#endif

namespace impact {

uint32_t hardware_threads() {
  const unsigned n = std::thread::hardware_concurrency();
  return n == 0 ? 1u : n;
}

bool backend_available(Backend backend) {
  switch (backend) {
    case Backend::kDefault:
    case Backend::kSerial: return true;
    case Backend::kTbb: return IMPACT_HAVE_TBB != 0;
    case Backend::kOpenMP: return IMPACT_HAVE_OPENMP != 0;
  }
  return false;
}

const char* to_string(Backend backend) {
  switch (backend) {
    case Backend::kDefault: return "default";
    case Backend::kSerial: return "serial";
    case Backend::kTbb: return "tbb";
    case Backend::kOpenMP: return "openmp";
  }
  return "?";
}

}  // namespace impact

namespace impact::host {

class ExecutorImpl {
 public:
#if IMPACT_HAVE_TBB
  explicit ExecutorImpl(uint32_t threads) : arena(static_cast<int>(threads)) {}
  tbb::task_arena arena;
#else
  explicit ExecutorImpl(uint32_t) {}
#endif
};

bool resolve_backend(Backend requested, Backend* out) {
  Backend b = requested;
  if (b == Backend::kDefault) {
#if IMPACT_DEFAULT_BACKEND_TBB
    b = Backend::kTbb;
#elif IMPACT_DEFAULT_BACKEND_OPENMP
    b = Backend::kOpenMP;
#else
    b = Backend::kSerial;
#endif
  }
  if (!backend_available(b)) return false;
  *out = b;
  return true;
}

Executor::Executor(Backend backend, uint32_t threads) {
  if (!resolve_backend(backend, &backend_)) backend_ = Backend::kSerial;
  threads_ = backend_ == Backend::kSerial ? 1u : (threads == 0 ? hardware_threads() : threads);
  // TBB caps its workers at the hardware threads (and warns when asked for more);
  // results do not depend on the count, so ask for no more than it will run.
  if (backend_ == Backend::kTbb) threads_ = std::min(threads_, hardware_threads());
  if (backend_ == Backend::kTbb) impl_ = std::make_unique<ExecutorImpl>(threads_);
}

Executor::~Executor() = default;
Executor::Executor(Executor&&) noexcept = default;
Executor& Executor::operator=(Executor&&) noexcept = default;

void Executor::for_each_chunk(uint64_t n, uint32_t grain, ChunkFn fn) const {
  if (n == 0) return;
  grain = std::max<uint32_t>(grain, 1);
  const uint32_t chunks = chunk_count(n, grain);
  auto run = [&](uint32_t c) {
    const uint64_t begin = static_cast<uint64_t>(c) * grain;
    const uint64_t end = std::min<uint64_t>(begin + grain, n);
    fn(static_cast<uint32_t>(begin), static_cast<uint32_t>(end), c);
  };
  if (chunks == 1 || threads_ == 1 || backend_ == Backend::kSerial) {
    for (uint32_t c = 0; c < chunks; ++c) run(c);
    return;
  }
#if IMPACT_HAVE_TBB
  if (backend_ == Backend::kTbb) {
    impl_->arena.execute([&] {
      tbb::parallel_for(tbb::blocked_range<uint32_t>(0, chunks, 1),
                        [&](const tbb::blocked_range<uint32_t>& r) {
                          for (uint32_t c = r.begin(); c != r.end(); ++c) run(c);
                        });
    });
    return;
  }
#endif
#if IMPACT_HAVE_OPENMP
  if (backend_ == Backend::kOpenMP) {
    const int t = static_cast<int>(std::min<uint32_t>(threads_, chunks));
#pragma omp parallel for schedule(dynamic, 1) num_threads(t)
    for (int64_t c = 0; c < static_cast<int64_t>(chunks); ++c) run(static_cast<uint32_t>(c));
    return;
  }
#endif
  for (uint32_t c = 0; c < chunks; ++c) run(c);
}

}  // namespace impact::host
