// Benchmark scenes; see scenes.h.
#include "bench/scenes/scenes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>

namespace impact::bench {
namespace {

constexpr std::array<std::string_view, 9> kSceneNames = {"box",  "rain",     "uniform", "pyramid", "wall",
                                                         "pyramids", "column", "hulls", "mixed"};

// Grid of the box scenes: horizontal pitch (> the largest diameter, 1 m, plus twice
// the jitter, so no two spheres start overlapping) and target number of layers,
// which fixes the footprint: ~16 layers of cols x cols spheres.
constexpr float kPitch = 1.1f;    // m
constexpr float kJitter = 0.04f;  // m, +- per axis in "box"
constexpr uint32_t kLayers = 16;

// Mass grows with volume: a 1 m diameter sphere weighs 1 kg.
float inv_mass_of(float radius) {
  return 1.0f / (8.0f * radius * radius * radius);
}

// Spheres per side of one layer, so that n spheres make about kLayers layers.
uint32_t columns_for(uint32_t n) {
  return std::max(1u, static_cast<uint32_t>(std::ceil(std::sqrt(static_cast<double>(n) / kLayers))));
}

// Floor y = 0 plus four walls at x, z = +-half_extent; each normal points into the box.
std::vector<PlaneDesc> open_box(float half_extent) {
  std::vector<PlaneDesc> planes;
  const Eigen::Vector3f normals[5] = {Eigen::Vector3f::UnitY(), Eigen::Vector3f::UnitX(),
                                      -Eigen::Vector3f::UnitX(), Eigen::Vector3f::UnitZ(),
                                      -Eigen::Vector3f::UnitZ()};
  for (int k = 0; k < 5; ++k) {
    PlaneDesc p;
    p.normal = normals[k];
    // Solid side is { x : dot(n, x) <= offset }: the floor's surface at 0, each wall's at -half_extent.
    p.offset = k == 0 ? 0.0f : -half_extent;
    p.restitution = 0.0f;
    planes.push_back(p);
  }
  return planes;
}

BodyDesc random_sphere(Rng& rng, const Eigen::Vector3f& position, const Eigen::Vector3f& velocity) {
  BodyDesc d;
  d.position = position;
  d.velocity = velocity;
  d.radius = rng.uniform(kMinRadius, kMaxRadius);
  d.inv_mass = inv_mass_of(d.radius);
  d.restitution = rng.uniform(0.0f, 0.5f);
  d.friction = 0.0f;  // frictionless: the scenes' spheres never rotate
  return d;
}

void make_box(uint32_t n, uint64_t seed, bool rain, Scene* s) {
  Rng rng(seed);
  const uint32_t cols = columns_for(n);
  const float half = 0.5f * kPitch * static_cast<float>(cols);
  s->planes = open_box(half + 0.05f);
  s->bodies.reserve(n);
  // Rain: layers 2.5 m apart with +-0.6 m vertical jitter, so they arrive spread in time.
  const float layer_pitch = rain ? 2.5f : kPitch;
  const float y0 = rain ? 3.0f : kMaxRadius + 0.1f;
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t layer = i / (cols * cols);
    const uint32_t in_layer = i % (cols * cols);
    const float cx = -half + kPitch * (static_cast<float>(in_layer % cols) + 0.5f);
    const float cz = -half + kPitch * (static_cast<float>(in_layer / cols) + 0.5f);
    const float cy = y0 + layer_pitch * static_cast<float>(layer);
    const float jy = rain ? 0.6f : kJitter;
    const Eigen::Vector3f p(cx + rng.uniform(-kJitter, kJitter), cy + rng.uniform(-jy, jy),
                            cz + rng.uniform(-kJitter, kJitter));
    Eigen::Vector3f v = Eigen::Vector3f::Zero();
    if (rain)
      v = Eigen::Vector3f(rng.uniform(-1.0f, 1.0f), -rng.uniform(4.0f, 12.0f), rng.uniform(-1.0f, 1.0f));
    s->bodies.push_back(random_sphere(rng, p, v));
  }
}

void make_uniform(uint32_t n, uint64_t seed, Scene* s) {
  Rng rng(seed);
  const float side = sphere_cube_side(n, kMinRadius, kMaxRadius, 1.0);
  s->gravity = Eigen::Vector3f::Zero();
  s->bodies.reserve(n);
  for (uint32_t i = 0; i < n; ++i) {
    const Eigen::Vector3f p(rng.uniform(-0.5f, 0.5f) * side, rng.uniform(-0.5f, 0.5f) * side,
                            rng.uniform(-0.5f, 0.5f) * side);
    s->bodies.push_back(random_sphere(rng, p, Eigen::Vector3f::Zero()));
  }
}

// --- rigid-body scenes ---------------------------------------------------------------

constexpr float kCubeHalf = 0.5f;  // m: the stacking scenes' 1 m cubes
constexpr float kFriction = 0.6f;
constexpr float kDensity = 1.0f;   // kg/m^3: a 1 m cube weighs 1 kg
constexpr uint32_t kSmallPyramidLayers = 5;
constexpr uint32_t kSmallPyramidBoxes = 55;  // 25 + 16 + 9 + 4 + 1
constexpr float kPyramidSpacing = 8.0f;      // m between the small pyramids' axes

// Boxes in a square pyramid of `layers` layers: 1 + 4 + ... + layers^2.
uint64_t square_pyramid_boxes(uint64_t layers) {
  return layers * (layers + 1) * (2 * layers + 1) / 6;
}

// Floor y = 0 of the stacking scenes.
PlaneDesc stack_floor() {
  PlaneDesc p;
  p.normal = Eigen::Vector3f::UnitY();
  p.offset = 0.0f;
  p.friction = kFriction;
  p.restitution = 0.0f;
  return p;
}

// A resting 1 m cube of shape 0 whose bottom face is `level` (0 = on the floor) layers up.
BodyDesc cube_at(float x, uint32_t level, float z) {
  BodyDesc d;
  d.shape = ShapeId{0};
  d.inv_mass = 1.0f;  // 1 kg
  d.friction = kFriction;
  d.restitution = 0.0f;
  const float pitch = 2.0f * kCubeHalf - kStackOverlap;
  d.position = Eigen::Vector3f(x, kCubeHalf - kStackOverlap + pitch * static_cast<float>(level), z);
  return d;
}

void add_cube_shape(Scene* s) {
  SceneShape cube;
  cube.type = ShapeType::kBox;
  cube.half_extents = Eigen::Vector3f::Constant(kCubeHalf);
  s->shapes.push_back(cube);
  s->planes.push_back(stack_floor());
  s->rigid = true;
}

// Square pyramid of `layers` layers centred on (cx, cz): layer l (0 = bottom) has
// (layers - l)^2 boxes.
void put_square_pyramid(uint32_t layers, float cx, float cz, Scene* s) {
  const float pitch = 2.0f * kCubeHalf + kStackGap;
  for (uint32_t l = 0; l < layers; ++l) {
    const uint32_t side = layers - l;
    const float first = -0.5f * pitch * static_cast<float>(side - 1);
    for (uint32_t iz = 0; iz < side; ++iz)
      for (uint32_t ix = 0; ix < side; ++ix)
        s->bodies.push_back(cube_at(cx + first + pitch * static_cast<float>(ix), l,
                                    cz + first + pitch * static_cast<float>(iz)));
  }
}

void make_pyramid(uint32_t n, Scene* s) {
  uint32_t layers = 1;
  while (square_pyramid_boxes(layers + 1) <= n) ++layers;
  add_cube_shape(s);
  s->bodies.reserve(square_pyramid_boxes(layers));
  put_square_pyramid(layers, 0.0f, 0.0f, s);
}

void make_wall(uint32_t n, Scene* s) {
  uint64_t rows = 1;
  while ((rows + 1) * (rows + 2) / 2 <= n) ++rows;
  add_cube_shape(s);
  s->bodies.reserve(rows * (rows + 1) / 2);
  const float pitch = 2.0f * kCubeHalf + kStackGap;
  for (uint32_t r = 0; r < rows; ++r) {
    const uint32_t count = static_cast<uint32_t>(rows) - r;
    const float first = -0.5f * pitch * static_cast<float>(count - 1);
    for (uint32_t i = 0; i < count; ++i) s->bodies.push_back(cube_at(first + pitch * static_cast<float>(i), r, 0.0f));
  }
}

void make_pyramids(uint32_t n, Scene* s) {
  const uint32_t count = std::max(1u, n / kSmallPyramidBoxes);
  uint32_t grid = 1;
  while (grid * grid < count) ++grid;
  add_cube_shape(s);
  s->bodies.reserve(size_t{count} * kSmallPyramidBoxes);
  const float first = -0.5f * kPyramidSpacing * static_cast<float>(grid - 1);
  for (uint32_t k = 0; k < count; ++k)
    put_square_pyramid(kSmallPyramidLayers, first + kPyramidSpacing * static_cast<float>(k % grid),
                       first + kPyramidSpacing * static_cast<float>(k / grid), s);
}

void make_column(uint32_t n, Scene* s) {
  add_cube_shape(s);
  s->bodies.reserve(n);
  for (uint32_t i = 0; i < n; ++i) s->bodies.push_back(cube_at(0.0f, i, 0.0f));
}

// A unit quaternion from four uniforms in [-1, 1) (rejecting short vectors; only a
// square root, which IEEE rounds exactly, so the same bytes everywhere). Not uniform
// over rotations, which a benchmark does not need.
Eigen::Quaternionf random_orientation(Rng& rng) {
  for (;;) {
    const float x = rng.uniform(-1.0f, 1.0f), y = rng.uniform(-1.0f, 1.0f), z = rng.uniform(-1.0f, 1.0f),
                w = rng.uniform(-1.0f, 1.0f);
    const float n2 = x * x + y * y + z * z + w * w;
    if (n2 < 0.01f || n2 > 1.0f) continue;
    const float inv = 1.0f / std::sqrt(n2);
    return Eigen::Quaternionf(w * inv, x * inv, y * inv, z * inv);
  }
}

// kHullPoints points uniform in a ball of radius 0.48 m, then squashed by a factor in
// [0.6, 1] per axis (so the hulls differ in shape, not only in their vertices).
SceneShape random_hull(Rng& rng) {
  SceneShape h;
  h.type = ShapeType::kConvex;
  const Eigen::Vector3f scale(rng.uniform(0.6f, 1.0f), rng.uniform(0.6f, 1.0f), rng.uniform(0.6f, 1.0f));
  while (h.points.size() < kHullPoints) {
    const Eigen::Vector3f p(rng.uniform(-1.0f, 1.0f), rng.uniform(-1.0f, 1.0f), rng.uniform(-1.0f, 1.0f));
    if (p.squaredNorm() > 1.0f) continue;
    h.points.push_back(0.48f * p.cwiseProduct(scale));
  }
  return h;
}

// Body i of a pile: falls from cell i of the grid of "box" (cols x cols per layer, 1.1 m
// pitch, jittered), randomly oriented, shape i of the scene, mass from the density.
BodyDesc pile_body(Rng& rng, uint32_t i, uint32_t cols, float y0, const MassProperties& mass) {
  const float half = 0.5f * kPitch * static_cast<float>(cols);
  const uint32_t layer = i / (cols * cols), in_layer = i % (cols * cols);
  BodyDesc d;
  d.position = Eigen::Vector3f(-half + kPitch * (static_cast<float>(in_layer % cols) + 0.5f) + rng.uniform(-kJitter, kJitter),
                               y0 + kPitch * static_cast<float>(layer) + rng.uniform(-kJitter, kJitter),
                               -half + kPitch * (static_cast<float>(in_layer / cols) + 0.5f) + rng.uniform(-kJitter, kJitter));
  d.orientation = random_orientation(rng);
  d.shape = ShapeId{i};
  d.inv_mass = static_cast<float>(1.0 / mass.mass);
  d.friction = kFriction;
  d.restitution = 0.0f;
  return d;
}

// Adds one scene shape to a set.
Status add_shape(const SceneShape& sh, ShapeSet* shapes, ShapeId* id) {
  switch (sh.type) {
    case ShapeType::kSphere: return shapes->add_sphere(sh.radius, id);
    case ShapeType::kCapsule: return shapes->add_capsule(sh.radius, sh.half_length, id);
    case ShapeType::kBox: return shapes->add_box(sh.half_extents, id);
    case ShapeType::kConvex: return shapes->add_convex_hull(sh.points, id);
    case ShapeType::kCylinder: return shapes->add_cylinder(sh.radius, sh.half_length, id);
    case ShapeType::kMesh: return shapes->add_mesh(sh.points, sh.indices, id);
    default:
      return Status(StatusCode::kInvalidArgument, std::string("scene shapes of type ") + to_string(sh.type) +
                                                      " are not supported");
  }
}

// Appends `shape` to the scene and measures its mass in `scratch` (a set that holds
// the scene's earlier shapes, so one set serves the whole pile). A hull is moved to
// put its centre of mass at its origin, and shrunk if need be so that no vertex lies
// more than kMaxRadius from it: its bounding radius about the body's centre stays
// within the grid's clearance.
Status add_pile_shape(SceneShape shape, ShapeSet* scratch, MassProperties* mass, Scene* s) {
  ShapeId id;
  if (Status st = add_shape(shape, scratch, &id); !st.ok()) return st;
  if (Status st = scratch->mass_properties(id, kDensity, mass); !st.ok()) return st;
  if (shape.type == ShapeType::kConvex) {
    const Eigen::Vector3f com = mass->center_of_mass.cast<float>();
    float reach = 0.0f;
    for (Eigen::Vector3f& p : shape.points) {
      p -= com;
      reach = std::max(reach, p.norm());
    }
    if (reach > kMaxRadius) {
      const float scale = kMaxRadius / reach;
      for (Eigen::Vector3f& p : shape.points) p *= scale;
      mass->mass *= static_cast<double>(scale) * scale * scale;
    }
  }
  s->shapes.push_back(std::move(shape));
  return Status();
}

// Random sizes with a bounding radius <= 0.5 m, so the 1.1 m grid (jitter 0.04 m)
// starts with no two bodies overlapping.
SceneShape random_mixed_shape(Rng& rng, uint32_t i) {
  SceneShape sh;
  switch (i % 5) {
    case 0:  // box, half extents in [0.15, 0.28]: corner at most 0.485 m out
      sh.type = ShapeType::kBox;
      sh.half_extents = Eigen::Vector3f(rng.uniform(0.15f, 0.28f), rng.uniform(0.15f, 0.28f), rng.uniform(0.15f, 0.28f));
      break;
    case 1:  // capsule, r + h <= 0.5
      sh.type = ShapeType::kCapsule;
      sh.radius = rng.uniform(0.15f, 0.25f);
      sh.half_length = rng.uniform(0.1f, 0.25f);
      break;
    case 2:
      sh = random_hull(rng);
      break;
    case 3:  // cylinder, sqrt(r^2 + h^2) <= 0.48
      sh.type = ShapeType::kCylinder;
      sh.radius = rng.uniform(0.2f, 0.33f);
      sh.half_length = rng.uniform(0.15f, 0.35f);
      break;
    default:
      sh.type = ShapeType::kSphere;
      sh.radius = rng.uniform(kMinRadius, kMaxRadius);
      break;
  }
  return sh;
}

// Heights of the mixed scene's mesh floor, m.
constexpr float kTerrainBump = 0.15f;

Status make_pile(uint32_t n, uint64_t seed, bool mixed, Scene* s) {
  Rng rng(seed);
  const uint32_t cols = columns_for(n);
  const float half = 0.5f * kPitch * static_cast<float>(cols);
  s->rigid = true;
  s->planes = open_box(half + 0.05f);
  for (PlaneDesc& p : s->planes) p.friction = kFriction;
  // Lowest start: a body's bounding radius (0.5) above the floor, and above the terrain's bumps.
  const float y0 = kMaxRadius + 0.1f + (mixed ? kTerrainBump : 0.0f);
  ShapeSet scratch;
  s->shapes.reserve(n + (mixed ? 1 : 0));
  s->bodies.reserve(n + (mixed ? 1 : 0));
  for (uint32_t i = 0; i < n; ++i) {
    const SceneShape shape = mixed ? random_mixed_shape(rng, i) : random_hull(rng);
    MassProperties mass;
    if (Status st = add_pile_shape(shape, &scratch, &mass, s); !st.ok()) return st;
    s->bodies.push_back(pile_body(rng, i, cols, y0, mass));
  }
  if (!mixed) return Status();
  // The mesh floor: a grid of cells about the pitch wide, reaching 0.5 m beyond the
  // walls, heights uniform in [-bump, bump]; two triangles per cell. The open box's
  // floor plane becomes a backstop 1 m below the mesh's lowest point.
  s->planes[0].offset = -1.0f - kTerrainBump;
  SceneShape mesh;
  mesh.type = ShapeType::kMesh;
  const uint32_t cells = cols + 1;
  const float extent = half + 0.55f;
  const float cell = 2.0f * extent / static_cast<float>(cells);
  for (uint32_t iz = 0; iz <= cells; ++iz)
    for (uint32_t ix = 0; ix <= cells; ++ix)
      mesh.points.emplace_back(-extent + cell * static_cast<float>(ix), rng.uniform(-kTerrainBump, kTerrainBump),
                               -extent + cell * static_cast<float>(iz));
  const uint32_t row = cells + 1;
  for (uint32_t iz = 0; iz < cells; ++iz)
    for (uint32_t ix = 0; ix < cells; ++ix) {
      const uint32_t v = iz * row + ix;
      for (uint32_t k : {v, v + row, v + 1, v + 1, v + row, v + row + 1}) mesh.indices.push_back(k);
    }
  s->shapes.push_back(std::move(mesh));
  BodyDesc floor;
  floor.shape = ShapeId{n};
  floor.inv_mass = 0.0f;
  floor.friction = kFriction;
  floor.restitution = 0.0f;
  s->bodies.push_back(floor);
  return Status();
}

// E[r^k] for r uniform in [a, b].
double uniform_moment(double a, double b, int k) {
  if (b <= a) return std::pow(a, k);
  return (std::pow(b, k + 1) - std::pow(a, k + 1)) / ((k + 1) * (b - a));
}

// n boxes (filled by put_cube) in a cube of the given side.
UniformBoxes sized_boxes(uint32_t n, float side) {
  UniformBoxes b;
  b.side = side;
  for (auto* v : {&b.min_x, &b.min_y, &b.min_z, &b.max_x, &b.max_y, &b.max_z}) v->resize(n);
  return b;
}

// Box i: the cube of half extent h about (x, y, z).
void put_cube(UniformBoxes& b, uint32_t i, float x, float y, float z, float h) {
  b.min_x[i] = x - h;
  b.min_y[i] = y - h;
  b.min_z[i] = z - h;
  b.max_x[i] = x + h;
  b.max_y[i] = y + h;
  b.max_z[i] = z + h;
}

}  // namespace

