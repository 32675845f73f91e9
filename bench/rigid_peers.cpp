// impact_rigidbench: one rigid-body scene stepped side by side by impact (the soft-step
// solver) and the peer engines found at build time, Bullet and ODE
// (bench/rigid_peers.h). Each engine holds its own copy of the scene; the engines take
// turns, a block of steps each, so that the noise of a shared machine falls on all of
// them alike. Reported per engine: the median and mean wall time of one step, how far
// the top box(es) moved from their start, the largest sideways (x-z) drift of any
// box, how many boxes moved more than 1 cm, and the kinetic energy at the end.
//
// Scenes: the stacking scenes of bench/scenes/scenes.h (1 m cubes on a floor plane).
// Settings that map between engines are the same: dt 1/60 s, gravity, the pair's
// friction sqrt(f_a f_b) = 0.6 and restitution 0, sleeping off; the iteration counts
// (impact's substeps, Bullet's and ODE's solver iterations) are options.
//
// Exit status: 0 on success, 1 when an engine fails, 2 on bad command-line arguments.
#include "bench/rigid_peers.h"

#include <algorithm>
#include <chrono>
#include <cinttypes>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "bench/cli_args.h"
#include "bench/scenes/scenes.h"
#include "bench/stats.h"
#include "impact/impact.h"

#ifndef IMPACT_RIGIDBENCH_HAVE_BULLET
#define IMPACT_RIGIDBENCH_HAVE_BULLET 0
#endif
#ifndef IMPACT_RIGIDBENCH_HAVE_ODE
#define IMPACT_RIGIDBENCH_HAVE_ODE 0
#endif

