#include "scenelod/eval/render.h"

#include <cmath>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "eval/test_meshes.h"

namespace scenelod::eval {
namespace {

using test::makeBox;
using test::makeIcosphere;

TEST(Render, StandardViewsAreSixAxesAndEightDiagonals) {
  int axes = 0, diagonals = 0;
  for (int i = 0; i < kStandardViewCount; ++i) {
    const View v = standardView(i);
    EXPECT_NEAR(glm::length(v.from), 1.0f, 1e-6f);
    EXPECT_LT(std::fabs(glm::dot(v.from, glm::normalize(v.up))), 0.99f);
    int nonzero = 0;
    for (int k = 0; k < 3; ++k) nonzero += v.from[k] != 0.0f;
    axes += nonzero == 1;
    diagonals += nonzero == 3;
    for (int j = 0; j < i; ++j) EXPECT_LT(glm::dot(v.from, standardView(j).from), 0.999f) << i << " " << j;
  }
  EXPECT_EQ(axes, 6);
  EXPECT_EQ(diagonals, 8);
}

TEST(ImageError, MeshAgainstItselfIsZero) {
  const Mesh m = makeIcosphere(2, 1.0f);
  ImageErrorResult r;
  ASSERT_TRUE(measureImageError(m, m, {}, r).ok());
  EXPECT_GT(r.either_px, 0u);
  EXPECT_EQ(r.one_px, 0u);
  EXPECT_EQ(r.silhouette, 0.0);
  EXPECT_LT(r.normal_deg, 1e-3);
}

TEST(ImageError, DisjointObjectsGiveFullSilhouetteMismatch) {
  const Mesh a = makeBox(glm::vec3(0.0f), glm::vec3(1.0f));
  const Mesh b = test::translated(a, glm::vec3(5.0f, 0.0f, 0.0f));  // outside a's bounding sphere
  ImageErrorResult r;
  ASSERT_TRUE(measureImageError(a, b, {}, r).ok());
  EXPECT_GT(r.either_px, 0u);
  EXPECT_EQ(r.both_px, 0u);
  EXPECT_EQ(r.silhouette, 1.0);
}

// The cube scaled by 1.01 covers a little more in every view and never less: mismatch is small and
// every mismatched pixel is covered by the bigger cube only. Seen along an axis both show a face
// head-on, so normals agree there; overall the faces are parallel, so the mean angle is ~0.
TEST(ImageError, SlightlyBiggerCubeGivesSmallMismatchAndParallelNormals) {
  const Mesh cube = makeBox(glm::vec3(0.0f), glm::vec3(1.0f));
  const Mesh big = test::scaled(cube, 1.01f, glm::vec3(0.5f));
  ImageErrorResult r;
  ASSERT_TRUE(measureImageError(cube, big, {}, r).ok());
  EXPECT_GT(r.silhouette, 0.0);
  EXPECT_LT(r.silhouette, 0.05);
  EXPECT_LT(r.normal_deg, 0.5);
  // the reverse comparison pools the same pixels
  ImageErrorResult rev;
  ImageErrorParams p;
  p.frame = boundingSphere(cube);
  ASSERT_TRUE(measureImageError(big, cube, p, rev).ok());
  EXPECT_EQ(rev.one_px, r.one_px);
  EXPECT_EQ(rev.either_px, r.either_px);
}

// A thick edge along x seen from +z: a capsule of radius r covers L * 2r + pi r^2 in projection, and
// its dynamic normal (Low & Tan §3.3.2) faces the camera everywhere, so it is flat-lit: every
// covered pixel has the same colour. (The capsule's geometric normal would shade it round.)
TEST(Render, ThickEdgeIsAFlatLitCapsule) {
  Mesh edge;
  edge.positions = {{-1, 0, 0}, {1, 0, 0}};
  edge.edges = {0, 1};
  edge.edge_thickness = {0.4f};
  RenderParams p;
  p.width = p.height = 256;
  p.view = standardView(4);
  p.frame = Sphere{glm::vec3(0.0f), 1.5f};
  p.background = glm::vec3(0.0f);
  Image img;
  ASSERT_TRUE(renderMesh(edge, p, img).ok());
  size_t covered = 0;
  const uint8_t* first = nullptr;
  bool flat = true;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const uint8_t* px = img.pixel(x, y);
      if (px[0] == 0 && px[1] == 0 && px[2] == 0) continue;
      ++covered;
      if (!first) first = px;
      flat = flat && px[0] == first[0] && px[1] == first[1] && px[2] == first[2];
    }
  const double pixel = 3.0 / 256.0, r = 0.2;
  const double expected = (2.0 * 2.0 * r + M_PI * r * r) / (pixel * pixel);
  EXPECT_NEAR(static_cast<double>(covered), expected, 0.02 * expected);
  EXPECT_TRUE(flat);