std::span<const std::string_view> scene_names() {
  return kSceneNames;
}

std::string_view scene_summary(std::string_view name) {
  if (name == "box") return "spheres on a jittered grid fall into an open box (floor + 4 walls)";
  if (name == "rain") return "spheres rain into the open box at 4..12 m/s";
  if (name == "uniform")
    return "spheres uniformly in a cube, ~1 overlapping pair per body, no gravity, no planes";
  if (name == "pyramid") return "square pyramid of 1 m boxes at rest on a floor, 15 layers = 1240 boxes";
  if (name == "wall") return "pyramid wall of boxes in one vertical plane, 100 rows = 5050 boxes";
  if (name == "pyramids") return "5-layer box pyramids (55 boxes) on a 14 x 14 grid = 10780 boxes";
  if (name == "column") return "one column of boxes at rest on a floor, 20 by default";
  if (name == "hulls") return "convex hulls of 32 random points fall into the open box";
  if (name == "mixed")
    return "boxes, capsules, hulls, cylinders, spheres fall on a triangle-mesh floor in the open box";
  return "";
}

uint32_t scene_default_bodies(std::string_view name) {
  if (name == "box" || name == "rain" || name == "uniform") return 100000;
  if (name == "pyramid") return 1240;
  if (name == "wall") return 5050;
  if (name == "pyramids") return 10780;
  if (name == "column") return 20;
  if (name == "hulls") return 5000;
  if (name == "mixed") return 10000;
  return 0;
}