namespace {

using Clock = std::chrono::steady_clock;
using impact::bench::rigid::BoxState;
using impact::bench::rigid::Engine;
using impact::bench::rigid::PeerScene;

constexpr int kExitError = 1;
constexpr std::string_view kScenes[] = {"pyramid", "wall", "pyramids", "column"};

struct Options {
  std::string scene = "pyramid";
  std::optional<uint32_t> bodies;  // unset: the scene's default
  uint32_t steps = 600;
  uint32_t block = 10;
  uint32_t threads = 1;
  uint32_t substeps = 4;
  bool sleep = false;
  uint32_t bullet_iterations = 10;
  uint32_t ode_iterations = 20;
  std::vector<std::string> engines;  // empty: every engine built in
};

std::vector<std::string> available_engines() {
  std::vector<std::string> e = {"impact"};
  if (IMPACT_RIGIDBENCH_HAVE_BULLET) e.emplace_back("bullet");
  if (IMPACT_RIGIDBENCH_HAVE_ODE) e.emplace_back("ode");
  return e;
}

std::string join(const std::vector<std::string>& v) {
  std::string out;
  for (const std::string& s : v) out += (out.empty() ? "" : ",") + s;
  return out;
}

void print_usage(std::FILE* f) {
  std::fprintf(f,
               "usage: impact_rigidbench [options]\n"
               "Steps one rigid-body scene in impact and in the peer engines, in turns, and\n"
               "reports time per step and how well each stack stands.\n\n"
               "  --scene NAME         pyramid | wall | pyramids | column (default pyramid;\n"
               "                       bench/scenes/scenes.h, impact_bench --help)\n"
               "  --bodies N           boxes, >= 1 (default: the scene's; the largest complete\n"
               "                       structure of at most N boxes)\n"
               "  --steps N            steps of 1/60 s, >= 1 (default 600 = 10 s)\n"
               "  --block N            steps an engine runs before the next takes its turn (default 10)\n"
               "  --engines LIST       comma-separated, from %s (default: all of them)\n"
               "  --threads N          impact's worker threads, 0 = all hardware threads (default 1);\n"
               "                       the peers run on one thread\n"
               "  --substeps N         impact's soft-step substeps (default 4)\n"
               "  --sleep              impact's islands and sleeping on (default off, as the peers')\n"
               "  --bullet-iterations N  Bullet's solver iterations (default 10)\n"
               "  --ode-iterations N   ODE's quickstep iterations (default 20)\n"
               "  --help               this text\n\n"
               "Output ends with one line per engine:\n"
               "'csv: engine,threads,boxes,steps,ms_median,ms_mean,top_moved_m,max_sideways_m,moved_1cm,ke_j'.\n"
               "Exit status: 0 ok, 1 engine error, 2 bad arguments.\n",
               join(available_engines()).c_str());
}

using impact::bench::parse_unsigned;

// Returns 0 and fills *o, or prints the error and returns impact::bench::kExitUsage;
// impact::bench::kAskedForHelp for --help.
int parse_args(int argc, char** argv, Options* o) {
  for (impact::bench::ArgCursor cur(argc, argv, "impact_rigidbench"); cur.next();) {
    auto fail = [&](const std::string& msg) { return cur.fail(msg); };
    const std::string_view arg = cur.name();
    const std::string_view& value = cur.value();  // set by need_value()
    auto need_value = [&] { return cur.need_value(); };
    auto number = [&](uint32_t* out, uint32_t min_value) -> int {
      if (!need_value()) return fail(std::string(arg) + " needs a value");
      if (!parse_unsigned(value, out) || *out < min_value)
        return fail(std::string(arg) + " needs an integer >= " + std::to_string(min_value) + ", got '" +
                    std::string(value) + "'");
      return 0;
    };
    if (arg == "--help" || arg == "-h") {
      return impact::bench::kAskedForHelp;
    } else if (arg == "--scene") {
      if (!need_value()) return fail("--scene needs a value");
      if (std::find(std::begin(kScenes), std::end(kScenes), value) == std::end(kScenes))
        return fail("unknown scene '" + std::string(value) + "' (known: pyramid, wall, pyramids, column)");
      o->scene = std::string(value);
    } else if (arg == "--bodies") {
      uint32_t n = 0;
      if (int r = number(&n, 1)) return r;
      o->bodies = n;
    } else if (arg == "--steps") {
      if (int r = number(&o->steps, 1)) return r;
    } else if (arg == "--block") {
      if (int r = number(&o->block, 1)) return r;
    } else if (arg == "--threads") {
      if (int r = number(&o->threads, 0)) return r;
    } else if (arg == "--substeps") {
      if (int r = number(&o->substeps, 1)) return r;
    } else if (arg == "--sleep") {
      o->sleep = true;
    } else if (arg == "--bullet-iterations") {
      if (int r = number(&o->bullet_iterations, 1)) return r;
    } else if (arg == "--ode-iterations") {
      if (int r = number(&o->ode_iterations, 1)) return r;
    } else if (arg == "--engines") {
      if (!need_value()) return fail("--engines needs a value");
      o->engines.clear();
      const std::vector<std::string> known = available_engines();
      size_t pos = 0;
      while (pos <= value.size()) {
        const size_t comma = std::min(value.find(',', pos), value.size());
        const std::string name(value.substr(pos, comma - pos));
        if (std::find(known.begin(), known.end(), name) == known.end())
          return fail("engine '" + name + "' is not built in (available: " + join(known) + ")");
        if (std::find(o->engines.begin(), o->engines.end(), name) == o->engines.end()) o->engines.push_back(name);
        pos = comma + 1;
      }
    } else {
      return fail("unknown option '" + std::string(cur.raw()) + "'");
    }
  }
  if (o->engines.empty()) o->engines = available_engines();
  return 0;
}

// The scene's bodies as plain boxes for the peers; fails unless every body is a
// dynamic cube (the kinetic energy below assumes the isotropic inertia of a cube).
bool to_peer_scene(const impact::bench::Scene& s, PeerScene* out) {
  for (const impact::BodyDesc& d : s.bodies) {
    if (!d.shape.valid() || d.shape.index >= s.shapes.size() || d.inv_mass <= 0.0f) return false;
    const impact::bench::SceneShape& sh = s.shapes[d.shape.index];
    if (sh.type != impact::ShapeType::kBox || sh.half_extents.minCoeff() != sh.half_extents.maxCoeff()) return false;
    impact::bench::rigid::BoxBody b{};
    for (int k = 0; k < 3; ++k) {
      b.position[k] = d.position[k];
      b.half_extents[k] = sh.half_extents[k];
    }
    b.orientation[0] = d.orientation.x();
    b.orientation[1] = d.orientation.y();
    b.orientation[2] = d.orientation.z();
    b.orientation[3] = d.orientation.w();
    b.mass = 1.0f / d.inv_mass;
    b.friction = d.friction;
    b.restitution = d.restitution;
    out->boxes.push_back(b);
  }
  for (const impact::PlaneDesc& p : s.planes) {
    const Eigen::Vector3f n = p.normal.normalized();
    out->planes.push_back({{n.x(), n.y(), n.z()}, p.offset / p.normal.norm(), p.friction, p.restitution});
  }
  for (int k = 0; k < 3; ++k) out->gravity[k] = s.gravity[k];
  return true;
}

// impact through its public API: a World with the soft step; sleeping off unless --sleep.
class ImpactEngine final : public Engine {
 public:
  static std::unique_ptr<ImpactEngine> create(const impact::bench::Scene& scene, const Options& o) {
    impact::WorldDesc desc;
    desc.gravity = scene.gravity;
    desc.threads = o.threads;
    desc.solver.kind = impact::SolverKind::kSoftStep;
    desc.solver.substeps = o.substeps;
    desc.solver.sleep = o.sleep;
    auto e = std::unique_ptr<ImpactEngine>(new ImpactEngine());
    impact::Status s = impact::World::create(desc, &e->world_);
    if (s.ok()) s = impact::bench::add_scene_shapes(scene, &e->world_->shapes());
    e->handles_.resize(scene.bodies.size());
    if (s.ok()) s = e->world_->create_bodies(scene.bodies, e->handles_);
    std::vector<impact::PlaneHandle> planes(scene.planes.size());
    if (s.ok()) s = e->world_->create_planes(scene.planes, planes);
    if (!s.ok()) {
      std::fprintf(stderr, "impact_rigidbench: impact setup failed: %s\n", s.message().c_str());
      return nullptr;
    }
    return e;
  }
  const char* name() const override { return "impact"; }
  std::string settings() const override {
    const impact::SolverDesc& s = world_->desc().solver;
    const std::string hertz = s.contact_hertz > 0.0f ? std::to_string(static_cast<int>(s.contact_hertz)) + " Hz"
                                                     : "automatic stiffness";
    return "impact soft step, " + std::to_string(s.substeps) + " substeps, contact " + hertz +
           (s.sleep ? ", sleeping" : "") + ", " + std::to_string(world_->threads()) +
           " thread(s) (" + impact::to_string(world_->backend()) + ")";
  }
  bool step() override {
    const impact::Status s = world_->step();
    if (!s.ok()) std::fprintf(stderr, "impact_rigidbench: World::step failed: %s\n", s.message().c_str());
    return s.ok();
  }
  void read(std::vector<BoxState>* out) const override {
    const size_t n = handles_.size();
    std::vector<Eigen::Vector3f> p(n), v(n), w(n);
    if (!world_->get_positions(handles_, p).ok() || !world_->get_velocities(handles_, v).ok() ||
        !world_->get_angular_velocities(handles_, w).ok()) {
      std::fprintf(stderr, "impact_rigidbench: reading impact's bodies failed\n");
    }
    out->resize(n);
    for (size_t i = 0; i < n; ++i)
      (*out)[i] = BoxState{{p[i].x(), p[i].y(), p[i].z()}, {v[i].x(), v[i].y(), v[i].z()}, {w[i].x(), w[i].y(), w[i].z()}};
  }
  uint64_t state_hash() const { return world_->state_hash(); }
  uint32_t threads() const { return world_->threads(); }