  // a hairline edge still shows, min_radius_px wide
  edge.edge_thickness = {0.0f};
  ASSERT_TRUE(renderMesh(edge, p, img).ok());
  covered = 0;
  for (size_t i = 0; i < img.rgb.size(); i += 3) covered += img.rgb[i] || img.rgb[i + 1] || img.rgb[i + 2];
  EXPECT_GT(covered, 2.0 / pixel);
  EXPECT_LT(covered, 3.0 * 2.0 / pixel);
}

TEST(Render, VertexColoursAreUsed) {
  Mesh m = makeBox(glm::vec3(0.0f), glm::vec3(1.0f));
  m.colors.assign(m.vertexCount(), glm::vec3(1.0f, 0.0f, 0.0f));
  RenderParams p;
  p.width = p.height = 64;
  p.ambient = 1.0f;  // unshaded: the colour itself
  Image img;
  ASSERT_TRUE(renderMesh(m, p, img).ok());
  const uint8_t* c = img.pixel(32, 32);
  EXPECT_EQ(c[0], 255);
  EXPECT_EQ(c[1], 0);
  EXPECT_EQ(c[2], 0);
}

TEST(Popping, ResolutionFollowsTheSwitchDistance) {
  LodChain chain;
  chain.levels.resize(3);
  chain.levels[0].mesh = makeIcosphere(3, 1.0f);
  chain.levels[1].mesh = makeIcosphere(1, 1.0f);
  chain.levels[1].cell_width = 0.05f;
  chain.levels[2].mesh = makeIcosphere(0, 1.0f);
  chain.levels[2].cell_width = 0.1f;
  PoppingParams p;
  p.pixels_per_cell = 2.0f;
  std::vector<PoppingTransition> out;
  ASSERT_TRUE(measurePopping(chain, p, out).ok());
  ASSERT_EQ(out.size(), 2u);
  // one pixel = w / X: 2 r X / w pixels across the unit sphere
  EXPECT_EQ(out[0].resolution, 80);
  EXPECT_EQ(out[1].resolution, 40);
  EXPECT_EQ(out[1].from_level, 1u);
  EXPECT_GT(out[0].error.silhouette, 0.0);
  EXPECT_GT(out[1].error.normal_deg, out[0].error.normal_deg);  // the icosahedron's facets are coarser

  // two identical levels do not pop
  chain.levels[2].mesh = chain.levels[1].mesh;
  ASSERT_TRUE(measurePopping(chain, p, out).ok());
  EXPECT_EQ(out[1].error.silhouette, 0.0);
}

TEST(ImageError, BadInputGivesClearErrors) {
  const Mesh m = makeBox(glm::vec3(0.0f), glm::vec3(1.0f));
  ImageErrorResult r;
  ImageErrorParams p;
  p.resolution = 0;
  EXPECT_EQ(measureImageError(m, m, p, r).status, Status::kInvalidArgument);
  EXPECT_EQ(measureImageError(Mesh{}, m, {}, r).status, Status::kInvalidMesh);
  Image img;
  RenderParams rp;
  rp.width = 0;
  EXPECT_EQ(renderMesh(m, rp, img).status, Status::kInvalidArgument);
  EXPECT_EQ(renderMesh(Mesh{}, RenderParams{}, img).status, Status::kInvalidMesh);
  LodChain one;
  one.levels.resize(1);
  one.levels[0].mesh = m;
  std::vector<PoppingTransition> out;
  EXPECT_EQ(measurePopping(one, {}, out).status, Status::kInvalidArgument);
  one.levels.resize(2);
  one.levels[1].mesh = m;  // cell width 0
  const Error e = measurePopping(one, {}, out);
  EXPECT_EQ(e.status, Status::kInvalidArgument);
  EXPECT_NE(e.message.find("level 1"), std::string::npos) << e.message;
}

}  // namespace
}  // namespace scenelod::eval