Status make_scene(std::string_view name, uint32_t bodies, uint64_t seed, Scene* out) {
  if (bodies == 0) return Status(StatusCode::kInvalidArgument, "scene needs at least one body");
  Scene s;
  s.name = std::string(name);
  if (name == "box") {
    make_box(bodies, seed, /*rain=*/false, &s);
  } else if (name == "rain") {
    make_box(bodies, seed, /*rain=*/true, &s);
  } else if (name == "uniform") {
    make_uniform(bodies, seed, &s);
  } else if (name == "pyramid") {
    make_pyramid(bodies, &s);
  } else if (name == "wall") {
    make_wall(bodies, &s);
  } else if (name == "pyramids") {
    make_pyramids(bodies, &s);
  } else if (name == "column") {
    make_column(bodies, &s);
  } else if (name == "hulls" || name == "mixed") {
    if (Status st = make_pile(bodies, seed, name == "mixed", &s); !st.ok()) return st;
  } else {
    std::string known;
    for (std::string_view k : kSceneNames) known += (known.empty() ? "" : ", ") + std::string(k);
    return Status(StatusCode::kInvalidArgument,
                  "unknown scene '" + std::string(name) + "' (known: " + known + ")");
  }
  *out = std::move(s);
  return Status();
}

Status add_scene_shapes(const Scene& scene, ShapeSet* shapes) {
  for (size_t k = 0; k < scene.shapes.size(); ++k) {
    ShapeId id;
    if (Status s = add_shape(scene.shapes[k], shapes, &id); !s.ok())
      return Status(s.code(), "scene shape " + std::to_string(k) + ": " + s.message());
    if (id.index != k)
      return Status(StatusCode::kInvalidArgument, "scene shape " + std::to_string(k) + " got id " +
                                                      std::to_string(id.index) + " (the set was not empty)");
  }
  return Status();
}

