// Bad input at the World API (host/world.cpp): every invalid value is rejected
// with the right StatusCode and a message naming the element ("body 3") and the
// field ("radius"); a rejected call leaves the world exactly as it was (all
// body arrays, counts, state hash, and the handles the next creation gets); a
// batch with one bad element adds nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "impact/impact.h"
#include "support/test_support.h"

namespace impact {
namespace {

using test::IsError;
using test::snapshot;
using test::WorldSnapshot;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

class WorldValidation : public ::testing::Test {
 protected:
  void SetUp() override {
    world_ = test::make_world(WorldDesc{});
    ASSERT_TRUE(world_);
    std::vector<BodyDesc> d(5);
    for (int i = 0; i < 5; ++i) {
      d[i].position = {static_cast<float>(i) * 2.0f, 1.0f, 0.0f};
      d[i].velocity = {0.0f, static_cast<float>(i), 0.0f};
    }
    handles_.resize(5);
    ASSERT_TRUE(test::IsOk(world_->create_bodies(d, handles_)));
    std::vector<PlaneDesc> p(1);
    std::vector<PlaneHandle> ph(1);
    ASSERT_TRUE(test::IsOk(world_->create_planes(p, ph)));
    ASSERT_TRUE(test::IsOk(world_->step()));
    before_ = snapshot(*world_);
  }

  // Every observable array, count and the state hash are as after SetUp().
  void expect_unchanged() { EXPECT_TRUE(snapshot(*world_) == before_) << "world changed by a rejected call"; }

  // A batch of 5 valid descs with desc `bad_index` modified by `spoil`.
  template <class Spoil>
  std::vector<BodyDesc> batch(size_t bad_index, Spoil&& spoil) {
    std::vector<BodyDesc> d(5);
    for (size_t i = 0; i < d.size(); ++i) d[i].position = {0.0f, 10.0f + static_cast<float>(i), 3.0f};
    spoil(d[bad_index]);
    return d;
  }