 private:
  ImpactEngine() = default;
  std::unique_ptr<impact::World> world_;
  std::vector<impact::BodyHandle> handles_;
};

using impact::bench::median;

// How the boxes stand after the run, against their start.
struct Standing {
  double top_moved = 0.0;      // m, the largest displacement of a top box
  double max_sideways = 0.0;   // m, the largest x-z displacement of any box
  uint32_t moved_1cm = 0;      // boxes displaced more than 1 cm
  double kinetic_energy = 0.0; // J, translation + rotation
  bool finite = true;
};

Standing measure(const PeerScene& scene, const std::vector<BoxState>& end) {
  Standing s;
  // The top boxes: those starting within 1 cm of the highest (one for pyramid, wall
  // and column; every apex of "pyramids").
  float top_y = -INFINITY;
  for (const auto& b : scene.boxes) top_y = std::max(top_y, b.position[1]);
  for (size_t i = 0; i < end.size(); ++i) {
    const auto& b = scene.boxes[i];
    const BoxState& e = end[i];
    double d2 = 0.0, v2 = 0.0, w2 = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double d = static_cast<double>(e.position[k]) - b.position[k];
      d2 += d * d;
      v2 += static_cast<double>(e.velocity[k]) * e.velocity[k];
      w2 += static_cast<double>(e.angular_velocity[k]) * e.angular_velocity[k];
      s.finite = s.finite && std::isfinite(e.position[k]) && std::isfinite(e.velocity[k]);
    }
    const double moved = std::sqrt(d2);
    const double dx = static_cast<double>(e.position[0]) - b.position[0];
    const double dz = static_cast<double>(e.position[2]) - b.position[2];
    s.max_sideways = std::max(s.max_sideways, std::hypot(dx, dz));
    if (b.position[1] >= top_y - 0.01f) s.top_moved = std::max(s.top_moved, moved);
    if (moved > 0.01) ++s.moved_1cm;
    // A cube of edge a: I = m a^2 / 6 about any axis through its centre.
    const double a = 2.0 * b.half_extents[0];
    s.kinetic_energy += 0.5 * b.mass * v2 + 0.5 * (b.mass * a * a / 6.0) * w2;
  }
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  if (int r = parse_args(argc, argv, &opt); r != 0) {
    if (r != impact::bench::kAskedForHelp) return r;
    print_usage(stdout);
    return 0;
  }