Status load_scene(const Scene& scene, WorldDesc desc, std::unique_ptr<World>* out) {
  desc.gravity = scene.gravity;
  std::unique_ptr<World> world;
  if (Status s = World::create(desc, &world); !s.ok()) return s;
  if (Status s = add_scene_shapes(scene, &world->shapes()); !s.ok()) return s;
  std::vector<BodyHandle> handles(scene.bodies.size());
  if (Status s = world->create_bodies(scene.bodies, handles); !s.ok()) return s;
  std::vector<PlaneHandle> planes(scene.planes.size());
  if (Status s = world->create_planes(scene.planes, planes); !s.ok()) return s;
  *out = std::move(world);
  return Status();
}

float sphere_cube_side(uint32_t n, float r_min, float r_max, double pairs_per_body) {
  // (ra + rb)^3 expanded, ra and rb independent: 2 E[r^3] + 6 E[r^2] E[r].
  const double a = r_min, b = r_max;
  const double e_d3 = 2.0 * uniform_moment(a, b, 3) + 6.0 * uniform_moment(a, b, 2) * uniform_moment(a, b, 1);
  const double others = std::max(1.0, static_cast<double>(n) - 1.0);
  const double volume = 0.5 * others * (4.0 / 3.0) * std::numbers::pi * e_d3 / pairs_per_body;
  return static_cast<float>(std::cbrt(volume));
}

