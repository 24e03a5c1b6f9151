#include "scenelod/eval/metrics.h"

#include <cmath>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "eval/test_meshes.h"

namespace scenelod::eval {
namespace {

using test::makeBox;
using test::makeIcosphere;

TEST(Metrics, MeshAgainstItselfIsZero) {
  const Mesh m = makeIcosphere(2, 1.0f);
  DistanceResult r;
  ASSERT_TRUE(measureSurfaceDistance(m, m, {}, r).ok());
  EXPECT_LT(r.hausdorff, 1e-6);
  EXPECT_LT(r.rms, 1e-6);
  EXPECT_GE(r.forward.sample_count, DistanceParams{}.area_sample_count + m.vertexCount());
}

// Unit cube against the cube scaled by 1.01 about its centre: the scaled faces sit 0.005 outside.
// Every point of the unit cube is 0.005 from the scaled cube (its nearest face is parallel), so the
// forward distance is 0.005 everywhere; the farthest point of the scaled cube from the unit cube is
// a corner, 0.005 off along all three axes: 0.005 * sqrt(3). Relative to the diagonal sqrt(3) the
// Hausdorff distance is exactly 0.005.
TEST(Metrics, CubeScaledByOnePercentGivesCornerOffset) {
  const Mesh cube = makeBox(glm::vec3(0.0f), glm::vec3(1.0f));
  const Mesh big = test::scaled(cube, 1.01f, glm::vec3(0.5f));
  DistanceResult r;
  ASSERT_TRUE(measureSurfaceDistance(cube, big, {}, r).ok());
  EXPECT_NEAR(r.diagonal, std::sqrt(3.0), 1e-6);
  EXPECT_NEAR(r.forward.max, 0.005, 1e-5);
  EXPECT_NEAR(r.forward.rms, 0.005, 1e-5);
  EXPECT_NEAR(r.backward.max, 0.005 * std::sqrt(3.0), 1e-5);  // a corner is a vertex: sampled exactly
  EXPECT_NEAR(r.hausdorff, 0.005, 1e-5);
  // most of the scaled cube's area is 0.005 from a face; only the rims near edges are farther
  EXPECT_GT(r.backward.rms, 0.005 - 1e-5);
  EXPECT_LT(r.backward.rms, 0.0052);
}

// A sphere (fine icosphere, radius 1) against the inscribed icosahedron: the largest gap is at the
// face centres, R minus the icosahedron's inradius, 1 - sqrt((5 + 2 sqrt 5) / 15) = 0.2053...; the
// fine sphere itself sits up to about 5e-4 inside the true sphere, and samples need not hit the
// exact face centre: allow 2e-3.
TEST(Metrics, SphereAgainstInscribedIcosahedronMatchesAnalyticGap) {
  const Mesh sphere = makeIcosphere(4, 1.0f);
  const Mesh ico = makeIcosphere(0, 1.0f);
  const double gap = 1.0 - std::sqrt((5.0 + 2.0 * std::sqrt(5.0)) / 15.0);
  DistanceResult r;
  ASSERT_TRUE(measureSurfaceDistance(sphere, ico, {}, r).ok());
  EXPECT_NEAR(r.forward.max, gap, 2e-3);
  EXPECT_NEAR(r.backward.max, gap, 2e-3);
  EXPECT_NEAR(r.hausdorff * r.diagonal, gap, 2e-3);
  EXPECT_LT(r.rms * r.diagonal, gap);
  EXPECT_GT(r.rms * r.diagonal, 0.2 * gap);
}

// A thin plate [0,1] x [-h,h] against one thick edge along its middle, radius r = t/2 < h:
// plate -> capsule solid: the long rims are h - r away; capsule surface -> plate: at most r (the
// top of the capsule above the plate). Hausdorff = max(h - r, r) = 0.07 here, and a level of
// edges only is valid.
TEST(Metrics, ThickEdgeIsACapsule) {
  const float h = 0.1f, r = 0.03f;
  Mesh plate;
  plate.positions = {{0, -h, 0}, {1, -h, 0}, {1, h, 0}, {0, h, 0}};
  plate.triangles = {0, 1, 2, 0, 2, 3};
  Mesh edge;
  edge.positions = {{0, 0, 0}, {1, 0, 0}};
  edge.edges = {0, 1};
  edge.edge_thickness = {2 * r};
  DistanceResult res;
  ASSERT_TRUE(measureSurfaceDistance(plate, edge, {}, res).ok());
  EXPECT_NEAR(res.forward.max, h - r, 1e-5);
  EXPECT_LE(res.backward.max, r + 1e-5);
  EXPECT_GT(res.backward.max, 0.98 * r);
  EXPECT_NEAR(res.hausdorff, (h - r) / std::sqrt(1.0 + 4.0 * h * h), 1e-5);

  // a hairline edge (thickness 0) is the bare segment: the rims are h away
  edge.edge_thickness = {0.0f};
  ASSERT_TRUE(measureSurfaceDistance(plate, edge, {}, res).ok());
  EXPECT_NEAR(res.forward.max, h, 1e-5);
  EXPECT_LT(res.backward.max, 1e-6);
}

// Points are spheres of radius 0: a 2 x 2 plate against its four corners as points. The corners lie
// on the plate (backward 0); the plate point farthest from every corner is its centre, sqrt(2) away.
TEST(Metrics, PointsAreSpheresOfRadiusZero) {
  Mesh plate;
  plate.positions = {{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}};
  plate.triangles = {0, 1, 2, 0, 2, 3};
  Mesh corners = plate;
  corners.triangles.clear();
  corners.points = {0, 1, 2, 3};
  DistanceResult res;
  ASSERT_TRUE(measureSurfaceDistance(plate, corners, {}, res).ok());
  EXPECT_LT(res.backward.max, 1e-6);
  EXPECT_LE(res.forward.max, std::sqrt(2.0) + 1e-5);
  EXPECT_GT(res.forward.max, std::sqrt(2.0) - 0.02);  // samples land near the centre, not on it
}

TEST(Metrics, DeterministicWhateverTheThreadCount) {
  const Mesh sphere = makeIcosphere(3, 1.0f);
  const Mesh ico = makeIcosphere(1, 1.0f);
  DistanceResult a, b;
  ASSERT_TRUE(measureSurfaceDistance(sphere, ico, {}, a).ok());
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    ASSERT_TRUE(measureSurfaceDistance(sphere, ico, {}, b).ok());
  }
  EXPECT_EQ(a.hausdorff, b.hausdorff);
  EXPECT_EQ(a.rms, b.rms);
  EXPECT_EQ(a.forward.sample_count, b.forward.sample_count);
}

TEST(Metrics, BadInputGivesClearErrors) {
  const Mesh cube = makeBox(glm::vec3(0.0f), glm::vec3(1.0f));
  DistanceResult r;
  Mesh no_triangles;
  no_triangles.positions = {{0, 0, 0}, {1, 0, 0}};
  no_triangles.edges = {0, 1};
  Error e = measureSurfaceDistance(no_triangles, cube, {}, r);
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_NE(e.message.find("no triangles"), std::string::npos) << e.message;

  e = measureSurfaceDistance(cube, Mesh{}, {}, r);
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_NE(e.message.find("simplified"), std::string::npos) << e.message;

  Mesh broken = cube;
  broken.triangles[4] = 99;
  e = measureSurfaceDistance(cube, broken, {}, r);
  EXPECT_EQ(e.status, Status::kInvalidMesh) << e.message;

  Mesh flat;
  flat.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  flat.triangles = {0, 1, 2};
  e = measureSurfaceDistance(flat, cube, {}, r);
  EXPECT_EQ(e.status, Status::kInvalidMesh);
  EXPECT_NE(e.message.find("zero-area"), std::string::npos) << e.message;
}

TEST(Metrics, MismatchedScalesAreRejected) {
  const Mesh cube = makeBox(glm::vec3(0.0f), glm::vec3(1.0f));
  EXPECT_TRUE(checkComparableScales(cube, "a.obj", test::scaled(cube, 5.0f, glm::vec3(0.0f)), "b.obj").ok());
  const Error e = checkComparableScales(cube, "a.obj", test::scaled(cube, 100.0f, glm::vec3(0.0f)), "b.obj");
  EXPECT_EQ(e.status, Status::kInvalidArgument);
  EXPECT_NE(e.message.find("a.obj"), std::string::npos);
  EXPECT_NE(e.message.find("100.0x"), std::string::npos) << e.message;
}

}  // namespace
}  // namespace scenelod::eval