  impact::bench::Scene scene;
  const uint32_t requested = opt.bodies.value_or(impact::bench::scene_default_bodies(opt.scene));
  if (impact::Status s = impact::bench::make_scene(opt.scene, requested, impact::bench::kDefaultSeed, &scene);
      !s.ok()) {
    std::fprintf(stderr, "impact_rigidbench: make_scene failed: %s\n", s.message().c_str());
    return kExitError;
  }
  PeerScene peer;
  if (!to_peer_scene(scene, &peer)) {
    std::fprintf(stderr, "impact_rigidbench: scene '%s' is not made of dynamic cubes\n", opt.scene.c_str());
    return kExitError;
  }

  std::vector<std::unique_ptr<Engine>> engines;
  ImpactEngine* impact_engine = nullptr;
  for (const std::string& name : opt.engines) {
    if (name == "impact") {
      auto e = ImpactEngine::create(scene, opt);
      if (!e) return kExitError;
      impact_engine = e.get();
      engines.push_back(std::move(e));
    }
#if IMPACT_RIGIDBENCH_HAVE_BULLET
    if (name == "bullet") engines.push_back(impact::bench::rigid::make_bullet_engine(peer, opt.bullet_iterations));
#endif
#if IMPACT_RIGIDBENCH_HAVE_ODE
    if (name == "ode") engines.push_back(impact::bench::rigid::make_ode_engine(peer, opt.ode_iterations));
#endif
  }

