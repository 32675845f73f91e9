// impact_bench: whole-step throughput of one scene.
//
// Builds a scene (bench/scenes/scenes.h), steps it a fixed number of times and
// reports the median wall time per step and per pass, mean pair and contact counts,
// body-steps per second and the final state hash. `--expect-hash` turns the run into
// a regression check: a different hash (a determinism or behaviour change) fails it.
//
// Exit status: 0 on success, 1 when the library reports an error or the hash does not
// match, 2 on bad command-line arguments.
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "bench/cli_args.h"
#include "bench/scenes/scenes.h"
#include "bench/stats.h"
#include "impact/impact.h"

namespace {

using Clock = std::chrono::steady_clock;
using impact::bench::Scene;

constexpr int kExitError = 1;

struct Options {
  std::string scene = "box";
  std::optional<uint32_t> bodies;  // unset: the scene's default (scene_default_bodies)
  uint32_t steps = 300;
  uint32_t threads = 0;  // 0 = all hardware threads
  impact::Backend backend = impact::Backend::kDefault;
  impact::BroadPhaseKind broad_phase = impact::BroadPhaseKind::kGrid;
  std::optional<uint32_t> iterations;  // unset: the library default
  std::optional<impact::SolverKind> solver;  // unset: the library default
  impact::ContinuousMode ccd = impact::ContinuousMode::kOff;
  bool sleep = true;
  uint64_t seed = impact::bench::kDefaultSeed;
  std::string json_path;
  std::optional<uint64_t> expect_hash;
  bool progress = true;
};

void print_usage(std::FILE* f) {
  std::fprintf(f,
               "usage: impact_bench [options]\n"
               "Steps a built-in scene and reports time per step and per pass.\n\n"
               "  --scene NAME         scene to run (default box):\n");
  for (std::string_view name : impact::bench::scene_names())
    std::fprintf(f, "                         %-9.*s %.*s\n", static_cast<int>(name.size()), name.data(),
                 static_cast<int>(impact::bench::scene_summary(name).size()),
                 impact::bench::scene_summary(name).data());
  std::fprintf(f,
               "  --bodies N           bodies, >= 1 (default: the scene's, 100000 for box, rain and\n"
               "                       uniform); pyramid, wall and pyramids build the largest\n"
               "                       complete structure of at most N boxes (pyramids: N / 55 of\n"
               "                       them, at least one); mixed adds its static mesh floor\n"
               "  --steps N            fixed steps of 1/60 s, >= 1 (default 300)\n"
               "  --threads N          worker threads, 0 = all hardware threads (default 0)\n"
               "  --backend NAME       default | tbb | openmp | serial (default: the build's)\n"
               "  --broadphase NAME    grid | lbvh | sap | brute (default grid)\n"
               "  --iterations N       jacobi velocity iterations (default: library default)\n"
               "  --solver NAME        jacobi | soft (default: soft for the rigid scenes pyramid,\n"
               "                       wall, pyramids, column, hulls and mixed, which need rotation\n"
               "                       and friction; otherwise the library default)\n"
               "  --no-sleep           soft step: islands and sleeping off (default on)\n"
               "  --ccd NAME           off | speculative: continuous collision (default off)\n"
               "  --seed N             scene seed (default %" PRIu64
               ")\n"
               "  --json FILE          also write every figure as JSON to FILE\n"
               "  --expect-hash HEX    fail (exit 1) unless the final state hash equals HEX\n"
               "  --no-progress        no progress line on stderr\n"
               "  --help               this text\n\n"
               "Output ends with a line 'csv: threads,bodies,steps,ms_per_step,hash'.\n"
               "Exit status: 0 ok, 1 library error or hash mismatch, 2 bad arguments.\n",
               impact::bench::kDefaultSeed);
}

using impact::bench::parse_unsigned;

// Returns 0 and fills *o, or prints the error and returns impact::bench::kExitUsage;
// impact::bench::kAskedForHelp for --help.
int parse_args(int argc, char** argv, Options* o) {
  for (impact::bench::ArgCursor cur(argc, argv, "impact_bench"); cur.next();) {
    auto fail = [&](const std::string& msg) { return cur.fail(msg); };
    const std::string_view arg = cur.name();
    const std::string_view& value = cur.value();  // set by need_value()
    auto need_value = [&] { return cur.need_value(); };
    auto number = [&](uint32_t* out, uint32_t min_value) -> int {
      if (!need_value()) return fail(std::string(arg) + " needs a value");
      if (!parse_unsigned(value, out)) {
        const bool digits = !value.empty() && value.find_first_not_of("0123456789") == std::string_view::npos;
        return fail(
            std::string(arg) +
            (digits ? " is out of range (max 4294967295), got '" : " needs a non-negative integer, got '") +
            std::string(value) + "'");
      }
      if (*out < min_value)
        return fail(std::string(arg) + " must be >= " + std::to_string(min_value) + ", got " +
                    std::string(value));
      return 0;
    };
    if (arg == "--help" || arg == "-h") {
      return impact::bench::kAskedForHelp;
    } else if (arg == "--bodies") {
      uint32_t n = 0;
      if (int r = number(&n, 1)) return r;
      o->bodies = n;
    } else if (arg == "--steps") {
      if (int r = number(&o->steps, 1)) return r;
    } else if (arg == "--threads") {
      if (int r = number(&o->threads, 0)) return r;
    } else if (arg == "--iterations") {
      uint32_t it = 0;
      if (int r = number(&it, 0)) return r;
      o->iterations = it;
    } else if (arg == "--no-sleep") {
      o->sleep = false;
    } else if (arg == "--solver") {
      if (!need_value()) return fail("--solver needs a value");
      if (value == "jacobi") {
        o->solver = impact::SolverKind::kJacobi;
      } else if (value == "soft") {
        o->solver = impact::SolverKind::kSoftStep;
      } else {
        return fail("--solver must be jacobi or soft, got '" + std::string(value) + "'");
      }
    } else if (arg == "--ccd") {
      if (!need_value()) return fail("--ccd needs a value");
      if (value == "off") {
        o->ccd = impact::ContinuousMode::kOff;
      } else if (value == "speculative") {
        o->ccd = impact::ContinuousMode::kSpeculative;
      } else {
        return fail("--ccd must be off or speculative, got '" + std::string(value) + "'");
      }
    } else if (arg == "--seed") {
      if (!need_value()) return fail("--seed needs a value");
      if (!parse_unsigned(value, &o->seed))
        return fail("--seed needs a non-negative integer, got '" + std::string(value) + "'");
    } else if (arg == "--scene") {
      if (!need_value()) return fail("--scene needs a value");
      const auto names = impact::bench::scene_names();
      if (std::find(names.begin(), names.end(), value) == names.end()) {
        std::string known;
        for (std::string_view k : names) known += (known.empty() ? "" : ", ") + std::string(k);
        return fail("unknown scene '" + std::string(value) + "' (known: " + known + ")");
      }
      o->scene = std::string(value);
    } else if (arg == "--backend") {
      if (!need_value()) return fail("--backend needs a value");
      if (value == "default")
        o->backend = impact::Backend::kDefault;
      else if (value == "tbb")
        o->backend = impact::Backend::kTbb;
      else if (value == "openmp")
        o->backend = impact::Backend::kOpenMP;
      else if (value == "serial")
        o->backend = impact::Backend::kSerial;
      else
        return fail("unknown backend '" + std::string(value) + "' (known: default, tbb, openmp, serial)");
      if (!impact::backend_available(o->backend))
        return fail("backend '" + std::string(value) + "' is not built into this library");
    } else if (arg == "--broadphase" || arg == "--broad-phase") {
      if (!need_value()) return fail(std::string(arg) + " needs a value");
      if (value == "grid")
        o->broad_phase = impact::BroadPhaseKind::kGrid;
      else if (value == "brute" || value == "brute-force")
        o->broad_phase = impact::BroadPhaseKind::kBruteForce;
      else if (value == "lbvh")
        o->broad_phase = impact::BroadPhaseKind::kLbvh;
      else if (value == "sap")
        o->broad_phase = impact::BroadPhaseKind::kSweepAndPrune;
      else
        return fail("unknown broad phase '" + std::string(value) + "' (known: grid, lbvh, sap, brute)");
    } else if (arg == "--json") {
      if (!need_value() || value.empty()) return fail("--json needs a file name");
      o->json_path = std::string(value);
    } else if (arg == "--expect-hash") {
      if (!need_value()) return fail("--expect-hash needs a value");
      uint64_t h = 0;
      if (!parse_unsigned(value, &h, 16))
        return fail("--expect-hash needs a hex number, got '" + std::string(value) + "'");
      o->expect_hash = h;
    } else if (arg == "--no-progress") {
      if (cur.has_value()) return fail("--no-progress takes no value");
      o->progress = false;
    } else {
      return fail("unknown option '" + std::string(cur.raw()) + "'");
    }
  }
  return 0;
}

using impact::bench::median;

double mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}

