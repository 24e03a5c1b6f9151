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

}  // namespace
}  // namespace scenelod::gl