  std::unique_ptr<World> world_;
  std::vector<BodyHandle> handles_;
  WorldSnapshot before_;
};

TEST_F(WorldValidation, CreateBodiesRejectsEachBadField) {
  struct Case {
    const char* field;
    void (*spoil)(BodyDesc&);
  };
  const Case cases[] = {
      {"position", [](BodyDesc& d) { d.position.x() = kNaN; }},
      {"position", [](BodyDesc& d) { d.position.z() = -kInf; }},
      {"position", [](BodyDesc& d) { d.position.y() = 2e18f; }},
      {"velocity", [](BodyDesc& d) { d.velocity.y() = kNaN; }},
      {"velocity", [](BodyDesc& d) { d.velocity.x() = kInf; }},
      {"radius", [](BodyDesc& d) { d.radius = 0.0f; }},
      {"radius", [](BodyDesc& d) { d.radius = -1.0f; }},
      {"radius", [](BodyDesc& d) { d.radius = kNaN; }},
      {"radius", [](BodyDesc& d) { d.radius = kInf; }},
      {"inv_mass", [](BodyDesc& d) { d.inv_mass = -0.5f; }},
      {"inv_mass", [](BodyDesc& d) { d.inv_mass = kNaN; }},
      {"inv_mass", [](BodyDesc& d) { d.inv_mass = kInf; }},
      {"restitution", [](BodyDesc& d) { d.restitution = -0.01f; }},
      {"restitution", [](BodyDesc& d) { d.restitution = 1.01f; }},
      {"restitution", [](BodyDesc& d) { d.restitution = kNaN; }},
  };
  for (const Case& c : cases) {
    for (size_t bad : {size_t{0}, size_t{3}}) {
      SCOPED_TRACE(std::string(c.field) + " at " + std::to_string(bad));
      const auto descs = batch(bad, c.spoil);
      std::vector<BodyHandle> out(descs.size());
      const std::string body = "body " + std::to_string(bad);
      EXPECT_TRUE(
          IsError(world_->create_bodies(descs, out), StatusCode::kInvalidArgument, {body.c_str(), c.field}));
      expect_unchanged();
    }
  }
  // Boundary values are valid.
  auto ok = batch(0, [](BodyDesc& d) {
    d.restitution = 1.0f;
    d.inv_mass = 0.0f;
    d.position = {1e18f, -1e18f, 0.0f};
  });
  std::vector<BodyHandle> out(ok.size());
  IMPACT_EXPECT_OK(world_->create_bodies(ok, out));
}

TEST_F(WorldValidation, RejectedBatchDoesNotConsumeHandles) {
  const auto bad = batch(4, [](BodyDesc& d) { d.radius = -2.0f; });
  std::vector<BodyHandle> out(bad.size());
  EXPECT_FALSE(world_->create_bodies(bad, out).ok());
  const auto good = batch(0, [](BodyDesc&) {});
  std::vector<BodyHandle> got(good.size());
  IMPACT_ASSERT_OK(world_->create_bodies(good, got));
  // Same handles as a world that never saw the rejected batch.
  auto twin = test::make_world(WorldDesc{});
  std::vector<BodyDesc> five(5);
  std::vector<BodyHandle> h5(5), want(good.size());
  IMPACT_ASSERT_OK(twin->create_bodies(five, h5));
  IMPACT_ASSERT_OK(twin->create_bodies(good, want));
  EXPECT_EQ(got, want);
}

TEST_F(WorldValidation, CreateBodiesSizeMismatch) {
  const auto descs = batch(0, [](BodyDesc&) {});
  std::vector<BodyHandle> out(descs.size() - 1);
  EXPECT_TRUE(IsError(world_->create_bodies(descs, out), StatusCode::kSizeMismatch));
  expect_unchanged();
}

TEST_F(WorldValidation, BulkImportRejectsBadColumnsAndSizes) {
  const int n = 6;
  Eigen::Matrix3Xf pos = Eigen::Matrix3Xf::Random(3, n) * 5.0f;
  Eigen::Matrix3Xf vel = Eigen::Matrix3Xf::Zero(3, n);
  Eigen::VectorXf radii = Eigen::VectorXf::Constant(n, 0.5f);
  Eigen::VectorXf inv = Eigen::VectorXf::Ones(n);
  BodyDesc common;
  std::vector<BodyHandle> out(n);
  {
    Eigen::Matrix3Xf p = pos;
    p(1, 3) = kNaN;
    EXPECT_TRUE(IsError(world_->create_bodies(p, vel, radii, inv, common, out), StatusCode::kInvalidArgument,
                        {"body 3", "position"}));
  }
  {
    Eigen::Matrix3Xf v = vel;
    v(2, 5) = kInf;
    EXPECT_TRUE(IsError(world_->create_bodies(pos, v, radii, inv, common, out), StatusCode::kInvalidArgument,
                        {"body 5", "velocity"}));
  }
  {
    Eigen::VectorXf r = radii;
    r[2] = -0.1f;
    EXPECT_TRUE(IsError(world_->create_bodies(pos, vel, r, inv, common, out), StatusCode::kInvalidArgument,
                        {"body 2", "radius"}));
  }
  {
    Eigen::VectorXf w = inv;
    w[1] = -1.0f;
    EXPECT_TRUE(IsError(world_->create_bodies(pos, vel, radii, w, common, out), StatusCode::kInvalidArgument,
                        {"body 1", "inv_mass"}));
  }
  {
    BodyDesc c = common;
    c.restitution = 2.0f;
    EXPECT_TRUE(IsError(world_->create_bodies(pos, vel, radii, inv, c, out), StatusCode::kInvalidArgument,
                        {"restitution"}));
  }
  EXPECT_TRUE(
      IsError(world_->create_bodies(pos, vel, Eigen::VectorXf::Constant(n - 1, 0.5f), inv, common, out),
              StatusCode::kSizeMismatch, {"radii"}));
  EXPECT_TRUE(IsError(world_->create_bodies(pos, vel, radii, Eigen::VectorXf::Ones(n + 1), common, out),
                      StatusCode::kSizeMismatch, {"inv_masses"}));
  EXPECT_TRUE(IsError(world_->create_bodies(pos, Eigen::Matrix3Xf::Zero(3, n - 2), radii, inv, common, out),
                      StatusCode::kSizeMismatch, {"velocities"}));
  std::vector<BodyHandle> short_out(n - 1);
  EXPECT_TRUE(
      IsError(world_->create_bodies(pos, vel, radii, inv, common, short_out), StatusCode::kSizeMismatch));
  expect_unchanged();
  // Zero velocity columns mean "all at rest"; the valid import lands as given.
  IMPACT_ASSERT_OK(world_->create_bodies(pos, Eigen::Matrix3Xf(3, 0), radii, inv, common, out));
  std::vector<Eigen::Vector3f> p(n), v(n);
  IMPACT_ASSERT_OK(world_->get_positions(out, p));
  IMPACT_ASSERT_OK(world_->get_velocities(out, v));
  for (int i = 0; i < n; ++i) {
    EXPECT_EQ(p[i], pos.col(i));
    EXPECT_EQ(v[i], Eigen::Vector3f::Zero());
  }
}

TEST_F(WorldValidation, SetPositionsAndVelocitiesRejectBadValuesAtomically) {
  std::vector<Eigen::Vector3f> values{{1, 2, 3}, {4, 5, 6}, {kNaN, 0, 0}};
  std::vector<BodyHandle> h{handles_[0], handles_[1], handles_[2]};
  EXPECT_TRUE(
      IsError(world_->set_positions(h, values), StatusCode::kInvalidArgument, {"body 2", "position"}));
  EXPECT_TRUE(
      IsError(world_->set_velocities(h, values), StatusCode::kInvalidArgument, {"body 2", "velocity"}));
  values[2] = {0, kInf, 0};
  EXPECT_TRUE(
      IsError(world_->set_positions(h, values), StatusCode::kInvalidArgument, {"body 2", "position"}));
  values[2] = {0, 0, 5e18f};
  EXPECT_TRUE(
      IsError(world_->set_positions(h, values), StatusCode::kInvalidArgument, {"body 2", "position"}));
  expect_unchanged();  // bodies 0 and 1 were not written either
  values.pop_back();
  EXPECT_TRUE(IsError(world_->set_positions(h, values), StatusCode::kSizeMismatch));
  EXPECT_TRUE(IsError(world_->set_velocities(h, values), StatusCode::kSizeMismatch));
  std::vector<Eigen::Vector3f> out(2);
  EXPECT_TRUE(IsError(world_->get_positions(h, out), StatusCode::kSizeMismatch));
  EXPECT_TRUE(IsError(world_->get_velocities(h, out), StatusCode::kSizeMismatch));
  expect_unchanged();
}

TEST_F(WorldValidation, StaleAndNullHandles) {
  const BodyHandle gone = handles_[1];
  IMPACT_ASSERT_OK(world_->destroy_bodies(std::span(&gone, 1)));
  before_ = snapshot(*world_);
  const BodyHandle null{};
  const BodyHandle out_of_range{1000, 1};
  const BodyHandle wrong_generation{handles_[0].index, handles_[0].generation + 7};
  const Eigen::Vector3f v(1, 1, 1);
  for (BodyHandle bad : {gone, null, out_of_range, wrong_generation}) {
    SCOPED_TRACE(bad.index);
    // The bad handle sits at position 1 of the batch, after a valid one.
    std::vector<BodyHandle> h{handles_[0], bad};
    std::vector<Eigen::Vector3f> vals{v, v};
    EXPECT_TRUE(IsError(world_->set_positions(h, vals), StatusCode::kStaleHandle, {"body 1"}));
    EXPECT_TRUE(IsError(world_->set_velocities(h, vals), StatusCode::kStaleHandle, {"body 1"}));
    std::vector<Eigen::Vector3f> out(2);
    EXPECT_TRUE(IsError(world_->get_positions(h, out), StatusCode::kStaleHandle, {"body 1"}));
    EXPECT_TRUE(IsError(world_->get_velocities(h, out), StatusCode::kStaleHandle, {"body 1"}));
    EXPECT_TRUE(IsError(world_->destroy_bodies(h), StatusCode::kStaleHandle, {"body 1"}));
    uint32_t slot = 12345;
    EXPECT_TRUE(IsError(world_->slot_of(bad, &slot), StatusCode::kStaleHandle));
    expect_unchanged();
  }
  EXPECT_TRUE(IsError(world_->set_positions(std::span(&null, 1), std::span(&v, 1)), StatusCode::kStaleHandle,
                      {"null"}));
}

TEST_F(WorldValidation, DestroyIsAllOrNothing) {
  std::vector<BodyHandle> dup{handles_[2], handles_[3], handles_[2]};
  EXPECT_TRUE(IsError(world_->destroy_bodies(dup), StatusCode::kInvalidArgument));
  expect_unchanged();
  for (BodyHandle h : handles_) {
    uint32_t slot;
    IMPACT_EXPECT_OK(world_->slot_of(h, &slot));
  }
}

TEST_F(WorldValidation, PlanesRejectBadFields) {
  struct Case {
    size_t bad;
    const char* field;
    void (*spoil)(PlaneDesc&);
  };
  const Case cases[] = {
      {1, "normal", [](PlaneDesc& p) { p.normal = Eigen::Vector3f::Zero(); }},
      {0, "normal", [](PlaneDesc& p) { p.normal.x() = kNaN; }},
      {2, "normal", [](PlaneDesc& p) { p.normal.z() = kInf; }},
      {2, "offset", [](PlaneDesc& p) { p.offset = kNaN; }},
      {1, "offset", [](PlaneDesc& p) { p.offset = -kInf; }},
      {1, "restitution", [](PlaneDesc& p) { p.restitution = 1.5f; }},
      {0, "restitution", [](PlaneDesc& p) { p.restitution = kNaN; }},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.field);
    std::vector<PlaneDesc> p(3);
    c.spoil(p[c.bad]);
    std::vector<PlaneHandle> out(3);
    const std::string who = "plane " + std::to_string(c.bad);
    EXPECT_TRUE(IsError(world_->create_planes(p, out), StatusCode::kInvalidArgument, {who.c_str(), c.field}));
    expect_unchanged();
  }
  std::vector<PlaneDesc> p(2);
  std::vector<PlaneHandle> out(1);
  EXPECT_TRUE(IsError(world_->create_planes(p, out), StatusCode::kSizeMismatch));
  expect_unchanged();
}

TEST_F(WorldValidation, PlaneNormalNeedNotBeUnitLength) {
  // PlaneDesc: the normal "need not be unit length (it is normalised) but must be
  // finite and non-zero". Very long and very short finite normals describe the
  // same floor as (0, 1, 0) and must be accepted.
  for (float s : {1e-30f, 1e-20f, 1e20f, 1e30f}) {
    SCOPED_TRACE(s);
    auto w = test::make_world(test::zero_gravity_desc());
    PlaneDesc p;
    p.normal = {0.0f, s, 0.0f};
    p.offset = 0.0f;
    PlaneHandle h;
    IMPACT_EXPECT_OK(w->create_planes(std::span(&p, 1), std::span(&h, 1)));
    if (w->plane_count() != 1) continue;
    BodyDesc b;
    b.position = {0, 0.25f, 0};
    BodyHandle bh;
    IMPACT_ASSERT_OK(w->create_bodies(std::span(&b, 1), std::span(&bh, 1)));
    IMPACT_ASSERT_OK(w->step());
    const ContactArrays c = w->contacts();
    ASSERT_EQ(c.size(), 1u);
    EXPECT_NEAR(c.normal_y[0], -1.0f, 1e-6);  // normalised to unit length
    EXPECT_NEAR(c.depth[0], 0.25f, 1e-6);
  }
}

TEST_F(WorldValidation, DestroyPlanesStaleAndDuplicate) {
  auto w = test::make_world(WorldDesc{});
  std::vector<PlaneDesc> p(3);
  std::vector<PlaneHandle> h(3);
  IMPACT_ASSERT_OK(w->create_planes(p, h));
  IMPACT_ASSERT_OK(w->destroy_planes(std::span(&h[1], 1)));
  EXPECT_EQ(w->plane_count(), 2u);
  EXPECT_TRUE(IsError(w->destroy_planes(std::span(&h[1], 1)), StatusCode::kStaleHandle, {"plane 0"}));
  const PlaneHandle null{};
  std::vector<PlaneHandle> with_null{h[0], null};
  EXPECT_TRUE(IsError(w->destroy_planes(with_null), StatusCode::kStaleHandle, {"plane 1"}));
  std::vector<PlaneHandle> dup{h[2], h[2]};
  EXPECT_TRUE(IsError(w->destroy_planes(dup), StatusCode::kInvalidArgument));
  EXPECT_EQ(w->plane_count(), 2u);
  // Swap-remove kept h[2] valid.
  IMPACT_ASSERT_OK(w->destroy_planes(std::span(&h[2], 1)));
  IMPACT_ASSERT_OK(w->destroy_planes(std::span(&h[0], 1)));
  EXPECT_EQ(w->plane_count(), 0u);
}

TEST(WorldDescValidation, InvalidDescsAreRejected) {
  struct Case {
    const char* field;
    StatusCode code;
    void (*spoil)(WorldDesc&);
  };
  const Case cases[] = {
      {"fixed_dt", StatusCode::kInvalidArgument, [](WorldDesc& d) { d.fixed_dt = 0.0f; }},
      {"fixed_dt", StatusCode::kInvalidArgument, [](WorldDesc& d) { d.fixed_dt = -0.01f; }},
      {"fixed_dt", StatusCode::kInvalidArgument, [](WorldDesc& d) { d.fixed_dt = kNaN; }},
      {"fixed_dt", StatusCode::kInvalidArgument, [](WorldDesc& d) { d.fixed_dt = kInf; }},
      {"gravity", StatusCode::kInvalidArgument, [](WorldDesc& d) { d.gravity.y() = kNaN; }},
      {"gravity", StatusCode::kInvalidArgument, [](WorldDesc& d) { d.gravity.x() = -kInf; }},
      {"max_steps_per_frame", StatusCode::kInvalidArgument, [](WorldDesc& d) { d.max_steps_per_frame = 0; }},
      {"position_correction", StatusCode::kInvalidArgument,
       [](WorldDesc& d) { d.solver.position_correction = 1.5f; }},
      {"penetration_slop", StatusCode::kInvalidArgument,
       [](WorldDesc& d) { d.solver.penetration_slop = -1.0f; }},
      {"restitution_threshold", StatusCode::kInvalidArgument,
       [](WorldDesc& d) { d.solver.restitution_threshold = kNaN; }},
      {"warm_start", StatusCode::kInvalidArgument, [](WorldDesc& d) { d.solver.warm_start = 2.0f; }},
      {"broad_phase", StatusCode::kInvalidArgument,
       [](WorldDesc& d) { d.broad_phase = static_cast<BroadPhaseKind>(7); }},
      {"lbvh_update", StatusCode::kInvalidArgument, [](WorldDesc& d) { d.lbvh_update = static_cast<LbvhUpdate>(9); }},
      {"lbvh_fat_margin", StatusCode::kInvalidArgument, [](WorldDesc& d) { d.lbvh_fat_margin = -1.0f; }},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.field);
    WorldDesc d;
    c.spoil(d);
    std::unique_ptr<World> w = test::make_world(WorldDesc{});  // non-null: must be reset
    EXPECT_TRUE(IsError(World::create(d, &w), c.code, {c.field}));
    EXPECT_EQ(w, nullptr);
  }
  EXPECT_TRUE(IsError(World::create(WorldDesc{}, nullptr), StatusCode::kInvalidArgument));
}

