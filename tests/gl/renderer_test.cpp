// The GL renderer draws what it is given at the right size: thick edges are as wide as their
// thickness in world units (Low & Tan 1997 §3.3 quads), hairlines at least one pixel, level -1 draws
// nothing, and the frame result counts what was drawn; geomorphs move a level toward its targets by
// the factor and cross-fades split the pixels between two levels. Skips where EGL cannot start.
#include <cmath>
#include <cstdlib>
#include <limits>

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

// the mean column of the pixels that differ from the background, -1 when none do
double coveredCentreX(const eval::Image& img) {
  double sum = 0.0;
  int n = 0;
  for (int x = 0; x < img.width; ++x) {
    const int c = coveredInColumn(img, x);
    sum += static_cast<double>(c) * x;
    n += c;
  }
  return n ? sum / n : -1.0;
}

// a 0.4 x 0.4 quad at the origin (level 0), red, whose morph targets lie 0.6 units to the right and
// are blue; level 1 is that target quad, with no morph data (the last level)
LodChain morphChain() {
  LodChain c = quadChain(0.2f, 0.0f);
  LodLevel& l0 = c.levels[0];
  l0.mesh.colors.assign(4, glm::vec3(1.0f, 0.0f, 0.0f));
  for (const glm::vec3& p : l0.mesh.positions) l0.morph.positions.push_back(p + glm::vec3(0.6f, 0.0f, 0.0f));
  l0.morph.normals = l0.mesh.normals;
  l0.morph.colors.assign(4, glm::vec3(0.0f, 0.0f, 1.0f));
  LodLevel l1 = c.levels[0];
  l1.mesh.positions = l0.morph.positions;
  l1.mesh.colors = l0.morph.colors;
  l1.morph = LevelMorph{};
  c.levels.push_back(l1);
  return c;
}

class TransitionTest : public RendererTest {
 protected:
  static constexpr float kEmpty = -100.0f;  // as a factor or fade: that span empty
  // draws object 0 of chain 0 with the given transition state
  FrameResult drawTransition(int8_t level, float factor, int8_t previous, float fade, eval::Image& img, bool* ok = nullptr) {
    FrameInput in;
    in.camera = &cam_;
    in.object_world = {&world_, 1};
    in.object_chain = {&chain_, 1};
    in.levels = {&level, 1};
    if (factor != kEmpty) in.morph = {&factor, 1};
    in.previous_levels = {&previous, 1};
    if (fade != kEmpty) in.fade = {&fade, 1};
    FrameResult r;
    const bool drawn = renderer_.drawFrame(in, &r);
    if (ok) *ok = drawn;
    else EXPECT_TRUE(drawn);
    EXPECT_TRUE(renderer_.readPixels(img).ok());
    return r;
  }
};

// pixel column 100 + 100 x is world x; the quad is 40 pixels wide around x = 0, its target 60
// pixels to the right
TEST_F(TransitionTest, MorphMovesTheLevelTowardItsTargetsByTheFactor) {
  ASSERT_TRUE(renderer_.uploadChains({morphChain()}, {{-1}}).ok());  // a white material: vertex colours show
  eval::Image img;
  const FrameResult r = drawTransition(0, 0.0f, -1, 1.0f, img);
  EXPECT_EQ(r.triangles, 2u);
  EXPECT_EQ(r.fading_objects, 0u);
  EXPECT_NEAR(coveredCentreX(img), 99.5, 0.6);
  EXPECT_EQ(coveredInColumn(img, 100), 40);
  const uint8_t* red = img.pixel(100, 100);
  EXPECT_GT(red[0], 240);
  EXPECT_LT(red[2], 10);
  drawTransition(0, 0.5f, -1, 1.0f, img);
  EXPECT_NEAR(coveredCentreX(img), 129.5, 0.6);
  EXPECT_EQ(coveredInColumn(img, 130), 40);
  EXPECT_EQ(coveredInColumn(img, 105), 0);  // the quad moved; nothing left behind
  const uint8_t* purple = img.pixel(130, 100);
  EXPECT_NEAR(purple[0], 128, 3);  // colour mixed halfway
  EXPECT_NEAR(purple[2], 128, 3);
  drawTransition(0, 1.0f, -1, 1.0f, img);
  EXPECT_NEAR(coveredCentreX(img), 159.5, 0.6);
  eval::Image level1;
  drawTransition(1, 0.0f, -1, 1.0f, level1);  // at factor 1, level 0 is drawn exactly as level 1
  ASSERT_EQ(img.rgb.size(), level1.rgb.size());
  EXPECT_TRUE(img.rgb == level1.rgb);
  // no morph span: factor 0
  drawTransition(0, kEmpty, -1, 1.0f, img);
  EXPECT_NEAR(coveredCentreX(img), 99.5, 0.6);
}

