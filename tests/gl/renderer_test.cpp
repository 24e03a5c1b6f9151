// The GL renderer draws what it is given at the right size: thick edges are as wide as their
// thickness in world units (Low & Tan 1997 §3.3 quads), hairlines at least one pixel, level -1 draws
// nothing, and the frame result counts what was drawn. Skips where EGL cannot start.
#include <cstdlib>

#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include "scenelod/gl/renderer.h"

namespace scenelod::gl {
namespace {

LodChain edgeChain(float thickness) {
  LodChain c;
  LodLevel l;
  l.mesh.positions = {{-0.5f, 0.0f, 0.0f}, {0.5f, 0.0f, 0.0f}};
  l.mesh.edges = {0, 1};
  l.mesh.edge_thickness = {thickness};
  c.levels.push_back(l);
  return c;
}

// pixels in column x that differ from the background
int coveredInColumn(const eval::Image& img, int x) {
  int n = 0;
  const uint8_t* bg = img.pixel(0, 0);
  for (int y = 0; y < img.height; ++y) {
    const uint8_t* p = img.pixel(x, y);
    if (std::abs(p[0] - bg[0]) + std::abs(p[1] - bg[1]) + std::abs(p[2] - bg[2]) > 6) ++n;
  }
  return n;
}

class RendererTest : public ::testing::Test {
 protected:
  void SetUp() override {
    RendererConfig rc;
    rc.width_px = 200;
    rc.height_px = 200;
    bool unavailable = false;
    Error e = renderer_.init(rc, &unavailable);
    if (!e.ok() && unavailable) GTEST_SKIP() << "EGL cannot start here: " << e.message;
    ASSERT_TRUE(e.ok()) << e.message;
    // orthographic, 2 world units over 200 pixels: 100 pixels per unit
    cam_.projection = selection::Projection::kOrthographic;
    cam_.ortho_height = 2.0f;
    cam_.eye = {0.0f, 0.0f, 5.0f};
    cam_.near_plane = 0.1f;
    cam_.far_plane = 100.0f;
    cam_.viewport_width_px = 200;
    cam_.viewport_height_px = 200;
  }

  FrameResult draw(int8_t level, eval::Image& img) {
    FrameInput in;
    in.camera = &cam_;
    in.object_world = {&world_, 1};
    in.object_chain = {&chain_, 1};
    in.levels = {&level, 1};
    FrameResult r;
    EXPECT_TRUE(renderer_.drawFrame(in, &r));
    Error e = renderer_.readPixels(img);
    EXPECT_TRUE(e.ok()) << e.message;
    return r;
  }