float box_cube_side(uint32_t n, float half_extent, double pairs_per_body) {
  const double w = 4.0 * half_extent;
  const double others = std::max(1.0, static_cast<double>(n) - 1.0);
  return static_cast<float>(std::cbrt(0.5 * others * w * w * w / pairs_per_body));
}

UniformBoxes make_mixed_boxes(uint32_t n, uint64_t seed) {
  // small-small window 0.2^3 m^3: ~1 pair each
  UniformBoxes b = sized_boxes(n, static_cast<float>(std::cbrt(n * 0.004)));
  const uint32_t big = std::max<uint32_t>(1, n / 10000);
  Rng rng(seed);
  for (uint32_t i = 0; i < n; ++i) {
    const float h = i < big ? 0.5f * std::pow(10.0f, rng.uniform()) : 0.05f;
    const float x = rng.uniform() * b.side, y = rng.uniform() * b.side, z = rng.uniform() * b.side;
    put_cube(b, i, x, y, z, h);
  }
  return b;
}

AabbInput UniformBoxes::view() const {
  AabbInput in;
  in.min_x = min_x;
  in.min_y = min_y;
  in.min_z = min_z;
  in.max_x = max_x;
  in.max_y = max_y;
  in.max_z = max_z;
  return in;
}

UniformBoxes make_size_spread_boxes(uint32_t n, double ratio, double sparsity, uint64_t seed) {
  // Two cubes of half extents h1, h2 overlap when their centres lie within a window of
  // (2 (h1 + h2))^3; E[(h1 + h2)^3] = 2 m3 + 6 m1 m2 with m_k = E[h^k] of the log-uniform
  // law, (1 - a^k) / (k ln(1 / a)) for a = 1 / ratio (1 when ratio is 1).
  const double a = 1.0 / std::max(ratio, 1.0);
  const double log_span = -std::log(a);
  auto moment = [&](int k) { return log_span > 0.0 ? (1.0 - std::pow(a, k)) / (k * log_span) : 1.0; };
  const double window = 8.0 * (2.0 * moment(3) + 6.0 * moment(1) * moment(2));
  const double others = std::max(1.0, static_cast<double>(n) - 1.0);
  UniformBoxes b = sized_boxes(n, static_cast<float>(sparsity * std::cbrt(0.5 * others * window)));
  Rng rng(seed);
  for (uint32_t i = 0; i < n; ++i) {
    const float h = static_cast<float>(std::exp(-log_span * static_cast<double>(rng.uniform())));
    const float x = rng.uniform() * b.side, y = rng.uniform() * b.side, z = rng.uniform() * b.side;
    put_cube(b, i, x, y, z, h);
  }
  return b;
}

