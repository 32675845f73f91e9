// The soft step's lane kernels (kernels/solver/soft_contact.h: constraints in blocks of
// kContactLanes, one a lane) on random constraint sets: random bodies (dynamic, a
// static one, a kinematic one that moves, planes: the zero body), manifolds of 1 to 4
// points (speculative, soft and deep ones), colours whose constraints share no dynamic
// body (with padded blocks and a block of exactly one constraint) and an overflow
// colour whose constraints share bodies; cold and warm starts, materials with and
// without restitution and rolling resistance. A step's passes (warm start, biased
// solve, position integration, relax; two substeps; restitution; store) run three ways:
//   blocks  the host's schedule: each colour's blocks (FloatW), the overflow slot by slot
//   slots   every colour slot by slot (Float1), in colour order
//   ref     the AoS per-constraint kernels (tests/support/soft_contact_reference.h)
// blocks and slots must be the same bytes after every pass (bodies, stored impulses);
// both must match ref to rounding (and do to the bit where the operation order and the
// build's FMA contraction agree, which this test reports); static bodies and the zero
// body are never written.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include "kernels/solver/soft_contact.h"
// The reference without FMA contraction, as the kernels (soft_contact.cpp).
#include "kernels/narrowphase/lanes/no_contract.h"
#include "support/soft_contact_reference.h"

namespace impact::kernels {
namespace {

constexpr uint32_t W = kContactLanes;

struct Manifolds {
  std::vector<uint32_t> pair, a, b, first_point;
  std::vector<uint8_t> b_is_plane, count;
  std::vector<float> normal[3], depth, point[3], point_depth;

