#include "scenelod/selection/visibility.h"

#include "scenelod/scene/scene.h"
#include "scenelod/selection/camera_path.h"
#include "scenelod/selection/level_table.h"
#include "scenelod/selection/replay_runner.h"
#include "scenelod/selection/replay_scene.h"
#include "scenelod/selection/replay_visibility.h"
#include "scenelod/selection/selector.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <thread>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "eval/test_meshes.h"

using namespace scenelod;
using namespace scenelod::selection;
using scenelod::test::makeBox;  // an axis-aligned box, 12 outward-facing triangles

namespace {

LodLevel level(Mesh mesh, float max_error) {
  LodLevel l;
  l.mesh = std::move(mesh);
  l.max_error = max_error;
  return l;
}

LodChain singleLevel(Mesh mesh) {
  LodChain c;
  c.levels.push_back(level(std::move(mesh), 0.0f));
  return c;
}

glm::mat4 at(glm::vec3 p) { return glm::translate(glm::mat4(1.0f), p); }

Camera frontCamera() {
  Camera c;
  c.eye = {0.0f, 0.0f, 10.0f};
  c.target = {0.0f, 0.0f, 0.0f};
  c.viewport_width_px = 160;
  c.viewport_height_px = 120;
  c.fov_y_rad = 0.8f;
  return c;
}

// True visible fraction of `object`: among the pixels where the object alone is hit (at full
// detail), the share where it is the first hit in the full-detail scene.
float denseVisibleFraction(const std::vector<const LodChain*>& chains, const std::vector<glm::mat4>& world,
                           const std::vector<uint32_t>& chain_ids, uint32_t object, const Camera& cam) {
  RayScene full, alone;
  EXPECT_TRUE(full.init(Span<const LodChain* const>(chains.data(), chains.size())).ok());
  EXPECT_TRUE(alone.init(Span<const LodChain* const>(chains.data(), chains.size())).ok());
  const std::vector<int32_t> finest(world.size(), 0);
  EXPECT_TRUE(full.setObjects(world, chain_ids, finest).ok());
  const glm::mat4 w = world[object];
  const uint32_t cid = chain_ids[object];
  const int32_t l0 = 0;
  EXPECT_TRUE(alone.setObjects(Span<const glm::mat4>(&w, 1), Span<const uint32_t>(&cid, 1), Span<const int32_t>(&l0, 1)).ok());
  full.commit();
  alone.commit();
  size_t covered = 0, visible = 0;
  for (uint32_t y = 0; y < cam.viewport_height_px; ++y)
    for (uint32_t x = 0; x < cam.viewport_width_px; ++x) {
      const glm::vec2 px(x + 0.5f, y + 0.5f);
      if (alone.pick(cam, px).object != 0) continue;
      ++covered;
      if (full.pick(cam, px).object == static_cast<int32_t>(object)) ++visible;
    }
  EXPECT_GT(covered, 100u);
  return covered ? static_cast<float>(visible) / static_cast<float>(covered) : 1.0f;
}

// Chains: 0 = unit cube (half size 0.5), 1 = wall 8 x 8 x 0.1, 2 = small cube (half size 0.2).
struct WallScene {
  LodChain cube = singleLevel(makeBox(glm::vec3(-0.5f), glm::vec3(0.5f)));
  LodChain wall = singleLevel(makeBox({-4.0f, -4.0f, -0.05f}, {4.0f, 4.0f, 0.05f}));
  LodChain small = singleLevel(makeBox(glm::vec3(-0.2f), glm::vec3(0.2f)));
  std::vector<const LodChain*> chains{&cube, &wall, &small};
  std::vector<glm::mat4> world;
  std::vector<uint32_t> chain_ids;
  std::vector<int32_t> levels;

  uint32_t add(uint32_t chain, glm::mat4 w) {
    world.push_back(w);
    chain_ids.push_back(chain);
    levels.push_back(0);
    return static_cast<uint32_t>(world.size() - 1);
  }
  Error build(RayScene& rs, const RaySceneParams& p = {}) {
    Error e = rs.init(Span<const LodChain* const>(chains.data(), chains.size()), p);
    if (!e.ok()) return e;
    e = rs.setObjects(world, chain_ids, levels);
    rs.commit();
    return e;
  }
};

// object 0: the cube behind the wall (object 1); objects 2..: small visible cubes around, so the
// estimator has more candidates than its per-frame budget
WallScene occludedScene() {
  WallScene s;
  s.add(0, at({0.0f, 0.0f, 0.0f}));
  s.add(1, at({0.0f, 0.0f, 4.0f}));
  for (int i = 0; i < 24; ++i) {
    const float x = -2.6f + 0.45f * static_cast<float>(i % 12);
    const float y = i < 12 ? 2.2f : -2.2f;
    s.add(2, at({x, y, 5.0f}));
  }
  return s;
}

}  // namespace

TEST(Visibility, PixelRayThroughCentreLooksAtTarget) {
  const Camera c = frontCamera();
  const Ray r = pixelRay(c, {80.0f, 60.0f});
  EXPECT_NEAR(r.direction.z, -1.0f, 1e-6f);
  EXPECT_NEAR(glm::length(r.direction), 1.0f, 1e-6f);
  // top-left pixel looks up and left
  const Ray tl = pixelRay(c, {0.5f, 0.5f});
  EXPECT_LT(tl.direction.x, 0.0f);
  EXPECT_GT(tl.direction.y, 0.0f);
  // vertical half-angle of the top edge equals fov/2
  const Ray top = pixelRay(c, {80.0f, 0.0f});
  EXPECT_NEAR(std::atan2(top.direction.y, -top.direction.z), 0.4f, 1e-5f);
}