UniformBoxes make_uniform_boxes(uint32_t n, float radius, double pairs_per_body, uint64_t seed) {
  UniformBoxes b = sized_boxes(n, box_cube_side(n, radius, pairs_per_body));
  Rng rng(seed);
  for (uint32_t i = 0; i < n; ++i) {
    const float x = rng.uniform() * b.side, y = rng.uniform() * b.side, z = rng.uniform() * b.side;
    put_cube(b, i, x, y, z, radius);
  }
  return b;
}

UniformBoxes make_clustered_boxes(uint32_t n, double pairs_per_body, uint64_t seed) {
  // Two unit boxes overlap when their centres are within a 4 x 4 x 4 window; for m
  // bodies in one isotropic gaussian of width sigma, E[pairs] = m^2 / 2 * 64 * integral
  // of p^2 = m^2 / 2 * 64 / (8 pi^1.5 sigma^3), so pairs per body = 4 m / (pi^1.5 sigma^3).
  constexpr float kRadius = 1.0f;
  const double m = std::max(1.0, static_cast<double>(n) / kClusterBlobs);
  const double sigma =
      std::max(1.0, std::cbrt(4.0 * m / (std::pow(std::numbers::pi, 1.5) * std::max(pairs_per_body, 1e-3))));
  UniformBoxes b = sized_boxes(n, static_cast<float>(16.0 * sigma));
  Rng rng(seed);
  float centre[kClusterBlobs][3];
  for (auto& c : centre)
    for (float& x : c) x = rng.uniform() * b.side;
  // Sum of 12 uniforms minus 6: mean 0, variance 1, within +-6 (Irwin-Hall).
  auto gauss = [&rng] {
    float s = 0.0f;
    for (int k = 0; k < 12; ++k) s += rng.uniform();
    return s - 6.0f;
  };
  const float sig = static_cast<float>(sigma);
  for (uint32_t i = 0; i < n; ++i) {
    const float* c = centre[rng.next_u64() % kClusterBlobs];
    const float x = c[0] + sig * gauss(), y = c[1] + sig * gauss(), z = c[2] + sig * gauss();
    put_cube(b, i, x, y, z, kRadius);
  }
  return b;
}