  std::printf("impact_rigidbench %d.%d.%d: scene %s, %zu boxes, %zu planes, %u steps of 1/60 s (%.4g s),\n"
              "  engines in turns of %u steps; hardware threads %u\n",
              IMPACT_VERSION_MAJOR, IMPACT_VERSION_MINOR, IMPACT_VERSION_PATCH, opt.scene.c_str(), peer.boxes.size(),
              peer.planes.size(), opt.steps, opt.steps * static_cast<double>(peer.dt), opt.block,
              impact::hardware_threads());
  for (const auto& e : engines) std::printf("  %-7s %s\n", e->name(), e->settings().c_str());
  std::fflush(stdout);

  // --- run: each engine a block of steps in turn --------------------------------------
  std::vector<std::vector<double>> ms(engines.size());
  for (auto& v : ms) v.reserve(opt.steps);
  for (uint32_t done = 0; done < opt.steps; done += opt.block) {
    const uint32_t n = std::min(opt.block, opt.steps - done);
    for (size_t k = 0; k < engines.size(); ++k)
      for (uint32_t i = 0; i < n; ++i) {
        const Clock::time_point t0 = Clock::now();
        const bool ok = engines[k]->step();
        ms[k].push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
        if (!ok) {
          std::fprintf(stderr, "impact_rigidbench: %s failed at step %u\n", engines[k]->name(), done + i + 1);
          return kExitError;
        }
      }
  }

  // --- report ---------------------------------------------------------------------------
  std::printf("\n%-8s %9s %9s %12s %15s %11s %12s\n", "engine", "ms/step", "mean", "top moved m", "max sideways m",
              "moved >1cm", "KE J");
  std::vector<double> medians(engines.size());
  std::vector<std::string> csv;
  bool all_finite = true;
  for (size_t k = 0; k < engines.size(); ++k) {
    std::vector<BoxState> end;
    engines[k]->read(&end);
    const Standing s = measure(peer, end);
    all_finite = all_finite && s.finite;
    medians[k] = median(ms[k]);
    double mean = 0.0;
    for (double x : ms[k]) mean += x;
    mean /= static_cast<double>(ms[k].size());
    const uint32_t threads = engines[k].get() == impact_engine ? impact_engine->threads() : 1u;
    std::printf("%-8s %9.3f %9.3f %12.4f %15.4f %11u %12.4g%s\n", engines[k]->name(), medians[k], mean, s.top_moved,
                s.max_sideways, s.moved_1cm, s.kinetic_energy, s.finite ? "" : "  (not finite)");
    char line[256];
    std::snprintf(line, sizeof line, "csv: %s,%u,%zu,%u,%.4f,%.4f,%.5f,%.5f,%u,%.5g", engines[k]->name(), threads,
                  peer.boxes.size(), opt.steps, medians[k], mean, s.top_moved, s.max_sideways, s.moved_1cm,
                  s.kinetic_energy);
    csv.emplace_back(line);
  }
  if (impact_engine != nullptr) {
    std::printf("\nimpact state_hash %016" PRIx64 "\n", impact_engine->state_hash());
    double fastest_peer = INFINITY;
    const char* fastest_name = nullptr;
    for (size_t k = 0; k < engines.size(); ++k)
      if (engines[k].get() != impact_engine && medians[k] < fastest_peer) {
        fastest_peer = medians[k];
        fastest_name = engines[k]->name();
      }
    for (size_t k = 0; k < engines.size(); ++k)
      if (engines[k].get() == impact_engine && fastest_name != nullptr && medians[k] > 0.0)
        std::printf("impact per step: %.3gx the speed of the fastest peer (%s)\n", fastest_peer / medians[k],
                    fastest_name);
  }
  for (const std::string& l : csv) std::printf("%s\n", l.c_str());
  return all_finite ? 0 : kExitError;
}