TEST(Visibility, OccluderLevelIsCoarsestWithinRelativeError) {
  LodChain c;
  c.levels.push_back(level(makeBox(glm::vec3(-1.0f), glm::vec3(1.0f)), 0.0f));
  c.levels.push_back(level(makeBox(glm::vec3(-1.0f), glm::vec3(1.0f)), 0.01f));
  c.levels.push_back(level(makeBox(glm::vec3(-1.0f), glm::vec3(1.0f)), 0.03f));
  c.levels.push_back(level(makeBox(glm::vec3(-1.0f), glm::vec3(1.0f)), 1.0f));
  const LodChain* chains[] = {&c};
  RaySceneParams p;
  p.occluder_relative_error = 0.01f;  // radius sqrt(3): allowance 0.0173
  RayScene rs;
  ASSERT_TRUE(rs.init(Span<const LodChain* const>(chains, 1), p).ok());
  EXPECT_EQ(rs.occluderLevel(0), 1);
  p.occluder_relative_error = 0.0f;
  ASSERT_TRUE(rs.init(Span<const LodChain* const>(chains, 1), p).ok());
  EXPECT_EQ(rs.occluderLevel(0), 0);
}

TEST(Visibility, BadInputIsRefusedWithAMessage) {
  RayScene rs;
  const LodChain* null_chain[] = {nullptr};
  Error e = rs.init(Span<const LodChain* const>(null_chain, 1));
  EXPECT_EQ(e.status, Status::kInvalidArgument);
  EXPECT_NE(e.message.find("chain 0 is null"), std::string::npos) << e.message;

  LodChain empty;
  const LodChain* empty_chain[] = {&empty};
  e = rs.init(Span<const LodChain* const>(empty_chain, 1));
  EXPECT_NE(e.message.find("chain 0 has no levels"), std::string::npos) << e.message;

  LodChain bad = singleLevel(makeBox(glm::vec3(0.0f), glm::vec3(1.0f)));
  bad.levels[0].mesh.triangles[5] = 99;
  const LodChain* bad_chain[] = {&bad};
  e = rs.init(Span<const LodChain* const>(bad_chain, 1));
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_NE(e.message.find("chain 0 level 0"), std::string::npos) << e.message;

  WallScene s;
  s.add(0, at({0, 0, 0}));
  ASSERT_TRUE(s.build(rs).ok());
  const glm::mat4 w(1.0f);
  const uint32_t chain_far = 7;
  const int32_t l0 = 0, l9 = 9;
  e = rs.setObjects(Span<const glm::mat4>(&w, 1), Span<const uint32_t>(&chain_far, 1), Span<const int32_t>(&l0, 1));
  EXPECT_NE(e.message.find("object 0: chain id 7 out of range"), std::string::npos) << e.message;
  const uint32_t c0 = 0;
  e = rs.setObjects(Span<const glm::mat4>(&w, 1), Span<const uint32_t>(&c0, 1), Span<const int32_t>(&l9, 1));
  EXPECT_NE(e.message.find("drawn level 9 outside [-1, 1)"), std::string::npos) << e.message;
  e = rs.setObjects(Span<const glm::mat4>(&w, 1), Span<const uint32_t>(&c0, 0), Span<const int32_t>(&l0, 1));
  EXPECT_NE(e.message.find("1 transforms, 0 chain ids"), std::string::npos) << e.message;
  const glm::mat4 singular(0.0f);
  uint32_t id = 0;
  e = rs.addObject(singular, 0, 0, id);
  EXPECT_NE(e.message.find("singular"), std::string::npos) << e.message;
  glm::mat4 nan_m(1.0f);
  nan_m[3][0] = std::nanf("");
  e = rs.addObject(nan_m, 0, 0, id);
  EXPECT_NE(e.message.find("not finite"), std::string::npos) << e.message;
  e = rs.removeObject(42);
  EXPECT_EQ(e.status, Status::kNotFound);
  EXPECT_NE(e.message.find("id 42"), std::string::npos) << e.message;

  OcclusionEstimator est;
  EXPECT_EQ(est.init(0).status, Status::kInvalidArgument);
  OcclusionParams p;
  p.rays_per_test = 0;
  EXPECT_NE(est.init(10, p).message.find("rays_per_test 0 outside [1, 256]"), std::string::npos);
  // output too small, scene larger than the estimator was sized for
  ASSERT_TRUE(est.init(1).ok());
  std::vector<float> none;
  EXPECT_TRUE(est.validate(rs, Span<float>(none)));
  ASSERT_TRUE(rs.addObject(at({2, 0, 0}), 0, 0, id).ok());
  rs.commit();
  std::vector<float> two(2);
  EXPECT_FALSE(est.validate(rs, Span<float>(two)));
  EXPECT_FALSE(est.update(rs, frontCamera(), Span<float>(two)));
  ASSERT_TRUE(est.init(2).ok());
  std::vector<float> one(1);
  EXPECT_FALSE(est.update(rs, frontCamera(), Span<float>(one)));
  EXPECT_TRUE(est.update(rs, frontCamera(), Span<float>(two)));
}

