// The only place threads exist. Passes run as for_each_chunk(n, grain, fn): the
// index space [0, n) is cut into ceil(n / grain) chunks whose boundaries depend
// on n and grain alone, never on the number of workers, and fn(begin, end, chunk)
// runs once per chunk on some worker. A kernel that writes only its own chunk's
// outputs therefore produces the same bytes on 1 or 64 threads, and per-chunk
// partial results combined in chunk order are deterministic too.
// Passes with a variable number of outputs build on this with the count -> scan ->
// write helpers of host/scan.h.
#pragma once

#include <cstdint>
#include <memory>
#include <type_traits>
#include <utility>

#include "impact/types.h"

namespace impact::host {

/// Non-owning reference to a callable (two words, no allocation).
template <class Sig>
class FunctionRef;

template <class R, class... Args>
class FunctionRef<R(Args...)> {
 public:
  template <class F>
    requires(!std::is_same_v<std::remove_cvref_t<F>, FunctionRef>)
  FunctionRef(F&& f)  // NOLINT: implicit by design
      : obj_(const_cast<void*>(static_cast<const void*>(std::addressof(f)))),
        call_([](void* o, Args... args) -> R {
          return (*static_cast<std::remove_reference_t<F>*>(o))(std::forward<Args>(args)...);
        }) {}
  R operator()(Args... args) const { return call_(obj_, std::forward<Args>(args)...); }

 private:
  void* obj_;
  R (*call_)(void*, Args...);
};

using ChunkFn = FunctionRef<void(uint32_t begin, uint32_t end, uint32_t chunk)>;

/// Number of chunks for_each_chunk(n, grain, ...) makes.
inline uint32_t chunk_count(uint64_t n, uint32_t grain) {
  return static_cast<uint32_t>((n + grain - 1) / grain);
}

class ExecutorImpl;

/// A thread runtime plus a worker count.
class Executor {
 public:
  /// backend kDefault resolves to the build's IMPACT_THREADS choice; threads 0 = all.
  explicit Executor(Backend backend = Backend::kDefault, uint32_t threads = 0);
  ~Executor();
  Executor(Executor&&) noexcept;
  Executor& operator=(Executor&&) noexcept;

  void for_each_chunk(uint64_t n, uint32_t grain, ChunkFn fn) const;

  /// The resolved backend (never kDefault) and the threads it runs (TBB: at most
  /// the hardware threads; OpenMP may oversubscribe).
  Backend backend() const { return backend_; }
  uint32_t threads() const { return threads_; }

 private:
  Backend backend_;
  uint32_t threads_;
  std::unique_ptr<ExecutorImpl> impl_;
};

/// Resolves kDefault to the build default; false if the backend is not built in.
bool resolve_backend(Backend requested, Backend* out);

}  // namespace impact::host