// a level without normals (the renderer computes them) morphs its normals toward the normals of
// the next-level vertices at its targets: at factor 1 it is shaded exactly as the next level
TEST_F(TransitionTest, LevelWithoutNormalsMorphsTowardTheNextLevelsNormals) {
  LodChain c;
  LodLevel l0;
  l0.mesh.positions = {{-0.4f, -0.4f, 0.0f}, {0.4f, -0.4f, 0.0f}, {0.4f, 0.4f, 0.0f}, {-0.4f, 0.4f, 0.0f}};
  l0.mesh.triangles = {0, 1, 2, 0, 2, 3};
  LodLevel l1 = l0;
  for (glm::vec3& p : l1.mesh.positions) p.z = 0.6f * p.x;  // tilted: its computed normals lean
  l0.morph.positions = l1.mesh.positions;
  c.levels = {l0, l1};
  ASSERT_TRUE(renderer_.uploadChains({c}).ok());
  eval::Image flat, morphed, next;
  drawTransition(0, 0.0f, -1, 1.0f, flat);
  drawTransition(0, 1.0f, -1, 1.0f, morphed);
  drawTransition(1, 0.0f, -1, 1.0f, next);
  EXPECT_FALSE(flat.rgb == next.rgb);  // the tilt shows in the shading
  EXPECT_TRUE(morphed.rgb == next.rgb);
}

TEST_F(TransitionTest, LevelWithoutMorphDataIgnoresTheFactor) {
  ASSERT_TRUE(renderer_.uploadChains({morphChain()}, {{-1}}).ok());
  eval::Image still, morphed;
  drawTransition(1, 0.0f, -1, 1.0f, still);
  drawTransition(1, 1.0f, -1, 1.0f, morphed);
  EXPECT_NEAR(coveredCentreX(still), 159.5, 0.6);
  EXPECT_TRUE(still.rgb == morphed.rgb);
  // a chain uploaded without any morph data at all (other vertex layout) likewise
  LodChain plain = morphChain();
  plain.levels[0].morph = LevelMorph{};
  ASSERT_TRUE(renderer_.uploadChains({plain}, {{-1}}).ok());
  drawTransition(0, 0.0f, -1, 1.0f, still);
  drawTransition(0, 0.7f, -1, 1.0f, morphed);
  EXPECT_NEAR(coveredCentreX(still), 99.5, 0.6);
  EXPECT_TRUE(still.rgb == morphed.rgb);
}

TEST_F(TransitionTest, EdgesAndPointsMorphTheirEndpoints) {
  LodChain c;
  LodLevel l;
  l.mesh.positions = {{-0.5f, 0.0f, 0.0f}, {0.5f, 0.0f, 0.0f}, {0.0f, -0.5f, 0.0f}};
  l.mesh.edges = {0, 1};
  l.mesh.edge_thickness = {0.1f};
  l.mesh.points = {2};
  for (const glm::vec3& p : l.mesh.positions) l.morph.positions.push_back(p + glm::vec3(0.0f, 0.4f, 0.0f));
  c.levels.push_back(l);
  ASSERT_TRUE(renderer_.uploadChains({c}).ok());
  // rows: image row 100 - 100 y; the edge at y = 0 covers rows 95..104, at y = 0.2 rows 75..84
  auto coveredRows = [](const eval::Image& img, int x, int y0, int y1) {
    const uint8_t* bg = img.pixel(0, 0);
    int n = 0;
    for (int y = y0; y < y1; ++y) {
      const uint8_t* p = img.pixel(x, y);
      if (std::abs(p[0] - bg[0]) + std::abs(p[1] - bg[1]) + std::abs(p[2] - bg[2]) > 6) ++n;
    }
    return n;
  };
  eval::Image img;
  const FrameResult r = drawTransition(0, 0.5f, -1, 1.0f, img);
  EXPECT_EQ(r.edges, 1u);
  EXPECT_EQ(r.points, 1u);
  EXPECT_GE(coveredRows(img, 60, 74, 86), 9);  // the edge at y = 0.2
  EXPECT_EQ(coveredRows(img, 60, 90, 110), 0);
  EXPECT_GE(coveredRows(img, 100, 127, 134), 2);  // the point at y = -0.3 (row 130)
  EXPECT_EQ(coveredRows(img, 100, 145, 155), 0);  // not at y = -0.5
}