TEST(Visibility, UntestedObjectsReadAsVisible) {
  WallScene s = occludedScene();
  RayScene rs;
  ASSERT_TRUE(s.build(rs).ok());
  OcclusionEstimator est;
  OcclusionParams p;
  p.ray_budget = 0;  // nothing gets tested
  ASSERT_TRUE(est.init(64, p).ok());
  std::vector<float> vis(rs.objectCapacity(), -1.0f);
  ASSERT_TRUE(est.update(rs, frontCamera(), Span<float>(vis)));
  for (float v : vis) EXPECT_EQ(v, 1.0f);
  EXPECT_EQ(est.ageFrames(rs, 0), UINT32_MAX);
  EXPECT_EQ(est.lastStats().objects_tested, 0u);
  EXPECT_EQ(est.lastStats().candidates, rs.objectCapacity());
}

TEST(Visibility, ObjectBehindWallFoundOccludedWithinTenFramesAndBackWhenWallGoes) {
  WallScene s = occludedScene();
  RayScene rs;
  ASSERT_TRUE(s.build(rs).ok());
  OcclusionEstimator est;
  OcclusionParams p;
  p.ray_budget = 4 * p.rays_per_test;  // 4 of 26 objects per frame
  ASSERT_TRUE(est.init(64, p).ok());
  const Camera cam = frontCamera();
  std::vector<float> vis(rs.objectCapacity());
  int found = -1;
  for (int f = 1; f <= 10 && found < 0; ++f) {
    ASSERT_TRUE(est.update(rs, cam, Span<float>(vis)));
    EXPECT_LE(est.lastStats().samples, p.ray_budget);
    if (est.ageFrames(rs, 0) != UINT32_MAX && vis[0] == 0.0f) found = f;
  }
  ASSERT_GT(found, 0) << "cube behind the wall not found occluded in 10 frames";
  // the wall and the small cubes in front of it are seen wherever they were tested
  // (the small cubes hide a little of the wall)
  size_t tested = 0;
  for (uint32_t id = 1; id < rs.objectCapacity(); ++id) {
    if (est.ageFrames(rs, id) == UINT32_MAX) continue;
    ++tested;
    if (id == 1) {
      EXPECT_GT(vis[id], 0.75f);
    } else {
      EXPECT_EQ(vis[id], 1.0f) << "object " << id;
    }
  }
  EXPECT_GT(tested, 0u);

  ASSERT_TRUE(rs.removeObject(1).ok());
  rs.commit();
  int back = -1;
  for (int f = 1; f <= 10 && back < 0; ++f) {
    ASSERT_TRUE(est.update(rs, cam, Span<float>(vis)));
    if (vis[0] == 1.0f && est.ageFrames(rs, 0) == 0) back = f;
  }
  EXPECT_GT(back, 0) << "cube not seen again within 10 frames of removing the wall";
}

TEST(Visibility, MovingInFrontOfTheWallMakesTheObjectVisible) {
  WallScene s = occludedScene();
  RayScene rs;
  ASSERT_TRUE(s.build(rs).ok());
  OcclusionEstimator est;
  ASSERT_TRUE(est.init(64).ok());  // default budget tests everything each frame here
  const Camera cam = frontCamera();
  ASSERT_TRUE(est.update(rs, cam, {}));
  EXPECT_EQ(est.visibleFraction(rs, 0), 0.0f);
  // the wall is at z = 4: move the cube between it and the eye
  rs.setTransform(0, at({0.0f, 0.0f, 6.0f}));
  rs.commit();
  ASSERT_TRUE(est.update(rs, cam, {}));
  EXPECT_EQ(est.visibleFraction(rs, 0), 1.0f);
  EXPECT_EQ(est.ageFrames(rs, 0), 0u);
}

TEST(Visibility, HalfHiddenObjectEstimatedWithinPointTwoOfDenseRayCasting) {
  // a cube turned 30 degrees about y, partly behind a wall whose edge does not cut it in half
  WallScene s;
  s.add(0, glm::rotate(at({0.0f, 0.0f, 0.0f}), 0.5236f, glm::vec3(0, 1, 0)));
  s.add(1, at({-4.0f, 0.0f, 3.0f}));  // wall spans x in [-8, 0] at z = 3
  const Camera cam = frontCamera();
  const float truth = denseVisibleFraction(s.chains, s.world, s.chain_ids, 0, cam);
  EXPECT_GT(truth, 0.25f);
  EXPECT_LT(truth, 0.75f);

  RayScene rs;
  ASSERT_TRUE(s.build(rs).ok());
  OcclusionEstimator est;
  ASSERT_TRUE(est.init(8).ok());
  // every test (the pattern rotates each frame) lands within 0.2 of the truth
  for (int f = 0; f < 12; ++f) {
    ASSERT_TRUE(est.update(rs, cam, {}));
    ASSERT_EQ(est.ageFrames(rs, 0), 0u);
    EXPECT_NEAR(est.visibleFraction(rs, 0), truth, 0.2f) << "frame " << f;
  }
}