// Progress on stderr: on a terminal at most 4 updates a second, rewritten in place;
// otherwise (CI logs) one line per 10% and only once the run has lasted 2 s, so
// short runs print nothing.
class Progress {
 public:
  Progress(bool enabled, uint32_t total)
      : enabled_(enabled),
        tty_(isatty(STDERR_FILENO) != 0),
        total_(total),
        start_(Clock::now()),
        last_(start_) {}
  void update(uint32_t done) {
    if (!enabled_) return;
    const Clock::time_point now = Clock::now();
    if (tty_) {
      if (now - last_ < std::chrono::milliseconds(250) && done != total_) return;
      std::fprintf(stderr, "\rstep %u/%u", done, total_);
      std::fflush(stderr);
      printed_ = true;
    } else {
      const uint32_t decile = static_cast<uint32_t>(uint64_t{done} * 10 / total_);
      if (decile == last_decile_) return;
      last_decile_ = decile;
      if (now - start_ < std::chrono::seconds(2) || done == total_) return;
      std::fprintf(stderr, "step %u/%u\n", done, total_);
    }
    last_ = now;
  }
  void finish() {
    if (printed_) std::fprintf(stderr, "\r%*s\r", 24, "");
  }

 private:
  bool enabled_, tty_;
  uint32_t total_;
  Clock::time_point start_, last_;
  uint32_t last_decile_ = 0;
  bool printed_ = false;
};

