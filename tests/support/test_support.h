// Shared helpers of the test suite: problem-size scaling, the list of thread
// configurations every determinism check runs over, Status matchers, float ulp
// distance, a snapshot of a world's observable state, and a golden-section minimiser.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <initializer_list>
#include <memory>
#include <string>
#include <vector>

#include "impact/impact.h"

#ifndef IMPACT_TEST_SANITIZE
#define IMPACT_TEST_SANITIZE 0
#endif

namespace impact::test {

/// True in a -DIMPACT_SANITIZE=ON build, for the tests that shorten their runs there
/// (determinism, extremes, broad-phase stage): the same checks over fewer steps.
inline constexpr bool kSanitized = IMPACT_TEST_SANITIZE != 0;

/// x rounded to float and back: what a kernel sees of a double input. Through a
/// volatile float, because GCC 12 at -O3 folds (double)(float) of two adjacent
/// values (SLP vectorisation of a cvtpd2ps / cvtps2pd pair) into a plain copy: seen
/// with Eigen's test::round_to_float(v) and with a Vector3d built from three
/// static_cast<float> (x and y kept unrounded, z rounded) on every -march tried,
/// which left triangle_triangle_test's "rounded" inputs unrounded 1e5 from the
/// origin (the kernel and the reference then saw different triangles).
inline double round_to_float(double x) {
  volatile float f = static_cast<float>(x);
  return f;
}
/// round_to_float of every coefficient.
template <class M>
auto round_to_float(const Eigen::MatrixBase<M>& m) {
  typename M::PlainObject r = m;
  for (Eigen::Index i = 0; i < r.size(); ++i) r.data()[i] = round_to_float(r.data()[i]);
  return r;
}

/// IMPACT_TEST_INTENSITY (default 1, clamped to [1, 1000]): multiplies problem sizes.
/// Only scales up: the default sizes are the smallest that still exercise every
/// chunking path (several 2^11..2^16-element chunks) and the tests' thresholds.
inline double intensity() {
  const char* s = std::getenv("IMPACT_TEST_INTENSITY");
  if (s == nullptr || *s == '\0') return 1.0;
  const double v = std::atof(s);
  if (!(v > 0.0)) return 1.0;
  return std::clamp(v, 1.0, 1000.0);
}

/// base * intensity, at least `at_least`.
inline uint32_t scaled(uint32_t base, uint32_t at_least = 1) {
  const double v = std::round(static_cast<double>(base) * intensity());
  return std::max(at_least, static_cast<uint32_t>(std::min(v, 4.0e9)));
}

/// Lanes per scenario of a test whose double references dominate its run time: base
/// scaled by IMPACT_TEST_INTENSITY; under the sanitizers a quarter (at least 2), the
/// kernel running the same code on fewer lanes.
inline int scenario_lanes(uint32_t base) {
  return static_cast<int>(kSanitized ? std::max((base + 3) / 4, 2u) : scaled(base));
}

/// One way of running the passes.
struct ExecCase {
  Backend backend;
  uint32_t threads;
};

inline std::string to_string(const ExecCase& c) {
  return std::string(impact::to_string(c.backend)) + "/" + std::to_string(c.threads);
}

/// The thread counts of exec_cases(): 1, 2, 3 and 8, or the comma-separated list in the
/// environment variable IMPACT_TEST_THREADS (e.g. 1,2,3,8,16 on a 16-core machine, where
/// the threads really run at once). A malformed list fails loudly, never silently
/// tests fewer cases.
inline std::vector<uint32_t> test_thread_counts() {
  const char* env = std::getenv("IMPACT_TEST_THREADS");
  if (env == nullptr || *env == '\0') return {1u, 2u, 3u, 8u};
  std::vector<uint32_t> out;
  const std::string s(env);
  for (size_t pos = 0; pos <= s.size();) {
    const size_t comma = std::min(s.find(',', pos), s.size());
    const std::string item = s.substr(pos, comma - pos);
    char* end = nullptr;
    const long v = item.empty() ? 0 : std::strtol(item.c_str(), &end, 10);
    if (item.empty() || *end != '\0' || v < 1 || v > 1024) {
      ADD_FAILURE() << "IMPACT_TEST_THREADS='" << env << "': expected thread counts in 1..1024";
      return {1u, 2u, 3u, 8u};
    }
    out.push_back(static_cast<uint32_t>(v));
    pos = comma + 1;
  }
  return out;
}

/// Serial, then every built-in parallel backend with each of test_thread_counts().
inline std::vector<ExecCase> exec_cases() {
  std::vector<ExecCase> out{{Backend::kSerial, 1}};
  for (Backend b : {Backend::kTbb, Backend::kOpenMP}) {
    if (!backend_available(b)) continue;
    for (uint32_t t : test_thread_counts()) out.push_back({b, t});
  }
  return out;
}

/// run(ExecCase) -> a state hash: the same value for every case of exec_cases().
template <class Run>
void expect_same_for_every_exec_case(Run&& run) {
  const std::vector<ExecCase> cases = exec_cases();
  const auto want = run(cases.front());
  for (const ExecCase& c : cases) EXPECT_EQ(run(c), want) << to_string(c);
}

inline ::testing::AssertionResult IsOk(const Status& s) {
  if (s.ok()) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "status " << impact::to_string(s.code()) << ": " << s.message();
}

/// Checks code and that the message contains every fragment.
inline ::testing::AssertionResult IsError(const Status& s, StatusCode code,
                                          std::initializer_list<const char*> fragments = {}) {
  if (s.code() != code)
    return ::testing::AssertionFailure() << "expected " << impact::to_string(code) << ", got "
                                         << impact::to_string(s.code()) << " (" << s.message() << ")";
  for (const char* f : fragments)
    if (s.message().find(f) == std::string::npos)
      return ::testing::AssertionFailure() << "message '" << s.message() << "' lacks '" << f << "'";
  return ::testing::AssertionSuccess();
}

#define IMPACT_ASSERT_OK(expr) ASSERT_TRUE(::impact::test::IsOk(expr))
#define IMPACT_EXPECT_OK(expr) EXPECT_TRUE(::impact::test::IsOk(expr))

/// Distance in units in the last place between two finite floats (0 = equal bits,
/// +0 and -0 count as equal).
inline uint32_t ulp_distance(float a, float b) {
  if (a == b) return 0;
  auto ordered = [](float f) {
    const int32_t i = std::bit_cast<int32_t>(f);
    return i < 0 ? static_cast<int64_t>(INT32_MIN) - i : static_cast<int64_t>(i);
  };
  const int64_t d = ordered(a) - ordered(b);
  return static_cast<uint32_t>(std::min<int64_t>(d < 0 ? -d : d, UINT32_MAX));
}

/// A world made from desc; fails the test (returns null) when creation fails.
inline std::unique_ptr<World> make_world(const WorldDesc& desc) {
  std::unique_ptr<World> w;
  const Status s = World::create(desc, &w);
  EXPECT_TRUE(IsOk(s));
  return w;
}

/// Gravity-free world: isolates collision tests from integration.
inline WorldDesc zero_gravity_desc() {
  WorldDesc d;
  d.gravity = Eigen::Vector3f::Zero();
  return d;
}

/// Every observable per-body array plus counts and the hash, for "unchanged" checks.
struct WorldSnapshot {
  size_t body_count = 0, plane_count = 0;
  uint64_t hash = 0;
  std::vector<float> floats;
  std::vector<uint32_t> words;
  friend bool operator==(const WorldSnapshot&, const WorldSnapshot&) = default;
};

inline WorldSnapshot snapshot(const World& w) {
  WorldSnapshot s;
  s.body_count = w.body_count();
  s.plane_count = w.plane_count();
  s.hash = w.state_hash();
  const BodyArrays b = w.bodies();
  for (auto sp : {b.pos_x, b.pos_y, b.pos_z, b.vel_x, b.vel_y, b.vel_z, b.inv_mass, b.radius, b.restitution})
    s.floats.insert(s.floats.end(), sp.begin(), sp.end());
  for (auto sp : {b.layer, b.mask}) s.words.insert(s.words.end(), sp.begin(), sp.end());
  for (const BodyHandle& h : b.handles) {
    s.words.push_back(h.index);
    s.words.push_back(h.generation);
  }
  return s;
}

/// The minimum of f over [lo, hi] for a unimodal (e.g. convex) f: iters golden-section
/// steps, then the bracket's ends; *arg gets its argument. The tests' 1-D reference
/// minimiser (nested for 2-D and 3-D minima of convex distances).
template <class Fn>
double golden_section_min(Fn f, double lo, double hi, int iters, double* arg) {
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo), f1 = f(x1), f2 = f(x2);
  for (int it = 0; it < iters; ++it) {
    if (f1 < f2) {
      hi = x2, x2 = x1, f2 = f1, x1 = hi - g * (hi - lo), f1 = f(x1);
    } else {
      lo = x1, x1 = x2, f1 = f2, x2 = lo + g * (hi - lo), f2 = f(x2);
    }
  }
  double best = std::min(f1, f2), at = f1 < f2 ? x1 : x2;
  for (double c : {lo, hi}) {
    const double fc = f(c);
    if (fc < best) best = fc, at = c;
  }
  *arg = at;
  return best;
}

}  // namespace impact::test