TEST(Visibility, CoarseOccluderErrorIsOnlyTrustedWhenItProjectsBelowThePixelLimit) {
  // the wall's coarse level bulges far past its true surface (level 0 misses the target, level 1
  // covers it) and says so in max_error: hits on it are ignored unless that error projects under
  // occluder_error_px pixels at the hit distance
  LodChain cube = singleLevel(makeBox(glm::vec3(-0.5f), glm::vec3(0.5f)));
  LodChain wall;
  wall.levels.push_back(level(makeBox({1.5f, -0.5f, -0.05f}, {2.5f, 0.5f, 0.05f}), 0.0f));
  wall.levels.push_back(level(makeBox({-0.5f, -0.5f, -0.05f}, {2.5f, 0.5f, 0.05f}), 2.0f));
  std::vector<const LodChain*> chains{&cube, &wall};
  std::vector<glm::mat4> world{at({0, 0, 0}), at({0, 0, 4})};
  std::vector<uint32_t> ids{0, 1};
  std::vector<int32_t> levels{0, 0};
  const Camera cam = frontCamera();
  // pixel size at the wall (distance 6): 2 * 6 * tan(0.4) / 120 = 0.0423; error 2 is ~47 px
  // 40 px: accepted if the test used the sample's far end (t ~ 9.5) instead of the hit distance 6
  for (float error_px : {1.0f, 40.0f, 100.0f}) {
    RaySceneParams p;
    p.occluder_relative_error = 10.0f;  // let the coarse level be the occluder
    p.occluder_error_px = error_px;
    RayScene rs;
    ASSERT_TRUE(rs.init(Span<const LodChain* const>(chains.data(), chains.size()), p).ok());
    ASSERT_EQ(rs.occluderLevel(1), 1);
    ASSERT_TRUE(rs.setObjects(world, ids, levels).ok());
    rs.commit();
    OcclusionEstimator est;
    ASSERT_TRUE(est.init(4).ok());
    ASSERT_TRUE(est.update(rs, cam, {}));
    if (error_px < 47.0f) {
      EXPECT_EQ(est.visibleFraction(rs, 0), 1.0f) << "untrusted coarse occluder hid the cube";
    } else {
      EXPECT_EQ(est.visibleFraction(rs, 0), 0.0f) << "trusted coarse occluder should hide the cube";
    }
  }
}

TEST(Visibility, PickReturnsNearerObjectAndTheLevelActuallyDrawn) {
  // object 0 (near): level 0 a cube of half size 0.5, level 1 a cube of half size 0.25;
  // object 1 (far): a big cube behind it
  LodChain near_chain;
  near_chain.levels.push_back(level(makeBox(glm::vec3(-0.5f), glm::vec3(0.5f)), 0.0f));
  near_chain.levels.push_back(level(makeBox(glm::vec3(-0.25f), glm::vec3(0.25f)), 0.25f));
  LodChain far_chain = singleLevel(makeBox(glm::vec3(-2.0f), glm::vec3(2.0f)));
  std::vector<const LodChain*> chains{&near_chain, &far_chain};
  std::vector<glm::mat4> world{at({0, 0, 2}), at({0, 0, -3})};
  std::vector<uint32_t> ids{0, 1};
  std::vector<int32_t> levels{1, 0};
  RayScene rs;
  ASSERT_TRUE(rs.init(Span<const LodChain* const>(chains.data(), chains.size())).ok());
  ASSERT_TRUE(rs.setObjects(world, ids, levels).ok());
  rs.commit();
  const Camera cam = frontCamera();

  PickHit h = rs.pick(cam, {80.0f, 60.0f});
  EXPECT_EQ(h.object, 0);
  EXPECT_EQ(h.level, 1);
  EXPECT_NEAR(h.distance, 10.0f - 2.25f, 1e-4f);
  EXPECT_NEAR(h.point.z, 2.25f, 1e-4f);

  // a pixel inside level 0's silhouette but outside level 1's: the drawn level misses, so the
  // far cube is what the user clicked on
  const Ray probe{cam.eye, glm::normalize(glm::vec3(0.4f, 0.0f, 2.5f) - cam.eye)};
  ASSERT_GT(std::fabs(probe.direction.x / probe.direction.z) * 7.5f, 0.25f);  // misses level 1
  h = rs.intersect(probe);
  EXPECT_EQ(h.object, 1);
  EXPECT_EQ(h.level, 0);
  EXPECT_NEAR(h.point.z, -1.0f, 1e-4f);

  rs.setDrawnLevel(0, 0);
  rs.commit();
  h = rs.intersect(probe);
  EXPECT_EQ(h.object, 0);
  EXPECT_EQ(h.level, 0);
  EXPECT_NEAR(h.point.z, 2.5f, 1e-4f);

  // not drawn: not pickable
  rs.setDrawnLevel(0, -1);
  rs.commit();
  h = rs.pick(cam, {80.0f, 60.0f});
  EXPECT_EQ(h.object, 1);

  // nothing there
  h = rs.pick(cam, {0.5f, 0.5f});
  EXPECT_EQ(h.object, -1);
}

TEST(Visibility, AddAndRemoveReuseIdsWithoutDisturbingOthers) {
  WallScene s;
  s.add(0, at({0, 0, 0}));
  s.add(0, at({3, 0, 0}));
  RayScene rs;
  ASSERT_TRUE(s.build(rs).ok());
  const uint32_t gen1 = rs.objectGeneration(1);
  ASSERT_TRUE(rs.removeObject(1).ok());
  rs.commit();
  EXPECT_FALSE(rs.isLive(1));
  const Camera cam = frontCamera();
  const Ray to1{cam.eye, glm::normalize(glm::vec3(3, 0, 0) - cam.eye)};
  EXPECT_EQ(rs.intersect(to1).object, -1);
  uint32_t id = 99;
  ASSERT_TRUE(rs.addObject(at({-3, 0, 0}), 2, 0, id).ok());
  EXPECT_EQ(id, 1u);
  EXPECT_NE(rs.objectGeneration(1), gen1);
  ASSERT_TRUE(rs.addObject(at({3, 0, 0}), 0, 0, id).ok());
  EXPECT_EQ(id, 2u);
  rs.commit();
  EXPECT_EQ(rs.intersect(to1).object, 2);
  EXPECT_EQ(rs.intersect(Ray{cam.eye, glm::normalize(glm::vec3(-3, 0, 0) - cam.eye)}).object, 1);
  EXPECT_EQ(rs.pick(cam, {80.0f, 60.0f}).object, 0);
  EXPECT_EQ(rs.objectCapacity(), 3u);
  EXPECT_NEAR(rs.worldSpheres()[2].x, 3.0f, 1e-6f);
}