BoxWalk::BoxWalk(const UniformBoxes& start, float step, uint64_t seed)
    : boxes_(start), step_(step), rng_(seed) {
  const size_t n = start.min_x.size();
  for (auto* v : {&cx_, &cy_, &cz_, &hx_, &hy_, &hz_}) v->resize(n);
  for (int k = 0; k < 3; ++k) lo_[k] = INFINITY, hi_[k] = -INFINITY;
  const std::vector<float>* mins[3] = {&start.min_x, &start.min_y, &start.min_z};
  const std::vector<float>* maxs[3] = {&start.max_x, &start.max_y, &start.max_z};
  std::vector<float>* centres[3] = {&cx_, &cy_, &cz_};
  std::vector<float>* halves[3] = {&hx_, &hy_, &hz_};
  for (int k = 0; k < 3; ++k) {
    for (size_t i = 0; i < n; ++i) {
      const float lo = (*mins[k])[i], hi = (*maxs[k])[i];
      (*centres[k])[i] = 0.5f * (lo + hi);
      (*halves[k])[i] = 0.5f * (hi - lo);
      lo_[k] = std::min(lo_[k], (*centres[k])[i]);
      hi_[k] = std::max(hi_[k], (*centres[k])[i]);
    }
  }
}

void BoxWalk::advance() {
  std::vector<float>* centres[3] = {&cx_, &cy_, &cz_};
  const std::vector<float>* halves[3] = {&hx_, &hy_, &hz_};
  std::vector<float>* mins[3] = {&boxes_.min_x, &boxes_.min_y, &boxes_.min_z};
  std::vector<float>* maxs[3] = {&boxes_.max_x, &boxes_.max_y, &boxes_.max_z};
  const size_t n = cx_.size();
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      float c = (*centres[k])[i] + rng_.uniform(-step_, step_);
      // Reflect at the walls (a step is far smaller than the box, so once is enough).
      if (c < lo_[k]) c = std::min(2.0f * lo_[k] - c, hi_[k]);
      if (c > hi_[k]) c = std::max(2.0f * hi_[k] - c, lo_[k]);
      (*centres[k])[i] = c;
      const float h = (*halves[k])[i];
      (*mins[k])[i] = c - h;
      (*maxs[k])[i] = c + h;
    }
  }
  ++frame_;
}

}  // namespace impact::bench