TEST_F(WorldValidation, SettersRejectInvalidValuesAndKeepSettings) {
  const Eigen::Vector3f g = world_->desc().gravity;
  EXPECT_TRUE(IsError(world_->set_gravity({0, kNaN, 0}), StatusCode::kInvalidArgument, {"gravity"}));
  EXPECT_EQ(world_->desc().gravity, g);
  SolverDesc s;
  s.position_correction = -0.5f;
  EXPECT_TRUE(IsError(world_->set_solver(s), StatusCode::kInvalidArgument, {"position_correction"}));
  EXPECT_EQ(world_->desc().solver.position_correction, SolverDesc{}.position_correction);
  EXPECT_TRUE(IsError(world_->set_broad_phase(static_cast<BroadPhaseKind>(9)), StatusCode::kInvalidArgument));
  EXPECT_EQ(world_->desc().broad_phase, BroadPhaseKind::kGrid);
  EXPECT_TRUE(IsError(world_->set_backend(static_cast<Backend>(42), 1), StatusCode::kUnsupported));
  expect_unchanged();
  // After all of that, a step still works.
  IMPACT_EXPECT_OK(world_->step());
}

}  // namespace
}  // namespace impact

namespace impact {
namespace {

TEST(WorldRobustness, FiniteInputsNeverLeadToNonFiniteState) {
  // Every value below passes validation (finite, positions within 1e18 m), but
  // x += v dt with |v| = 3e38 m/s overflows to Inf after ~70 steps of 1/60 s.
  // The world must then either refuse the input, report an error from step(),
  // or keep its state finite: an Inf position reaches the grid's cell
  // computation (a float -> int64 cast of Inf) and the sort keys.
  auto world = test::make_world(test::zero_gravity_desc());
  std::vector<BodyDesc> d(3);
  d[0].velocity = {3e38f, 0.0f, 0.0f};
  d[1].position = {5.0f, 0.0f, 0.0f};
  d[2].position = {5.5f, 0.0f, 0.0f};
  std::vector<BodyHandle> h(3);
  const Status created = world->create_bodies(d, h);
  if (!created.ok()) {
    EXPECT_TRUE(IsError(created, StatusCode::kInvalidArgument, {"body 0", "velocity"}));
    return;
  }
  for (int k = 1; k <= 200; ++k) {
    if (!world->step().ok()) return;  // reported: acceptable
    const BodyArrays b = world->bodies();
    for (size_t i = 0; i < b.size(); ++i) {
      ASSERT_TRUE(std::isfinite(b.pos_x[i]) && std::isfinite(b.vel_x[i]))
          << "step " << k << ": slot " << i << " holds x = " << b.pos_x[i] << ", v = " << b.vel_x[i]
          << " after a step that reported success";
    }
  }
}

}  // namespace
}  // namespace impact