TEST(Visibility, FocusPeaksAtThePickAndFallsToOneAtTheRadius) {
  WallScene s;
  for (int i = 0; i < 6; ++i) s.add(0, at({1.5f * static_cast<float>(i) - 3.0f, 0.0f, 0.0f}));
  RayScene rs;
  ASSERT_TRUE(s.build(rs).ok());
  const Camera cam = frontCamera();
  const PickHit h = rs.pick(cam, {80.0f, 60.0f});
  ASSERT_GE(h.object, 0);
  const FocusParams f = focusFromPick(rs, h, 2.0f, 3.0f);
  ASSERT_TRUE(f.enabled);
  std::vector<float> focus(rs.objectCapacity());
  computeFocusFactors(rs.worldSpheres(), f, Span<float>(focus));
  EXPECT_FLOAT_EQ(focus[static_cast<size_t>(h.object)], 4.0f);
  // factors never below 1 and never rising with distance from the pick
  const glm::vec3 p = h.point;
  for (size_t i = 0; i < focus.size(); ++i) {
    EXPECT_GE(focus[i], 1.0f);
    for (size_t j = 0; j < focus.size(); ++j) {
      const float di = glm::length(glm::vec3(rs.worldSpheres()[i]) - p);
      const float dj = glm::length(glm::vec3(rs.worldSpheres()[j]) - p);
      if (di < dj) {
        EXPECT_GE(focus[i], focus[j]);
      }
    }
  }
  // the cubes at x = -3 and 4.5 are more than 2 radii (2 * 0.866) beyond the pick: exactly 1
  EXPECT_EQ(focus[0], 1.0f);
  EXPECT_EQ(focus[5], 1.0f);
  // a pick that misses disables focus
  const FocusParams none = focusFromPick(rs, rs.pick(cam, {0.5f, 0.5f}));
  EXPECT_FALSE(none.enabled);
  computeFocusFactors(rs.worldSpheres(), none, Span<float>(focus));
  for (float v : focus) EXPECT_EQ(v, 1.0f);
}

namespace {

// closest hit of a ray with the surface of an axis-aligned box (the exit face when the origin is
// inside), or +inf
float slabHit(const Ray& r, glm::vec3 lo, glm::vec3 hi) {
  float t0 = -1e30f, t1 = 1e30f;
  for (int a = 0; a < 3; ++a) {
    const float inv = 1.0f / r.direction[a];
    float ta = (lo[a] - r.origin[a]) * inv, tb = (hi[a] - r.origin[a]) * inv;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  if (t0 > t1 || t1 < 0.0f) return std::numeric_limits<float>::infinity();
  return t0 >= 0.0f ? t0 : t1;
}

}  // namespace

TEST(Visibility, TopLevelMatchesBruteForceThroughMovesAddsAndRemoves) {
  // 400 cubes (translation and uniform scale keep them axis-aligned, so a slab test is the truth);
  // then rounds of moving every object (refits), removing and adding some (pending list, rebuilds)
  LodChain cube = singleLevel(makeBox(glm::vec3(-0.5f), glm::vec3(0.5f)));
  const LodChain* chains[] = {&cube};
  RayScene rs;
  ASSERT_TRUE(rs.init(Span<const LodChain* const>(chains, 1)).ok());
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-20.0f, 20.0f), size(0.2f, 2.0f);
  struct Box {
    glm::vec3 c;
    float s;
  };
  std::vector<Box> boxes(400);
  std::vector<glm::mat4> world;
  for (Box& b : boxes) {
    b = {{u(rng), u(rng), u(rng)}, size(rng)};
    world.push_back(glm::scale(at(b.c), glm::vec3(b.s)));
  }
  const std::vector<uint32_t> chain_ids(400, 0);
  const std::vector<int32_t> levels(400, 0);
  ASSERT_TRUE(rs.setObjects(world, chain_ids, levels).ok());
  rs.commit();
  std::vector<bool> live(400, true);
  for (int round = 0; round < 6; ++round) {
    if (round > 0) {
      for (size_t i = 0; i < boxes.size(); ++i) {
        if (!live[i]) continue;
        boxes[i].c += glm::vec3(u(rng), u(rng), u(rng)) * (round % 2 ? 0.05f : 0.5f);
        rs.setTransform(static_cast<uint32_t>(i), glm::scale(at(boxes[i].c), glm::vec3(boxes[i].s)));
      }
      for (int k = 0; k < 20 * round; ++k) {
        const uint32_t id = static_cast<uint32_t>(rng() % boxes.size());
        if (live[id]) {
          ASSERT_TRUE(rs.removeObject(id).ok());
          live[id] = false;
        }
      }
      for (int k = 0; k < 10 * round; ++k) {
        const Box b{{u(rng), u(rng), u(rng)}, size(rng)};
        uint32_t id = 0;
        ASSERT_TRUE(rs.addObject(glm::scale(at(b.c), glm::vec3(b.s)), 0, 0, id).ok());
        if (id >= boxes.size()) {
          boxes.resize(id + 1);
          live.resize(id + 1, false);
        }
        boxes[id] = b;
        live[id] = true;
      }
      rs.commit();
    }
    for (int q = 0; q < 300; ++q) {
      const Ray r{{u(rng), u(rng), u(rng)}, glm::normalize(glm::vec3(u(rng), u(rng), u(rng)))};
      float best = std::numeric_limits<float>::infinity();
      int32_t best_id = -1;
      for (size_t i = 0; i < boxes.size(); ++i) {
        if (!live[i]) continue;
        const float t = slabHit(r, boxes[i].c - 0.5f * boxes[i].s, boxes[i].c + 0.5f * boxes[i].s);
        if (t < best) {
          best = t;
          best_id = static_cast<int32_t>(i);
        }
      }
      const PickHit h = rs.intersect(r);
      ASSERT_EQ(h.object, best_id) << "round " << round << " ray " << q;
      if (best_id >= 0) {
        EXPECT_NEAR(h.distance, best, 1e-3f * std::max(1.0f, best));
      }
    }
  }
}