// a 1.6 x 1.6 quad: level 0 red, level 1 blue, no morph data; each pixel of the fading object shows
// exactly one of them, in the share the fade gives
TEST_F(TransitionTest, FadeSplitsThePixelsBetweenTheTwoLevels) {
  LodChain c = quadChain(0.8f, 0.0f);
  c.levels[0].mesh.colors.assign(4, glm::vec3(1.0f, 0.0f, 0.0f));
  c.levels.push_back(c.levels[0]);
  c.levels[1].mesh.colors.assign(4, glm::vec3(0.0f, 0.0f, 1.0f));
  ASSERT_TRUE(renderer_.uploadChains({c}, {{-1}}).ok());
  // pixels 40..159 in both directions are inside: count red, blue and other
  struct Count {
    int red = 0, blue = 0, other = 0;
  };
  auto count = [](const eval::Image& img) {
    Count n;
    for (int y = 40; y < 160; ++y)
      for (int x = 40; x < 160; ++x) {
        const uint8_t* p = img.pixel(x, y);
        if (p[0] > 240 && p[1] < 10 && p[2] < 10) ++n.red;
        else if (p[2] > 240 && p[0] < 10 && p[1] < 10) ++n.blue;
        else ++n.other;
      }
    return n;
  };
  const int total = 120 * 120;
  eval::Image img;
  FrameResult r = drawTransition(1, 0.0f, 0, 0.5f, img);
  Count n = count(img);
  EXPECT_EQ(n.other, 0);
  EXPECT_EQ(n.blue, total / 2);  // 8 of every 4 x 4 pixels
  EXPECT_EQ(n.red, total / 2);
  EXPECT_EQ(r.triangles, 4u);  // both levels
  EXPECT_EQ(r.fade_triangles, 2u);
  EXPECT_EQ(r.draw_calls, 2u);
  EXPECT_EQ(r.fade_draw_calls, 1u);
  EXPECT_EQ(r.fading_objects, 1u);
  // no 4 x 4 block is all one level: the pattern is spread, not split in halves
  for (int y = 40; y < 160; y += 4)
    for (int x = 40; x < 160; x += 4) {
      int blue = 0;
      for (int k = 0; k < 16; ++k) blue += img.pixel(x + k % 4, y + k / 4)[2] > 240;
      ASSERT_EQ(blue, 8) << x << ", " << y;
    }
  n = count((drawTransition(1, 0.0f, 0, 0.25f, img), img));
  EXPECT_EQ(n.other, 0);
  EXPECT_EQ(n.blue, total / 4);
  r = drawTransition(1, 0.0f, 0, 0.0f, img);
  n = count(img);
  EXPECT_EQ(n.red, total);  // only the previous level
  EXPECT_EQ(r.triangles, 2u);
  EXPECT_EQ(r.fade_triangles, 2u);
  r = drawTransition(1, 0.0f, 0, 1.0f, img);
  n = count(img);
  EXPECT_EQ(n.blue, total);  // only the new level
  EXPECT_EQ(r.fade_triangles, 0u);
  EXPECT_EQ(r.fading_objects, 0u);
  n = count((drawTransition(1, 0.0f, 0, kEmpty, img), img));  // no fade span: the new level
  EXPECT_EQ(n.blue, total);
  // appearing (no previous level): the new level on its share, the background elsewhere
  r = drawTransition(1, 0.0f, -1, 0.5f, img);
  n = count(img);
  EXPECT_EQ(n.blue, total / 2);
  EXPECT_EQ(n.red, 0);
  EXPECT_EQ(r.triangles, 2u);
  EXPECT_EQ(r.fading_objects, 1u);
  // leaving (new level -1): the previous level on the complement
  n = count((drawTransition(-1, 0.0f, 0, 0.25f, img), img));
  EXPECT_EQ(n.red, total * 3 / 4);
  EXPECT_EQ(n.blue, 0);
}