  ContactManifoldArrays view() {
    ContactManifoldArrays c{};
    c.pair = pair.data();
    c.a = a.data();
    c.b = b.data();
    c.b_is_plane = b_is_plane.data();
    for (int d = 0; d < 3; ++d) c.normal[d] = normal[d].data(), c.point[d] = point[d].data();
    c.depth = depth.data();
    c.count = count.data();
    c.first_point = first_point.data();
    c.point_depth = point_depth.data();
    return c;
  }
};

struct Scene {
  uint32_t body_count = 0, dynamic = 0, planes = 2;
  std::vector<SolverBody> bodies;  // body_count + 1: the zero body last
  std::vector<Sym3> ii;
  std::vector<Vec3> com;
  std::vector<float> friction, restitution, rolling, plane_friction, plane_restitution;
  Manifolds m;
  std::vector<WarmPoint> warm;
  std::vector<std::vector<uint32_t>> colours;  // manifold indices per colour; the last: overflow
  SoftParams p{};
};

Quat random_rotation(std::mt19937& g) {
  std::normal_distribution<float> nd(0.0f, 1.0f);
  return normalize({nd(g), nd(g), nd(g), nd(g)});
}

Scene make_scene(uint32_t seed, bool warm) {
  std::mt19937 g(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), u01(0.0f, 1.0f);
  std::normal_distribution<float> nd(0.0f, 1.0f);
  Scene s;
  s.dynamic = 48;
  s.body_count = s.dynamic + 2;  // then a static body and a kinematic one
  s.bodies.resize(s.body_count + 1);
  s.ii.resize(s.body_count);
  s.com.resize(s.body_count);
  for (uint32_t i = 0; i < s.body_count; ++i) {
    SolverBody& b = s.bodies[i];
    b = SolverBody{};
    const bool dyn = i < s.dynamic, kinematic = i == s.dynamic + 1;
    b.inv_mass = dyn ? 0.2f + 2.0f * u01(g) : 0.0f;
    if (dyn || kinematic) {
      b.v = {2 * u(g), 2 * u(g), 2 * u(g)};
      b.w = {3 * u(g), 3 * u(g), 3 * u(g)};
      b.dp = {0.01f * u(g), 0.01f * u(g), 0.01f * u(g)};
      b.dq = normalize({0.02f * u(g), 0.02f * u(g), 0.02f * u(g), 1.0f});
    } else {
      b.dq = {0, 0, 0, 1};
    }
    s.ii[i] = dyn ? rotate_diagonal(to_matrix(random_rotation(g)), {0.5f + 2 * u01(g), 0.5f + 2 * u01(g),
                                                                  0.5f + 2 * u01(g)})
                  : Sym3{0, 0, 0, 0, 0, 0};
    s.com[i] = {5 * u(g), 5 * u(g), 5 * u(g)};
    s.friction.push_back(0.2f + 0.8f * u01(g));
    s.restitution.push_back(g() % 2 == 0 ? 0.0f : 0.1f + 0.8f * u01(g));
    s.rolling.push_back(g() % 3 == 0 ? 0.05f * u01(g) : 0.0f);
  }
  s.bodies[s.body_count] = SolverBody{};
  s.bodies[s.body_count].dq = {0, 0, 0, 1};
  for (uint32_t k = 0; k < s.planes; ++k) {
    s.plane_friction.push_back(0.3f + 0.5f * u01(g));
    s.plane_restitution.push_back(k == 0 ? 0.0f : 0.5f);
  }
  s.p = soft_params(1.0f / 60.0f, 2, 0.0f, 10.0f);
  s.p.slop = 0.005f;
  s.p.max_push_speed = 3.0f;
  s.p.restitution_threshold = 0.5f;
  s.p.warm_start = 1.0f;
  const float deep = s.p.max_push_speed * s.p.dt;

  auto add_manifold = [&](uint32_t a, uint32_t b, bool plane) {
    Manifolds& m = s.m;
    const auto id = static_cast<uint32_t>(m.a.size());
    m.pair.push_back(id);
    m.a.push_back(a);
    m.b.push_back(b);
    m.b_is_plane.push_back(plane ? 1 : 0);
    const auto count = static_cast<uint8_t>(1 + g() % 4);
    m.count.push_back(count);
    m.first_point.push_back(static_cast<uint32_t>(m.point_depth.size()));
    Vec3 n{nd(g), nd(g), nd(g)};
    n = (1.0f / length(n)) * n;
    for (int d = 0; d < 3; ++d) m.normal[d].push_back(d == 0 ? n.x : d == 1 ? n.y : n.z);
    const auto kind = static_cast<uint32_t>(g() % 6);  // 0: deep, 1: separated (speculative), else touching
    float depth = 0.0f;
    for (uint32_t j = 0; j < count; ++j) {
      const Vec3 x = s.com[a] + Vec3{u(g), u(g), u(g)};
      for (int d = 0; d < 3; ++d) m.point[d].push_back(d == 0 ? x.x : d == 1 ? x.y : x.z);
      const float pd = kind == 0 ? deep * (1.5f + u01(g)) : kind == 1 ? -0.02f * u01(g) : 0.03f * u(g);
      m.point_depth.push_back(pd);
      depth = std::max(depth, pd);
      WarmPoint w{-1.0f, 0, 0, 0, 0, 0, 0, 0};
      if (warm && g() % 4 != 0) w = {u01(g), 0.3f * u(g), 0.3f * u(g), 0.3f * u(g), 0.1f * u(g),
                                     0.05f * u(g), 0.05f * u(g), 0.05f * u(g)};
      s.warm.push_back(w);
    }
    m.depth.push_back(std::max(depth, 1e-4f));
    return id;
  };

  // Colours of 13 (two blocks at W = 8, three padding lanes), 8, 1 and 21 constraints:
  // the dynamic bodies of a colour all distinct; statics and planes shared.
  for (uint32_t size : {13u, 8u, 1u, 21u}) {
    std::vector<uint32_t> dyn(s.dynamic);
    for (uint32_t i = 0; i < s.dynamic; ++i) dyn[i] = i;
    std::shuffle(dyn.begin(), dyn.end(), g);
    uint32_t next = 0;
    std::vector<uint32_t> colour;
    for (uint32_t k = 0; k < size; ++k) {
      const auto kind = static_cast<uint32_t>(g() % 6);
      const uint32_t a = dyn[next++];
      if (kind == 0) {
        colour.push_back(add_manifold(a, static_cast<uint32_t>(g() % s.planes), true));
      } else if (kind == 1) {
        colour.push_back(add_manifold(a, s.dynamic + static_cast<uint32_t>(g() % 2), false));
      } else if (kind == 2) {
        colour.push_back(add_manifold(s.dynamic + static_cast<uint32_t>(g() % 2), a, false));  // static a
      } else {
        colour.push_back(add_manifold(a, dyn[next++], false));
      }
    }
    s.colours.push_back(colour);
  }
  // The overflow colour: bodies shared between its constraints.
  std::vector<uint32_t> overflow;
  for (uint32_t k = 0; k < 9; ++k) {
    const uint32_t a = static_cast<uint32_t>(g() % 4), b = 4 + static_cast<uint32_t>(g() % 3);
    overflow.push_back(g() % 4 == 0 ? add_manifold(a, 1, true) : add_manifold(a, b, false));
  }
  s.colours.push_back(overflow);
  return s;
}

ContactMaterials materials(const Scene& s) {
  return {s.friction.data(), s.restitution.data(), s.rolling.data(), s.plane_friction.data(),
          s.plane_restitution.data()};
}

// The state compared after each pass: bodies, then the stored per-row values.
struct Snapshot {
  std::vector<SolverBody> bodies;
  std::vector<WarmPoint> stored;
  std::vector<float> impulse;
};

enum class Mode { kBlocks, kSlots };

// The lane kernels, scheduled as the host does (kBlocks) or every slot in order (kSlots).
std::vector<Snapshot> run_lanes(Scene s, Mode mode) {
  const uint32_t colours = static_cast<uint32_t>(s.colours.size());
  std::vector<uint32_t> start(colours + 1, 0), order;
  for (uint32_t k = 0; k < colours; ++k) {
    start[k + 1] = start[k] + contact_blocks(static_cast<uint32_t>(s.colours[k].size())) * W;
    for (uint32_t m : s.colours[k]) order.push_back(m);
    order.resize(start[k + 1], kNoConstraint);
  }
  const uint32_t slots = start[colours];
  std::vector<ContactBlock> blocks(slots / W);
  ContactManifoldArrays c = s.m.view();
  // Prepare in two ranges (any partition of the slots gives the same bytes).
  const uint32_t cut = slots / 2;
  prepare_contacts(s.p, c, order.data(), s.bodies.data(), s.ii.data(), s.com.data(), s.body_count, materials(s),
                   s.warm.data(), blocks.data(), {0, cut});
  prepare_contacts(s.p, c, order.data(), s.bodies.data(), s.ii.data(), s.com.data(), s.body_count, materials(s),
                   s.warm.data(), blocks.data(), {cut, slots});
  SolverBody* bodies = s.bodies.data();
  auto each = [&](auto wide, auto serial) {
    for (uint32_t k = 0; k < colours; ++k) {
      const uint32_t b = start[k], e = b + static_cast<uint32_t>(s.colours[k].size());
      if (mode == Mode::kBlocks && k + 1 < colours)
        wide(Range{b / W, start[k + 1] / W});
      else
        serial(Range{b, e});
    }
  };
  std::vector<Snapshot> out;
  auto snap = [&] { out.push_back({s.bodies, {}, {}}); };
  for (int sub = 0; sub < 2; ++sub) {
    each([&](Range r) { warm_start_contacts(blocks.data(), bodies, r); },
         [&](Range r) { warm_start_contacts_serial(blocks.data(), bodies, r); });
    snap();
    each([&](Range r) { solve_contacts(s.p, true, blocks.data(), bodies, r); },
         [&](Range r) { solve_contacts_serial(s.p, true, blocks.data(), bodies, r); });
    snap();
    integrate_substep_positions(s.p.h, nullptr, bodies, {0, s.body_count});
    each([&](Range r) { solve_contacts(s.p, false, blocks.data(), bodies, r); },
         [&](Range r) { solve_contacts_serial(s.p, false, blocks.data(), bodies, r); });
    snap();
  }
  each([&](Range r) { restitute_contacts(s.p, blocks.data(), bodies, r); },
       [&](Range r) { restitute_contacts_serial(s.p, blocks.data(), bodies, r); });
  snap();
  Snapshot& last = out.back();
  last.stored.assign(s.warm.size(), WarmPoint{});
  last.impulse.assign(s.warm.size(), 0.0f);
  store_contacts(c, order.data(), blocks.data(), last.stored.data(), last.impulse.data(), {0, slots});
  return out;
}

std::vector<Snapshot> run_reference(Scene s) {
  namespace ref = test::soft_ref;
  std::vector<uint32_t> order, first;
  for (const auto& colour : s.colours)
    for (uint32_t m : colour) order.push_back(m);
  const auto nc = static_cast<uint32_t>(order.size());
  uint32_t run = 0;
  for (uint32_t m : order) first.push_back(run), run += s.m.count[m];
  std::vector<ref::ContactConstraint> cons(nc);
  std::vector<ref::ContactPoint> points(run);
  ContactManifoldArrays c = s.m.view();
  ref::prepare_contacts(s.p, c, order.data(), first.data(), s.bodies.data(), s.ii.data(), s.com.data(), s.body_count,
                        materials(s), s.warm.data(), cons.data(), points.data(), {0, nc});
  SolverBody* bodies = s.bodies.data();
  std::vector<Snapshot> out;
  auto snap = [&] { out.push_back({s.bodies, {}, {}}); };
  for (int sub = 0; sub < 2; ++sub) {
    ref::warm_start_contacts(cons.data(), points.data(), bodies, {0, nc});
    snap();
    ref::solve_contacts(s.p, true, cons.data(), points.data(), bodies, {0, nc});
    snap();
    integrate_substep_positions(s.p.h, nullptr, bodies, {0, s.body_count});
    ref::solve_contacts(s.p, false, cons.data(), points.data(), bodies, {0, nc});
    snap();
  }
  ref::restitute_contacts(s.p, cons.data(), points.data(), bodies, {0, nc});
  snap();
  Snapshot& last = out.back();
  last.stored.assign(s.warm.size(), WarmPoint{});
  last.impulse.assign(s.warm.size(), 0.0f);
  ref::store_contacts(c, order.data(), cons.data(), points.data(), last.stored.data(), last.impulse.data(), {0, nc});
  return out;
}

// Every float of a snapshot, in order (the bodies' pads included).
std::vector<float> floats(const Snapshot& s) {
  std::vector<float> f(s.bodies.size() * 16 + s.stored.size() * 8 + s.impulse.size());
  std::memcpy(f.data(), s.bodies.data(), sizeof(SolverBody) * s.bodies.size());
  std::memcpy(f.data() + s.bodies.size() * 16, s.stored.data(), sizeof(WarmPoint) * s.stored.size());
  std::memcpy(f.data() + s.bodies.size() * 16 + s.stored.size() * 8, s.impulse.data(),
              sizeof(float) * s.impulse.size());
  return f;
}

bool same_bytes(const Snapshot& x, const Snapshot& y) {
  const std::vector<float> a = floats(x), b = floats(y);
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(float) * a.size()) == 0;
}

int g_bytewise_runs = 0, g_runs = 0;

void check_scene(uint32_t seed, bool warm) {
  const Scene scene = make_scene(seed, warm);
  const std::vector<Snapshot> blocks = run_lanes(scene, Mode::kBlocks);
  const std::vector<Snapshot> slots = run_lanes(scene, Mode::kSlots);
  const std::vector<Snapshot> ref = run_reference(scene);
  ASSERT_EQ(blocks.size(), slots.size());
  ASSERT_EQ(blocks.size(), ref.size());
  bool bytewise = true;
  for (size_t k = 0; k < blocks.size(); ++k) {
    if (!same_bytes(blocks[k], slots[k])) {
      const std::vector<float> a = floats(blocks[k]), b = floats(slots[k]), r = floats(ref[k]);
      int shown = 0;
      for (size_t i = 0; i < a.size() && shown < 8; ++i)
        if (std::memcmp(&a[i], &b[i], 4) != 0)
          ++shown, ADD_FAILURE() << "float " << i << " blocks " << a[i] << " slots " << b[i] << " ref " << r[i];
      FAIL() << "seed " << seed << " pass " << k << ": blocks != slots";
    }
    const std::vector<float> a = floats(blocks[k]), b = floats(ref[k]);
    bytewise = bytewise && std::memcmp(a.data(), b.data(), sizeof(float) * a.size()) == 0;
    for (size_t i = 0; i < a.size(); ++i) {
      const float tol = 2e-5f * std::max(1.0f, std::max(std::fabs(a[i]), std::fabs(b[i])));
      ASSERT_LE(std::fabs(a[i] - b[i]), tol) << "seed " << seed << " pass " << k << " float " << i;
    }
  }
  // The static, the kinematic body and the zero body: read, never written (v, inv_mass,
  // w; the kinematic body's dp and dq move with its velocity).
  for (uint32_t i = scene.dynamic; i <= scene.body_count; ++i)
    EXPECT_EQ(0, std::memcmp(&blocks.back().bodies[i], &scene.bodies[i], offsetof(SolverBody, dp))) << "body " << i;
  ++g_runs;
  g_bytewise_runs += bytewise ? 1 : 0;
}

TEST(SoftContactLanes, BlocksMatchSlotsBytewiseAndTheReference) {
  for (uint32_t seed = 1; seed <= 24; ++seed) {
    check_scene(seed, seed % 3 != 0);
    if (HasFatalFailure()) return;
  }
  std::printf("lane kernels equal to the AoS reference bytewise in %d of %d scenes\n", g_bytewise_runs, g_runs);
  RecordProperty("bytewise_vs_reference", g_bytewise_runs);
}

}  // namespace
}  // namespace impact::kernels