TEST(Visibility, SyncFromSceneMirrorsMovesAndSwapRemovals) {
  // root -> a (unit cube at x = -2), b (small cube at x = 0), c (unit cube at x = 2)
  scene::SceneData data;
  data.meshes.resize(2);
  data.meshes[0].mesh = makeBox(glm::vec3(-0.5f), glm::vec3(0.5f));
  data.meshes[1].mesh = makeBox(glm::vec3(-0.2f), glm::vec3(0.2f));
  data.nodes.resize(4);
  data.roots = {0};
  data.nodes[0].children = {1, 2, 3};
  const float xs[3] = {-2.0f, 0.0f, 2.0f};
  const int32_t meshes[3] = {0, 1, 0};
  for (int k = 0; k < 3; ++k) {
    data.nodes[1 + k].parent = 0;
    data.nodes[1 + k].local = at({xs[k], 0.0f, 0.0f});
    data.nodes[1 + k].mesh = meshes[k];
  }
  scene::Scene sc;
  ASSERT_TRUE(scene::Scene::fromSceneData(data, sc).ok());
  ASSERT_EQ(sc.objectCount(), 3u);
  LodChain c0 = singleLevel(data.meshes[0].mesh), c1 = singleLevel(data.meshes[1].mesh);
  const LodChain* chains[] = {&c0, &c1};
  RayScene rs;
  ASSERT_TRUE(rs.init(Span<const LodChain* const>(chains, 2)).ok());
  ASSERT_TRUE(rs.syncFromScene(sc).ok());
  rs.commit();
  const Camera cam = frontCamera();
  auto hitAt = [&](float x) {
    return rs.intersect(Ray{cam.eye, glm::normalize(glm::vec3(x, 0.0f, 0.0f) - cam.eye)});
  };
  EXPECT_EQ(hitAt(-2.0f).object, 0);
  EXPECT_EQ(hitAt(0.0f).object, 1);
  EXPECT_NEAR(hitAt(0.0f).distance, 9.8f, 1e-4f);
  EXPECT_EQ(hitAt(2.0f).object, 2);

  // move the root: every object follows
  ASSERT_TRUE(sc.setLocal(sc.nodeAt(0), at({0.0f, 0.0f, 1.0f})).ok());
  sc.update();
  const uint32_t gen0 = rs.objectGeneration(0);
  ASSERT_TRUE(rs.syncFromScene(sc).ok());
  rs.commit();
  EXPECT_NEAR(hitAt(0.0f).distance, 8.8f, 1e-4f);
  EXPECT_EQ(rs.objectGeneration(0), gen0);  // moved, not replaced

  // remove object 0: the scene swaps object 2 into index 0
  ASSERT_TRUE(sc.removeObject(sc.objectAt(0)).ok());
  sc.update();
  ASSERT_EQ(sc.objectCount(), 2u);
  ASSERT_TRUE(rs.syncFromScene(sc).ok());
  rs.commit();
  EXPECT_FALSE(rs.isLive(2));
  EXPECT_NE(rs.objectGeneration(0), gen0);
  EXPECT_EQ(hitAt(-2.0f).object, -1);
  EXPECT_EQ(hitAt(2.0f).object, 0);

  // drawn levels per dense index: -1 hides object 1 from picking
  const std::vector<int32_t> levels{0, -1};
  ASSERT_TRUE(rs.syncFromScene(sc, levels).ok());
  EXPECT_EQ(hitAt(0.0f).object, -1);
  const std::vector<int32_t> bad_levels{0, 3};
  const Error e = rs.syncFromScene(sc, bad_levels);
  EXPECT_NE(e.message.find("scene object 1: drawn level 3 outside [-1, 1)"), std::string::npos) << e.message;
  const std::vector<int32_t> short_levels{0};
  EXPECT_NE(rs.syncFromScene(sc, short_levels).message.find("1 drawn levels for 2 scene objects"), std::string::npos);
}