int library_error(const char* what, const impact::Status& s) {
  std::fprintf(stderr, "impact_bench: %s failed: %s: %s\n", what, impact::to_string(s.code()),
               s.message().c_str());
  return kExitError;
}

std::string json_escape(std::string_view s) {
  std::string out;
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += c;
    }
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  if (int r = parse_args(argc, argv, &opt); r != 0) {
    if (r != impact::bench::kAskedForHelp) return r;
    print_usage(stdout);
    return 0;
  }

  // --- setup -------------------------------------------------------------------------
  const Clock::time_point t_setup = Clock::now();
  Scene scene;
  const uint32_t requested = opt.bodies.value_or(impact::bench::scene_default_bodies(opt.scene));
  if (impact::Status s = impact::bench::make_scene(opt.scene, requested, opt.seed, &scene); !s.ok())
    return library_error("make_scene", s);
  const auto bodies = static_cast<uint32_t>(scene.bodies.size());
  impact::WorldDesc desc;
  desc.backend = opt.backend;
  desc.threads = opt.threads;
  desc.broad_phase = opt.broad_phase;
  if (opt.iterations) desc.solver.velocity_iterations = *opt.iterations;
  desc.solver.sleep = opt.sleep;
  desc.ccd.mode = opt.ccd;
  if (opt.solver)
    desc.solver.kind = *opt.solver;
  else if (scene.rigid)
    desc.solver.kind = impact::SolverKind::kSoftStep;
  std::unique_ptr<impact::World> world;
  if (impact::Status s = impact::bench::load_scene(scene, desc, &world); !s.ok())
    return library_error("world setup", s);
  const double setup_ms = std::chrono::duration<double, std::milli>(Clock::now() - t_setup).count();
  const uint32_t threads = world->threads();  // what actually runs (kDefault resolved)

  // --- run ---------------------------------------------------------------------------
  std::vector<double> step_ms, integrate, bounds, broad, narrow, solve, total;
  for (auto* v : {&step_ms, &integrate, &bounds, &broad, &narrow, &solve, &total}) v->reserve(opt.steps);
  double pairs = 0.0, contacts = 0.0, plane_contacts = 0.0, asleep = 0.0;
  Progress progress(opt.progress, opt.steps);
  for (uint32_t i = 0; i < opt.steps; ++i) {
    const Clock::time_point t0 = Clock::now();
    const impact::Status s = world->step();
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    if (!s.ok()) {
      progress.finish();
      std::fprintf(stderr, "impact_bench: step %u of %u:\n", i + 1, opt.steps);
      return library_error("World::step", s);
    }
    const impact::StepStats& st = world->last_step();
    step_ms.push_back(ms);
    integrate.push_back(st.ms.integrate);
    bounds.push_back(st.ms.bounds);
    broad.push_back(st.ms.broad_phase);
    narrow.push_back(st.ms.narrow_phase);
    solve.push_back(st.ms.solve);
    total.push_back(st.ms.total);
    pairs += static_cast<double>(st.pairs);
    contacts += static_cast<double>(st.contacts);
    plane_contacts += static_cast<double>(st.plane_contacts);
    asleep += static_cast<double>(st.asleep_bodies);
    progress.update(i + 1);
  }
  progress.finish();
  const uint64_t hash = world->state_hash();

  // --- report ------------------------------------------------------------------------
  const double n_steps = opt.steps;
  const double med = median(step_ms);
  const double body_steps_per_s = med > 0.0 ? bodies / (med * 1e-3) : 0.0;
  const char* backend = impact::to_string(world->backend());
  const char* broad_name = impact::to_string(opt.broad_phase);
  const uint32_t iterations = world->desc().solver.velocity_iterations;
  std::printf("impact_bench %d.%d.%d: scene %s, %u bodies, %zu planes, %u steps of %.6g s\n",
              IMPACT_VERSION_MAJOR, IMPACT_VERSION_MINOR, IMPACT_VERSION_PATCH, opt.scene.c_str(), bodies,
              scene.planes.size(), opt.steps, static_cast<double>(desc.fixed_dt));
  const bool soft = world->desc().solver.kind == impact::SolverKind::kSoftStep;
  std::printf("  backend %s, threads %u (hardware %u), broad phase %s, solver %s, %s %u\n", backend, threads,
              impact::hardware_threads(), broad_name, soft ? "soft step" : "jacobi",
              soft ? "substeps" : "velocity iterations", soft ? world->desc().solver.substeps : iterations);
  std::printf("  setup            %10.2f ms\n", setup_ms);
  std::printf("  ms per step      %10.3f median  (mean %.3f, min %.3f, max %.3f)\n", med, mean(step_ms),
              *std::min_element(step_ms.begin(), step_ms.end()),
              *std::max_element(step_ms.begin(), step_ms.end()));
  std::printf(
      "  ms per pass      integrate %.3f  bounds %.3f  broad_phase %.3f  narrow_phase %.3f  solve %.3f"
      "  (library total %.3f), medians\n",
      median(integrate), median(bounds), median(broad), median(narrow), median(solve), median(total));
  std::printf("  per step (mean)  %.0f pairs, %.0f contacts (%.0f body-plane), %.0f bodies asleep\n",
              pairs / n_steps, contacts / n_steps, plane_contacts / n_steps, asleep / n_steps);
  std::printf("  throughput       %.4g body-steps/s (bodies / median step time)\n", body_steps_per_s);
  std::printf("  state_hash       %016" PRIx64 "\n", hash);
  std::printf("csv: %u,%u,%u,%.4f,%016" PRIx64 "\n", threads, bodies, opt.steps, med, hash);
  std::fflush(stdout);

  if (!opt.json_path.empty()) {
    std::FILE* f = std::fopen(opt.json_path.c_str(), "w");
    if (f == nullptr) {
      std::fprintf(stderr, "impact_bench: cannot write '%s': %s\n", opt.json_path.c_str(),
                   std::strerror(errno));
      return kExitError;
    }
    std::fprintf(f,
                 "{\n"
                 "  \"tool\": \"impact_bench\",\n"
                 "  \"version\": \"%d.%d.%d\",\n"
                 "  \"scene\": \"%s\",\n"
                 "  \"seed\": %" PRIu64
                 ",\n"
                 "  \"bodies\": %u,\n"
                 "  \"planes\": %zu,\n"
                 "  \"steps\": %u,\n"
                 "  \"fixed_dt\": %.9g,\n"
                 "  \"backend\": \"%s\",\n"
                 "  \"threads\": %u,\n"
                 "  \"hardware_threads\": %u,\n"
                 "  \"broad_phase\": \"%s\",\n"
                 "  \"solver\": \"%s\",\n"
                 "  \"velocity_iterations\": %u,\n"
                 "  \"substeps\": %u,\n"
                 "  \"setup_ms\": %.6g,\n"
                 "  \"ms_per_step\": {\"median\": %.6g, \"mean\": %.6g, \"min\": %.6g, \"max\": %.6g},\n"
                 "  \"pass_ms_median\": {\"integrate\": %.6g, \"bounds\": %.6g, \"broad_phase\": %.6g, "
                 "\"narrow_phase\": %.6g, \"solve\": %.6g, \"total\": %.6g},\n"
                 "  \"mean_pairs\": %.6g,\n"
                 "  \"mean_contacts\": %.6g,\n"
                 "  \"mean_plane_contacts\": %.6g,\n"
                 "  \"body_steps_per_second\": %.6g,\n"
                 "  \"state_hash\": \"%016" PRIx64
                 "\"\n"
                 "}\n",
                 IMPACT_VERSION_MAJOR, IMPACT_VERSION_MINOR, IMPACT_VERSION_PATCH,
                 json_escape(opt.scene).c_str(), opt.seed, bodies, scene.planes.size(), opt.steps,
                 static_cast<double>(desc.fixed_dt), backend, threads, impact::hardware_threads(), broad_name,
                 soft ? "soft" : "jacobi", iterations, world->desc().solver.substeps, setup_ms, med, mean(step_ms), *std::min_element(step_ms.begin(), step_ms.end()),
                 *std::max_element(step_ms.begin(), step_ms.end()), median(integrate), median(bounds),
                 median(broad), median(narrow), median(solve), median(total), pairs / n_steps,
                 contacts / n_steps, plane_contacts / n_steps, body_steps_per_s, hash);
    const bool write_ok = std::ferror(f) == 0;
    if (std::fclose(f) != 0 || !write_ok) {
      std::fprintf(stderr, "impact_bench: error writing '%s'\n", opt.json_path.c_str());
      return kExitError;
    }
  }

  if (opt.expect_hash && *opt.expect_hash != hash) {
    std::fprintf(stderr, "impact_bench: state hash %016" PRIx64 " differs from expected %016" PRIx64 "\n",
                 hash, *opt.expect_hash);
    return kExitError;
  }
  return 0;
}