  Renderer renderer_;
  selection::Camera cam_;
  glm::mat4 world_{1.0f};
  uint32_t chain_ = 0;
};

TEST_F(RendererTest, ThickEdgeIsAsWideAsItsThickness) {
  ASSERT_TRUE(renderer_.uploadChains({edgeChain(0.1f), edgeChain(0.0f)}).ok());
  eval::Image img;
  FrameResult r = draw(0, img);
  EXPECT_EQ(r.edges, 1u);
  EXPECT_EQ(r.triangles, 0u);
  EXPECT_EQ(r.draw_calls, 1u);
  EXPECT_GE(r.measured_ms, 0.0);
  const int covered = coveredInColumn(img, 100);
  EXPECT_GE(covered, 9);   // 0.1 units = 10 pixels
  EXPECT_LE(covered, 11);
  EXPECT_EQ(coveredInColumn(img, 20), 0);  // beyond the edge's end at x = 50
  // scaled by 2 under the world matrix: twice as wide
  world_ = glm::scale(glm::mat4(1.0f), glm::vec3(2.0f));
  draw(0, img);
  EXPECT_GE(coveredInColumn(img, 100), 19);
  EXPECT_LE(coveredInColumn(img, 100), 21);
}

TEST_F(RendererTest, HairlineIsAtLeastOnePixelAndLevelMinusOneDrawsNothing) {
  ASSERT_TRUE(renderer_.uploadChains({edgeChain(0.0f)}).ok());
  eval::Image img;
  draw(0, img);
  const int covered = coveredInColumn(img, 100);
  EXPECT_GE(covered, 1);
  EXPECT_LE(covered, 2);
  FrameResult r = draw(-1, img);
  EXPECT_EQ(r.draw_calls, 0u);
  EXPECT_EQ(coveredInColumn(img, 100), 0);
}

TEST_F(RendererTest, RejectsBadLevelsAndInputs) {
  LodChain bad = edgeChain(0.1f);
  bad.levels[0].mesh.edges = {0, 7};  // index out of range
  Error e = renderer_.uploadChains({bad});
  EXPECT_FALSE(e.ok());
  EXPECT_NE(e.message.find("chain 0 level 0"), std::string::npos) << e.message;
  FrameInput in;  // no camera
  FrameResult r;
  EXPECT_FALSE(renderer_.drawFrame(in, &r));
}

LodChain quadChain(float half, float z) {
  LodChain c;
  LodLevel l;
  l.mesh.positions = {{-half, -half, z}, {half, -half, z}, {half, half, z}, {-half, half, z}};
  l.mesh.normals.assign(4, glm::vec3(0.0f, 0.0f, 1.0f));
  l.mesh.triangles = {0, 1, 2, 0, 2, 3};
  c.levels.push_back(l);
  return c;
}

int brightness(const eval::Image& img, int x, int y) {
  const uint8_t* p = img.pixel(x, y);
  return p[0] + p[1] + p[2];
}

// a floor 2 x 2 at z = 0 and a card 0.5 x 0.5 at z = 1 over its middle, seen from above; a light
// tilted toward +x throws the card's shadow 0.6 units toward -x: the floor there is darker than at
// the mirrored point, unless the card casts no shadow (its shadow level -1)
TEST_F(RendererTest, ShadowPassDarkensTheFloorBehindTheCasterOnly) {
  ASSERT_TRUE(renderer_.uploadChains({quadChain(1.0f, 0.0f), quadChain(0.25f, 1.0f)}).ok());
  const glm::mat4 world[2] = {glm::mat4(1.0f), glm::mat4(1.0f)};
  const uint32_t chains[2] = {0, 1};
  const int8_t levels[2] = {0, 0};
  selection::Camera light;
  light.projection = selection::Projection::kOrthographic;
  light.eye = {3.0f, 0.0f, 5.0f};
  light.target = {0.0f, 0.0f, 0.0f};
  light.ortho_height = 4.0f;
  light.near_plane = 0.1f;
  light.far_plane = 20.0f;
  light.viewport_width_px = light.viewport_height_px = 512;
  FrameInput in;
  in.camera = &cam_;
  in.object_world = {world, 2};
  in.object_chain = {chains, 2};
  in.levels = {levels, 2};
  in.shadow_camera = &light;
  auto frame = [&](const int8_t* shadow_levels, eval::Image& img) {
    in.shadow_levels = {shadow_levels, 2};
    FrameResult r;
    EXPECT_TRUE(renderer_.drawFrame(in, &r));
    EXPECT_TRUE(renderer_.readPixels(img).ok());
    return r;
  };
  // pixel (100 + 100 x, 100) is the floor at (x, 0) (image rows top to bottom, y = 0 in the middle)
  eval::Image img;
  const int8_t casting[2] = {0, 0};
  const FrameResult r = frame(casting, img);
  EXPECT_EQ(r.shadow_triangles, 4u);
  EXPECT_EQ(r.triangles, 4u);
  const int shadowed = brightness(img, 40, 100), lit = brightness(img, 160, 100);
  EXPECT_LT(shadowed, lit * 3 / 4) << "shadowed " << shadowed << ", lit " << lit;
  EXPECT_GT(shadowed, 0);  // ambient and headlight remain
  const int8_t floor_only[2] = {0, -1};
  frame(floor_only, img);
  EXPECT_NEAR(brightness(img, 40, 100), brightness(img, 160, 100), 3);
  EXPECT_NEAR(brightness(img, 160, 100), lit, 3);
  // a perspective light is refused
  light.projection = selection::Projection::kPerspective;
  in.shadow_levels = {casting, 2};
  FrameResult bad;
  EXPECT_FALSE(renderer_.drawFrame(in, &bad));
}

// two quads side by side in two groups: the left one textured (a 2 x 1 texture, red then green,
// across its u), the right one a blue material without texture; each pixel shows its material
TEST_F(RendererTest, GroupsAreDrawnWithTheirMaterialsAndTextures) {
  LodChain c;
  LodLevel l;
  Mesh& m = l.mesh;
  m.positions = {{-1, -1, 0}, {0, -1, 0}, {0, 1, 0}, {-1, 1, 0}, {0, -1, 0}, {1, -1, 0}, {1, 1, 0}, {0, 1, 0}};
  m.normals.assign(8, glm::vec3(0, 0, 1));
  m.uvs = {{0, 1}, {1, 1}, {1, 0}, {0, 0}, {0, 1}, {1, 1}, {1, 0}, {0, 0}};
  m.triangles = {4, 5, 6, 0, 1, 2, 4, 6, 7, 0, 2, 3};  // groups interleaved
  m.triangle_groups = {1, 0, 1, 0};
  c.levels.push_back(l);
  const uint8_t texels[8] = {255, 0, 0, 255, 0, 255, 0, 255};
  MaterialDesc mats[2];
  mats[0].rgba8 = texels;
  mats[0].width = 2;
  mats[0].height = 1;
  mats[0].wrap_s = mats[0].wrap_t = 33071;  // CLAMP_TO_EDGE
  mats[1].base_color[0] = mats[1].base_color[1] = 0.0f;
  ASSERT_TRUE(renderer_.uploadMaterials({mats, 2}).ok());
  ASSERT_TRUE(renderer_.uploadChains({c}, {{0, 1}}).ok());
  eval::Image img;
  const FrameResult r = draw(0, img);
  EXPECT_EQ(r.triangles, 4u);
  EXPECT_EQ(r.draw_calls, 2u);  // one per group
  const uint8_t* red = img.pixel(20, 100);
  const uint8_t* green = img.pixel(80, 100);
  const uint8_t* blue = img.pixel(150, 100);
  EXPECT_GT(red[0], 200);
  EXPECT_LT(red[1], 40);
  EXPECT_GT(green[1], 200);
  EXPECT_LT(green[0], 40);
  EXPECT_GT(blue[2], 200);
  EXPECT_LT(blue[0] + blue[1], 20);
  // a group material past the uploaded ones is refused naming the chain
  const Error e = renderer_.uploadChains({c}, {{0, 2}});
  EXPECT_FALSE(e.ok());
  EXPECT_NE(e.message.find("chain 0: material 2 but 2 were uploaded"), std::string::npos) << e.message;
}

}  // namespace
}  // namespace scenelod::gl
