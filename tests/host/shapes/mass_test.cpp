// shape_mass_properties (host/shapes/mass.cpp) against independent answers: Monte
// Carlo integration in double (fixed seed) for every closed form and for a hull; exact
// identities (hull of a box's corners == the box, capsule of zero length == sphere,
// compound of two boxes == the box of their union, parallel-axis sums for offset
// spheres); a hull of many sphere points converges to the sphere; errors for
// half-spaces, meshes and bad densities.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "host/shapes/convex_hull.h"
#include "host/shapes/mass.h"
#include "host/shapes/shape_store.h"
#include "support/test_support.h"

namespace impact {
namespace {

using Vec3d = Eigen::Vector3d;
using Mat3d = Eigen::Matrix3d;
constexpr double kPi = std::numbers::pi;

uint32_t add(ShapeStore& s, ShapeType t, Vec3d e, uint32_t ref = 0) {
  ShapeRecord r;
  r.type = t;
  for (int i = 0; i < 3; ++i) r.e[i] = static_cast<float>(e[i]);
  r.ref = ref;
  s.shapes.push_back(r);
  return static_cast<uint32_t>(s.shapes.size() - 1);
}

uint32_t add_hull(ShapeStore& s, const std::vector<Eigen::Vector3f>& pts) {
  HullData h;
  EXPECT_TRUE(test::IsOk(build_convex_hull(pts, &h)));
  return add(s, ShapeType::kConvex, Vec3d::Zero(), s.hulls.add(h));
}

uint32_t add_compound(ShapeStore& s, const std::vector<CompoundChild>& children) {
  const uint32_t c = static_cast<uint32_t>(s.child_begin.size() - 1);
  for (const auto& ch : children) s.children.push_back(ch);
  s.child_begin.push_back(static_cast<uint32_t>(s.children.size()));
  return add(s, ShapeType::kCompound, Vec3d::Zero(), c);
}

MassProperties props(const ShapeStore& s, uint32_t id, double density) {
  MassProperties m;
  EXPECT_TRUE(test::IsOk(shape_mass_properties(s, id, density, &m)));
  return m;
}

/// Monte Carlo over the box [lo, hi]: volume, centre of mass, inertia about it.
MassProperties monte_carlo(const std::function<bool(const Vec3d&)>& inside, const Vec3d& lo, const Vec3d& hi,
                           double density, uint32_t samples) {
  std::mt19937_64 rng(1234);
  std::uniform_real_distribution<double> u(0, 1);
  double n_in = 0;
  Vec3d s1 = Vec3d::Zero();
  Mat3d s2 = Mat3d::Zero();
  for (uint32_t i = 0; i < samples; ++i) {
    const Vec3d p = lo + (hi - lo).cwiseProduct(Vec3d(u(rng), u(rng), u(rng)));
    if (!inside(p)) continue;
    n_in += 1;
    s1 += p;
    s2 += p * p.transpose();
  }
  const double box_vol = (hi - lo).prod();
  MassProperties m;
  m.volume = box_vol * n_in / samples;
  m.mass = density * m.volume;
  m.center_of_mass = s1 / n_in;
  const Mat3d cov = density * box_vol / samples * s2 - m.mass * m.center_of_mass * m.center_of_mass.transpose();
  m.inertia = cov.trace() * Mat3d::Identity() - cov;
  return m;
}

void expect_close(const MassProperties& a, const MassProperties& b, double rel, double size) {
  EXPECT_NEAR(a.volume, b.volume, rel * b.volume);
  EXPECT_NEAR(a.mass, b.mass, rel * b.mass);
  EXPECT_LT((a.center_of_mass - b.center_of_mass).norm(), rel * size);
  EXPECT_LT((a.inertia - b.inertia).norm(), rel * b.mass * size * size)
      << "\n" << a.inertia << "\nvs\n" << b.inertia;
}

TEST(MassProperties, ClosedFormsMatchMonteCarlo) {
  ShapeStore s;
  const double rho = 7.5;
  const uint32_t samples = test::scaled(1u << 20);
  const double rel = 1e-2;  // ~5 sigma at 1M samples
  {
    const double r = 0.7;
    const auto id = add(s, ShapeType::kSphere, {r, 0, 0});
    const auto mc = monte_carlo([&](const Vec3d& p) { return p.norm() <= r; }, Vec3d::Constant(-r), Vec3d::Constant(r),
                                rho, samples);
    expect_close(props(s, id, rho), mc, rel, r);
  }
  {
    const Vec3d h(0.3, 0.8, 1.9);
    const auto id = add(s, ShapeType::kBox, h);
    const auto mc = monte_carlo([&](const Vec3d& p) { return (p.cwiseAbs() - h).maxCoeff() <= 0; }, -h, h, rho, samples);
    expect_close(props(s, id, rho), mc, rel, h.norm());
    const auto aabb = add(s, ShapeType::kAabb, h);
    expect_close(props(s, aabb, rho), mc, rel, h.norm());
  }
  {
    const double r = 0.4, hl = 1.1;
    const auto id = add(s, ShapeType::kCylinder, {r, hl, 0});
    const auto mc = monte_carlo([&](const Vec3d& p) { return std::hypot(p.x(), p.y()) <= r && std::fabs(p.z()) <= hl; },
                                Vec3d(-r, -r, -hl), Vec3d(r, r, hl), rho, samples);
    expect_close(props(s, id, rho), mc, rel, hl);
  }
  {
    const double r = 0.5, hl = 0.9;
    const auto id = add(s, ShapeType::kCapsule, {r, hl, 0});
    const auto mc = monte_carlo(
        [&](const Vec3d& p) {
          const double z = std::clamp(p.z(), -hl, hl);
          return (p - Vec3d(0, 0, z)).norm() <= r;
        },
        Vec3d(-r, -r, -hl - r), Vec3d(r, r, hl + r), rho, samples);
    expect_close(props(s, id, rho), mc, rel, hl + r);
  }
  {
    const Vec3d e(0.5, 1.3, 0.8);
    const auto id = add(s, ShapeType::kEllipsoid, e);
    const auto mc = monte_carlo([&](const Vec3d& p) { return p.cwiseQuotient(e).norm() <= 1; }, -e, e, rho, samples);
    expect_close(props(s, id, rho), mc, rel, e.maxCoeff());
  }
  {
    // An off-centre random hull: centre of mass and a full (non-diagonal) tensor.
    std::mt19937 g(7);
    std::normal_distribution<float> n;
    std::vector<Eigen::Vector3f> pts;
    for (int i = 0; i < 25; ++i) pts.emplace_back(1.0f + n(g), 0.5f * n(g) + 0.3f * n(g), -2.0f + 0.7f * n(g));
    const auto id = add_hull(s, pts);
    const HullData& h = [&]() -> const HullData& {
      static HullData hd;
      EXPECT_TRUE(test::IsOk(build_convex_hull(pts, &hd)));
      return hd;
    }();
    Vec3d lo = Vec3d::Constant(INFINITY), hi = Vec3d::Constant(-INFINITY);
    for (const auto& v : h.vertices) {
      lo = lo.cwiseMin(v.cast<double>());
      hi = hi.cwiseMax(v.cast<double>());
    }
    const auto mc = monte_carlo(
        [&](const Vec3d& p) {
          for (size_t f = 0; f < h.faces.size(); ++f)
            if (h.face_normals[f].cast<double>().dot(p) > h.face_offsets[f]) return false;
          return true;
        },
        lo, hi, rho, samples);
    const MassProperties m = props(s, id, rho);
    expect_close(m, mc, rel, (hi - lo).norm());
    EXPECT_GT(std::fabs(m.inertia(0, 1)) + std::fabs(m.inertia(0, 2)) + std::fabs(m.inertia(1, 2)), 0.0);
  }
}

TEST(MassProperties, HullOfABoxIsTheBox) {
  ShapeStore s;
  const Vec3d h(0.5, 1.5, 2.0);
  const auto box = add(s, ShapeType::kBox, h);
  std::vector<Eigen::Vector3f> pts;
  for (int i = 0; i < 8; ++i)
    pts.emplace_back((i & 1) ? 0.5f : -0.5f, (i & 2) ? 1.5f : -1.5f, (i & 4) ? 2.0f : -2.0f);
  const auto hull = add_hull(s, pts);
  expect_close(props(s, hull, 3.0), props(s, box, 3.0), 1e-12, h.norm());
  // Translated: same tensor about the centre of mass, which moves.
  for (auto& p : pts) p += Eigen::Vector3f(10, -5, 3);
  const MassProperties t = props(s, add_hull(s, pts), 3.0);
  EXPECT_LT((t.center_of_mass - Vec3d(10, -5, 3)).norm(), 1e-9);
  EXPECT_LT((t.inertia - props(s, box, 3.0).inertia).norm(), 1e-9 * t.inertia.norm());
}

TEST(MassProperties, HullOfSpherePointsApproachesTheSphere) {
  ShapeStore s;
  std::mt19937 g(8);
  std::normal_distribution<float> n;
  std::vector<Eigen::Vector3f> pts;
  for (int i = 0; i < 4000; ++i) pts.push_back(Eigen::Vector3f(n(g), n(g), n(g)).normalized() * 2.0f);
  const MassProperties hull = props(s, add_hull(s, pts), 1.0);
  const MassProperties sphere = props(s, add(s, ShapeType::kSphere, {2, 0, 0}), 1.0);
  // Inscribed polytope: slightly smaller, within the discretisation error (~0.5 %).
  EXPECT_LT(hull.volume, sphere.volume);
  EXPECT_GT(hull.volume, 0.99 * sphere.volume);
  EXPECT_LT(hull.center_of_mass.norm(), 0.01);
  EXPECT_LT((hull.inertia - sphere.inertia).norm(), 0.02 * sphere.inertia.norm());
}

TEST(MassProperties, CapsuleOfZeroLengthIsASphere) {
  ShapeStore s;
  const MassProperties c = props(s, add(s, ShapeType::kCapsule, {0.6, 0, 0}), 2.0);
  const MassProperties sp = props(s, add(s, ShapeType::kSphere, {0.6, 0, 0}), 2.0);
  expect_close(c, sp, 1e-6, 0.6);
}

TEST(MassProperties, CompoundOfTwoBoxesIsTheUnionBox) {
  ShapeStore s;
  const auto whole = add(s, ShapeType::kBox, {1, 1, 1});
  const auto slab_x = add(s, ShapeType::kBox, {0.5, 1, 1});
  const auto slab_y = add(s, ShapeType::kBox, {1, 0.5, 1});  // turned 90 degrees about z
  CompoundChild left{{slab_x}, {}}, right{{slab_y}, {}};
  left.local.position = Eigen::Vector3f(-0.5f, 0, 0);
  right.local.position = Eigen::Vector3f(0.5f, 0, 0);
  right.local.orientation = Eigen::Quaternionf(Eigen::AngleAxisf(static_cast<float>(kPi / 2), Eigen::Vector3f::UnitZ()));
  const auto comp = add_compound(s, {left, right});
  expect_close(props(s, comp, 5.0), props(s, whole, 5.0), 1e-6, 1.0);
  // The compound, posed as a child itself (off-centre, rotated), keeps its tensor up to
  // rotation: R I R^T about the moved centre of mass.
  CompoundChild moved{{whole}, {}};
  moved.local.position = Eigen::Vector3f(3, 4, 5);
  const Eigen::Quaternionf q(Eigen::AngleAxisf(0.7f, Eigen::Vector3f(1, 2, 3).normalized()));
  moved.local.orientation = q;
  const MassProperties m = props(s, add_compound(s, {moved}), 5.0);
  const Mat3d R = q.cast<double>().toRotationMatrix();
  EXPECT_LT((m.center_of_mass - Vec3d(3, 4, 5)).norm(), 1e-6);
  EXPECT_LT((m.inertia - R * props(s, whole, 5.0).inertia * R.transpose()).norm(), 1e-6 * m.inertia.norm());
}

TEST(MassProperties, ParallelAxis) {
  ShapeStore s;
  const double r = 0.5, d = 3.0, rho = 2.0;
  const auto sp = add(s, ShapeType::kSphere, {r, 0, 0});
  CompoundChild a{{sp}, {}}, b{{sp}, {}};
  a.local.position = Eigen::Vector3f(0, 0, static_cast<float>(-d / 2));
  b.local.position = Eigen::Vector3f(0, 0, static_cast<float>(d / 2));
  const MassProperties m = props(s, add_compound(s, {a, b}), rho);
  const double ms = rho * 4.0 / 3.0 * kPi * r * r * r;
  EXPECT_NEAR(m.mass, 2 * ms, 1e-12);
  EXPECT_LT(m.center_of_mass.norm(), 1e-12);
  EXPECT_NEAR(m.inertia(2, 2), 2 * 0.4 * ms * r * r, 1e-9);
  EXPECT_NEAR(m.inertia(0, 0), 2 * (0.4 * ms * r * r + ms * (d / 2) * (d / 2)), 1e-9);
  EXPECT_NEAR(m.inertia(1, 1), m.inertia(0, 0), 1e-9);
  // One sphere off the origin: the centre of mass moves, the tensor about it does not.
  const MassProperties one = props(s, add_compound(s, {b}), rho);
  EXPECT_NEAR(one.center_of_mass.z(), d / 2, 1e-6);
  EXPECT_LT((one.inertia - props(s, sp, rho).inertia).norm(), 1e-9);
}

TEST(MassProperties, Errors) {
  ShapeStore s;
  const auto hs = add(s, ShapeType::kHalfSpace, {0, 0, 1});
  const auto mesh = add(s, ShapeType::kMesh, {0, 0, 0});
  const auto sp = add(s, ShapeType::kSphere, {1, 0, 0});
  MassProperties m;
  EXPECT_TRUE(test::IsError(shape_mass_properties(s, hs, 1.0, &m), StatusCode::kInvalidArgument, {"half-space"}));
  EXPECT_TRUE(test::IsError(shape_mass_properties(s, mesh, 1.0, &m), StatusCode::kInvalidArgument, {"mesh"}));
  EXPECT_TRUE(test::IsError(shape_mass_properties(s, sp, 0.0, &m), StatusCode::kInvalidArgument, {"density"}));
  EXPECT_TRUE(test::IsError(shape_mass_properties(s, sp, NAN, &m), StatusCode::kInvalidArgument, {"density"}));
  EXPECT_TRUE(test::IsError(shape_mass_properties(s, 99, 1.0, &m), StatusCode::kInvalidArgument, {"unknown shape"}));
  // A compound holding a half-space reports it.
  CompoundChild c{{hs}, {}};
  const auto comp = add_compound(s, {c});
  EXPECT_TRUE(test::IsError(shape_mass_properties(s, comp, 1.0, &m), StatusCode::kInvalidArgument, {"half-space"}));
}

}  // namespace
}  // namespace impact