TEST(Visibility, SelectorGivesAnOccludedObjectItsCoarsestLevelOrNone) {
  // a cube behind a wall and a second cube in plain view, same 4-level chain (the level table's
  // counts make detail expensive); budget mode with room for both cubes at full detail
  WallScene s;
  LodChain cube4;
  for (int k = 0; k < 4; ++k) cube4.levels.push_back(level(makeBox(glm::vec3(-0.5f), glm::vec3(0.5f)), 0.0f));
  s.chains[0] = &cube4;
  s.add(0, at({0.0f, 0.0f, 0.0f}));   // hidden
  s.add(1, at({0.0f, 0.0f, 4.0f}));   // wall
  s.add(0, at({2.0f, 0.0f, 6.0f}));   // seen, in front of the wall
  RayScene rs;
  ASSERT_TRUE(s.build(rs).ok());
  const Camera cam = frontCamera();

  LevelTableData table;
  const float widths[4] = {0.0f, 0.01f, 0.04f, 0.16f};
  const uint32_t tris[4] = {200000, 50000, 12000, 3000}, verts[4] = {100000, 25000, 6000, 1500}, lp[4] = {0, 0, 0, 0};
  table.addChain(Span<const float>(widths, 4), Span<const uint32_t>(tris, 4), Span<const uint32_t>(verts, 4),
                 Span<const uint32_t>(lp, 4));
  const float wall_w[1] = {0.0f};
  const uint32_t wall_t[1] = {12}, wall_v[1] = {8}, wall_lp[1] = {0};
  table.addChain(Span<const float>(wall_w, 1), Span<const uint32_t>(wall_t, 1), Span<const uint32_t>(wall_v, 1),
                 Span<const uint32_t>(wall_lp, 1));
  const std::vector<uint32_t> chains{0, 1, 0};
  std::vector<glm::vec3> centers;
  std::vector<float> radii, scales;
  for (uint32_t id = 0; id < 3; ++id) {
    centers.push_back(glm::vec3(rs.worldSpheres()[id]));
    radii.push_back(rs.worldSpheres()[id].w);
    scales.push_back(1.0f);
  }

  SelectorConfig config;
  config.max_object_count = 3;
  SelectorContext* ctx = createSelectorContext(config);
  ASSERT_NE(ctx, nullptr);
  auto select = [&](Span<const float> visible) {
    std::vector<int8_t> out(3, 0);
    SelectionJob job;
    job.camera = &cam;
    job.params.mode = SelectionMode::kBudget;
    job.params.budget_ms = 1.0f;  // 0.5 per frame; a cube costs ~0.25 ms at level 0, 0.06 at level 1
    job.params.calibrate = false;
    job.levels = table.view();
    job.centers = Span<const glm::vec3>(centers.data(), centers.size());
    job.radii = Span<const float>(radii.data(), radii.size());
    job.max_scales = Span<const float>(scales.data(), scales.size());
    job.chains = Span<const uint32_t>(chains.data(), chains.size());
    job.visible_fraction = visible;
    job.context = ctx;
    job.levels_out = Span<int8_t>(out.data(), out.size());
    EXPECT_TRUE(job.run());
    return out;
  };
  // without visibility the hidden cube is drawn finer than its coarsest level
  resetSelectorHistory(ctx);
  const std::vector<int8_t> blind = select({});
  EXPECT_GE(blind[0], 0);
  EXPECT_LT(blind[0], 3);

  OcclusionEstimator est;
  OcclusionParams p;
  p.ray_budget = p.rays_per_test;  // one object per frame
  ASSERT_TRUE(est.init(3, p).ok());
  std::vector<float> vis(3);
  resetSelectorHistory(ctx);
  bool coarse = false;
  std::vector<int8_t> seen;
  for (int f = 0; f < 10 && !coarse; ++f) {
    ASSERT_TRUE(est.update(rs, cam, Span<float>(vis)));
    seen = select(Span<const float>(vis.data(), vis.size()));
    coarse = seen[0] == -1 || seen[0] == 3;
  }
  EXPECT_TRUE(coarse) << "hidden cube still at level " << int(seen[0]) << " after 10 frames";
  // the cube in view is drawn, at least as finely as without visibility (budget freed)
  EXPECT_GE(seen[2], 0);
  EXPECT_GE(blind[2], 0);
  EXPECT_LE(seen[2], blind[2]);
  EXPECT_EQ(vis[2], 1.0f);
  destroySelectorContext(ctx);
}

TEST(Visibility, ReplayWithVisibilityDropsHiddenObjectsAndLogsEstimates) {
  ReplayScene scene;
  ASSERT_TRUE(makeBuiltinScene("builtin:city", scene).ok());
  Replay replay;
  replay.header.scene = "builtin:city";
  replay.header.has_budget = true;
  replay.header.budget_ms = 8.0;
  makeCameraPath(sceneBounds(scene), CameraPathKind::kFlythrough, 40, 60.0, replay);
  for (size_t i = 0; i < replay.frames.size(); i += 10) {
    replay.frames[i].has_pick = true;
    replay.frames[i].pick_px[0] = 640.0f;
    replay.frames[i].pick_px[1] = 360.0f;
  }
  ReplayVisibility vis;
  ASSERT_TRUE(vis.init(scene).ok());
  ReplayRunOptions opt;
  opt.visibility = &vis;
  std::vector<ReplayLogFrame> log;
  ReplayScene run_scene = scene;
  ASSERT_TRUE(runReplay(replay, run_scene, opt, log).ok());
  ASSERT_EQ(log.size(), replay.frames.size());
  const LevelTable table = scene.table.view();
  size_t hidden_total = 0, picks = 0;
  for (const ReplayLogFrame& f : log) {
    ASSERT_TRUE(f.has_visibility);
    ASSERT_EQ(f.visible.size(), scene.objectCount());
    EXPECT_NE(replayLogLine(f).find("\"visible\": ["), std::string::npos);
    hidden_total += f.hidden_count;
    picks += f.pick_object >= 0 ? 1 : 0;
    for (size_t i = 0; i < f.visible.size(); ++i) {
      EXPECT_GE(f.visible[i], 0.0f);
      EXPECT_LE(f.visible[i], 1.0f);
      if (f.visible[i] != 0.0f) continue;
      // nothing to gain from detail: not drawn, or the coarsest level
      const uint32_t c = scene.object_chain[i];
      const int coarsest = static_cast<int>(table.chain_level_offset[c + 1] - table.chain_level_offset[c]) - 1;
      EXPECT_TRUE(f.levels[i] == -1 || f.levels[i] == coarsest)
          << "frame " << f.frame << " object " << i << " hidden but at level " << int(f.levels[i]);
    }
  }
  EXPECT_GT(hidden_total, 0u) << "the city fly-through should hide some buildings";
  EXPECT_GT(picks, 0u);
  // without visibility the log keeps its documented keys only
  std::vector<ReplayLogFrame> plain;
  ReplayScene plain_scene = scene;
  ASSERT_TRUE(runReplay(replay, plain_scene, ReplayRunOptions(), plain).ok());
  EXPECT_EQ(replayLogLine(plain[0]).find("visible"), std::string::npos);
}