TEST_F(TransitionTest, RefusesBadFactorsFadesAndSpanSizes) {
  ASSERT_TRUE(renderer_.uploadChains({morphChain()}).ok());
  eval::Image img;
  bool ok = true;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (float bad : {-0.01f, 1.01f, nan, std::numeric_limits<float>::infinity()}) {
    drawTransition(0, bad, -1, 1.0f, img, &ok);
    EXPECT_FALSE(ok) << "morph " << bad;
    drawTransition(1, 0.0f, 0, bad, img, &ok);
    EXPECT_FALSE(ok) << "fade " << bad;
  }
  drawTransition(0, 1.0f, 1, 0.0f, img, &ok);  // the bounds themselves are fine
  EXPECT_TRUE(ok);
  // spans of the wrong length
  const int8_t levels[2] = {0, 0};
  const uint32_t chains[2] = {0, 0};
  const glm::mat4 world[2] = {glm::mat4(1.0f), glm::mat4(1.0f)};
  const float factors[3] = {0.0f, 0.0f, 0.0f};
  const int8_t previous[3] = {-1, -1, -1};
  FrameInput in;
  in.camera = &cam_;
  in.object_world = {world, 2};
  in.object_chain = {chains, 2};
  in.levels = {levels, 2};
  FrameResult r;
  EXPECT_TRUE(renderer_.drawFrame(in, &r));
  in.morph = {factors, 1};
  EXPECT_FALSE(renderer_.drawFrame(in, &r));
  in.morph = {factors, 2};
  EXPECT_TRUE(renderer_.drawFrame(in, &r));
  in.previous_levels = {previous, 3};
  EXPECT_FALSE(renderer_.drawFrame(in, &r));
  in.previous_levels = {previous, 2};
  in.fade = {factors, 3};
  EXPECT_FALSE(renderer_.drawFrame(in, &r));
  in.fade = {factors, 2};
  EXPECT_TRUE(renderer_.drawFrame(in, &r));
  // morph targets that are not one per vertex are refused at upload, naming the level
  LodChain bad = morphChain();
  bad.levels[0].morph.normals.pop_back();
  const Error e = renderer_.uploadChains({bad});
  EXPECT_FALSE(e.ok());
  EXPECT_NE(e.message.find("chain 0 level 0: 3 morph target normals for 4 vertices"), std::string::npos) << e.message;
}

// the shadow pass draws the shadow level morphed like the camera's when they are the same level:
// a caster morphed 0.6 to the right moves its shadow with it
TEST_F(TransitionTest, ShadowFollowsTheMorph) {
  LodChain floor = quadChain(1.0f, 0.0f);
  LodChain card = quadChain(0.15f, 1.0f);
  for (const glm::vec3& p : card.levels[0].mesh.positions) card.levels[0].morph.positions.push_back(p + glm::vec3(0.6f, 0.0f, 0.0f));
  ASSERT_TRUE(renderer_.uploadChains({floor, card}).ok());
  const glm::mat4 world[2] = {glm::mat4(1.0f), glm::mat4(1.0f)};
  const uint32_t chains[2] = {0, 1};
  const int8_t levels[2] = {0, 0};
  selection::Camera light;
  light.projection = selection::Projection::kOrthographic;
  light.eye = {0.0f, 0.0f, 5.0f};  // straight above: the shadow lies under the card
  light.up = {0.0f, 1.0f, 0.0f};
  light.target = {0.0f, 0.0f, 0.0f};
  light.ortho_height = 4.0f;
  light.near_plane = 0.1f;
  light.far_plane = 20.0f;
  cam_.eye = {0.0f, -3.0f, 5.0f};  // tilted, so the card does not hide its own shadow
  cam_.ortho_height = 3.0f;
  FrameInput in;
  in.camera = &cam_;
  in.object_world = {world, 2};
  in.object_chain = {chains, 2};
  in.levels = {levels, 2};
  in.shadow_camera = &light;
  in.shadow_levels = {levels, 2};
  // the mean column of the pixels the card's shadow darkens (against the frame where it casts none)
  auto shadowCentreX = [&](float factor) {
    const float factors[2] = {0.0f, factor};
    in.morph = {factors, 2};
    FrameResult r;
    eval::Image lit, shadowed;
    const int8_t no_card[2] = {0, -1};
    in.shadow_levels = {no_card, 2};
    EXPECT_TRUE(renderer_.drawFrame(in, &r));
    EXPECT_TRUE(renderer_.readPixels(lit).ok());
    in.shadow_levels = {levels, 2};
    EXPECT_TRUE(renderer_.drawFrame(in, &r));
    EXPECT_EQ(r.shadow_triangles, 4u);
    EXPECT_TRUE(renderer_.readPixels(shadowed).ok());
    double sum = 0.0;
    int n = 0;
    for (int y = 0; y < lit.height; ++y)
      for (int x = 0; x < lit.width; ++x)
        if (brightness(lit, x, y) - brightness(shadowed, x, y) > 60) {
          sum += x;
          ++n;
        }
    EXPECT_GT(n, 200) << "factor " << factor;
    return n ? sum / n : -1.0;
  };
  const double still = shadowCentreX(0.0f), moved = shadowCentreX(1.0f);
  EXPECT_NEAR(still, 100.0, 3.0);
  // orthographic camera 3 units over 200 pixels: 0.6 units = 40 pixels
  EXPECT_NEAR(moved - still, 40.0, 3.0);
}

}  // namespace
}  // namespace scenelod::gl