TEST(Visibility, OrthographicCameraPicksAndFindsTheHiddenCube) {
  WallScene s = occludedScene();
  RayScene rs;
  ASSERT_TRUE(s.build(rs).ok());
  Camera cam = frontCamera();
  cam.projection = Projection::kOrthographic;
  cam.ortho_height = 10.0f;
  // the centre pixel's ray is parallel to -z through x = y = 0: the wall is first
  const PickHit h = rs.pick(cam, {80.0f, 60.0f});
  EXPECT_EQ(h.object, 1);
  EXPECT_NEAR(h.point.z, 4.05f, 1e-4f);
  EXPECT_NEAR(h.distance, 10.0f - 4.05f, 1e-4f);
  OcclusionEstimator est;
  ASSERT_TRUE(est.init(64).ok());
  ASSERT_TRUE(est.update(rs, cam, {}));
  EXPECT_EQ(est.visibleFraction(rs, 0), 0.0f);
  // parallel rays: a cube beside the wall (x = 5, beyond its half width 4) is seen in full
  rs.setTransform(0, at({5.0f, 0.0f, 0.0f}));
  rs.commit();
  ASSERT_TRUE(est.update(rs, cam, {}));
  EXPECT_EQ(est.visibleFraction(rs, 0), 1.0f);
}

TEST(Visibility, OffCentreObjectIsHiddenByASmallOccluderInBothProjections) {
  // parallel rays: the occluders of an object are searched along its own line of sight (through its
  // centre), not along the view axis through the eye
  WallScene s;
  s.add(0, at({3.0f, 2.0f, 0.0f}));
  s.add(0, glm::scale(at({3.0f, 2.0f, 3.0f}), glm::vec3(1.5f)));  // covers the first cube's silhouette
  s.add(2, at({-3.0f, -2.0f, 0.0f}));                              // nothing in front of it
  RayScene rs;
  ASSERT_TRUE(s.build(rs).ok());
  Camera cam = frontCamera();
  cam.projection = Projection::kOrthographic;
  cam.ortho_height = 10.0f;
  OcclusionEstimator est;
  ASSERT_TRUE(est.init(8).ok());
  ASSERT_TRUE(est.update(rs, cam, {}));
  ASSERT_EQ(est.ageFrames(rs, 0), 0u);
  EXPECT_EQ(est.visibleFraction(rs, 0), 0.0f);
  EXPECT_EQ(est.visibleFraction(rs, 1), 1.0f);
  EXPECT_EQ(est.visibleFraction(rs, 2), 1.0f);

  // perspective: the same off the view axis, the occluder on the line from the eye to the cube
  // (at 0.7 of the way its inscribed sphere, radius 0.75, holds the cube's cone of radius <= 0.61)
  cam.projection = Projection::kPerspective;
  const glm::vec3 on_line = cam.eye + 0.7f * (glm::vec3(3.0f, 2.0f, 0.0f) - cam.eye);
  rs.setTransform(1, glm::scale(at(on_line), glm::vec3(1.5f)));
  rs.commit();
  ASSERT_TRUE(est.update(rs, cam, {}));
  ASSERT_EQ(est.ageFrames(rs, 0), 0u);
  EXPECT_EQ(est.visibleFraction(rs, 0), 0.0f);
  EXPECT_EQ(est.visibleFraction(rs, 2), 1.0f);
}

TEST(Visibility, ConcurrentQueriesAfterCommitMatchSerialOnes) {
  WallScene s = occludedScene();
  RayScene rs;
  ASSERT_TRUE(s.build(rs).ok());
  const Camera cam = frontCamera();
  std::vector<int32_t> serial;
  for (uint32_t y = 0; y < 120; y += 3)
    for (uint32_t x = 0; x < 160; x += 3) serial.push_back(rs.pick(cam, {x + 0.5f, y + 0.5f}).object);
  OcclusionEstimator serial_est;
  ASSERT_TRUE(serial_est.init(64).ok());
  std::vector<float> serial_vis(rs.objectCapacity());
  ASSERT_TRUE(serial_est.update(rs, cam, Span<float>(serial_vis)));

  std::vector<std::vector<int32_t>> picks(2);
  std::vector<std::vector<float>> vis(2, std::vector<float>(rs.objectCapacity()));
  std::vector<std::thread> threads;
  for (int t = 0; t < 2; ++t)
    threads.emplace_back([&, t] {
      OcclusionEstimator est;  // one estimator per thread
      if (!est.init(64).ok()) return;
      for (int round = 0; round < 20; ++round) {
        picks[t].clear();
        for (uint32_t y = 0; y < 120; y += 3)
          for (uint32_t x = 0; x < 160; x += 3) picks[t].push_back(rs.pick(cam, {x + 0.5f, y + 0.5f}).object);
      }
      est.update(rs, cam, Span<float>(vis[t]));
    });
  for (std::thread& th : threads) th.join();
  for (int t = 0; t < 2; ++t) {
    EXPECT_EQ(picks[t], serial);
    EXPECT_EQ(vis[t], serial_vis);
  }
}
