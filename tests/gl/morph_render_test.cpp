// Nested clustering chains drawn by the GL renderer: level k at morph factor 1 renders like level
// k + 1 (the same pixels, colour for colour, on most level pairs; at most 0.2 % of the covered
// pixels differ on any), on the Stanford bunny (no normals in the file:
// level 0's are computed at upload) and on the Duck of the shared models with a checker texture on
// its texture coordinates (so that a texture coordinate target other than the one level k + 1 draws
// shows). Skips where EGL cannot start or the model is missing.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "scenelod/gl/renderer.h"
#include "scenelod/lodcore/chain.h"
#include "scenelod/lodcore/obj_io.h"
#include "scenelod/scene/gltf_io.h"

namespace scenelod::gl {
namespace {

constexpr int kSize = 400;

class MorphRenderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    RendererConfig rc;
    rc.width_px = kSize;
    rc.height_px = kSize;
    for (float& c : rc.background) c = 0.0f;
    bool unavailable = false;
    Error e = renderer_.init(rc, &unavailable);
    if (!e.ok() && unavailable) GTEST_SKIP() << "EGL cannot start here: " << e.message;
    ASSERT_TRUE(e.ok()) << e.message;
  }

  // the camera looking at the chain's level 0 from direction `dir`, the model filling most of the view
  void frame(const LodChain& chain, const glm::vec3& dir) {
    const Sphere s = chain.levels[0].bounds;
    cam_ = selection::Camera();
    cam_.viewport_width_px = cam_.viewport_height_px = kSize;
    cam_.fov_y_rad = 0.6f;
    cam_.target = s.center;
    cam_.eye = s.center + glm::normalize(dir) * (s.radius / std::tan(0.5f * cam_.fov_y_rad));
    cam_.near_plane = 0.05f * s.radius;
    cam_.far_plane = 10.0f * s.radius;
  }

  void draw(int8_t level, float factor, eval::Image& img) {
    FrameInput in;
    const glm::mat4 world(1.0f);
    const uint32_t chain = 0;
    in.camera = &cam_;
    in.object_world = {&world, 1};
    in.object_chain = {&chain, 1};
    in.levels = {&level, 1};
    in.morph = {&factor, 1};
    ASSERT_TRUE(renderer_.drawFrame(in, nullptr));
    ASSERT_TRUE(renderer_.readPixels(img).ok());
  }

  // every level k < last at factor 1 against level k + 1, from three directions: the pixels that
  // differ at all (any channel) must be none; also checks that the morph is not trivially exact
  // (level k at factor 0 differs from level k + 1)
  void expectFactorOneIsNextLevel(const LodChain& chain, const std::string& what) {
    ASSERT_GE(chain.levelCount(), 3u) << what;
    size_t compared_pairs = 0, collapsed_pairs = 0, exact_pairs = 0;
    for (const glm::vec3& dir : {glm::vec3(0.3f, 0.2f, 1.0f), glm::vec3(-1.0f, 0.4f, 0.1f), glm::vec3(0.2f, -0.3f, -1.0f)}) {
      frame(chain, dir);
      for (size_t k = 0; k + 1 < chain.levelCount(); ++k) {
        ASSERT_FALSE(chain.levels[k].morph.empty()) << what << " level " << k;
        const Mesh& a = chain.levels[k].mesh;
        const Mesh& b = chain.levels[k + 1].mesh;
        if (b.edgeCount() + b.pointCount() > a.edgeCount() + a.pointCount()) {
          ++collapsed_pairs;  // triangles that collapse into thick edges or points: no morph draws those
          continue;
        }
        ++compared_pairs;
        eval::Image own, morphed, next;
        draw(static_cast<int8_t>(k), 0.0f, own);
        draw(static_cast<int8_t>(k), 1.0f, morphed);
        draw(static_cast<int8_t>(k + 1), 0.0f, next);
        ASSERT_EQ(morphed.rgb.size(), next.rgb.size());
        size_t covered = 0, differ = 0, differ_own = 0, differ2 = 0, differ16 = 0;
        for (size_t i = 0; i + 2 < next.rgb.size(); i += 3) {
          const bool bg = next.rgb[i] == background_[0] && next.rgb[i + 1] == background_[1] && next.rgb[i + 2] == background_[2];
          covered += !bg;
          bool d = false, d_own = false;
          int md = 0;
          for (int c = 0; c < 3; ++c) {
            md = std::max(md, std::abs(int(morphed.rgb[i + c]) - int(next.rgb[i + c])));
            d = d || morphed.rgb[i + c] != next.rgb[i + c];
            d_own = d_own || own.rgb[i + c] != next.rgb[i + c];
          }
          differ += d;
          differ2 += md > 2;
          differ16 += md > 16;
          differ_own += d_own;
        }
        EXPECT_GT(covered, size_t(kSize * kSize / 20)) << what << " level " << k;
        EXPECT_GT(differ_own, 0u) << what << " level " << k << ": level " << k << " unmorphed already looks like level " << k + 1;
        // (exact on most pairs; a few pixels where coinciding surfaces tie in depth or a triangle
        // matches the next level's reversed)
        EXPECT_LE(differ, covered / 500) << what << " level " << k << " at factor 1 against level " << k + 1 << ": " << differ
                                         << " of " << covered << " covered pixels differ (" << differ2 << " by > 2, "
                                         << differ16 << " by > 16)";
        exact_pairs += differ == 0;
      }
    }
    // most pairs are compared; the ones left out are the last few, where parts end as edges or points
    EXPECT_GE(compared_pairs, 3 * (chain.levelCount() - 3)) << what;
    EXPECT_GE(2 * exact_pairs, compared_pairs) << what;
    std::printf("%s: %zu level pairs x views compared, %zu pixel-exact, %zu left out (thick edges or points appear)\n",
                what.c_str(), compared_pairs, exact_pairs, collapsed_pairs);
  }

  Renderer renderer_;
  selection::Camera cam_;
  const uint8_t background_[3] = {0, 0, 0};
};

TEST_F(MorphRenderTest, NestedBunnyAtFactorOneRendersAsTheNextLevel) {
  Mesh bunny;
  const Error e = readObj(SCENELOD_BUNNY_PATH, bunny);
  if (!e.ok()) GTEST_SKIP() << "no bunny: " << e.message;
  ChainParams cp;
  cp.nested = true;
  LodChain chain;
  ASSERT_TRUE(buildChain(bunny, cp, chain).ok());
  ASSERT_TRUE(renderer_.uploadChains({chain}).ok());
  expectFactorOneIsNextLevel(chain, "bunny");
}

TEST_F(MorphRenderTest, NestedTexturedDuckAtFactorOneRendersAsTheNextLevel) {
  scene::SceneData duck;
  const Error e = scene::importGltf(std::string(SCENELOD_SHARED_MODELS_DIR) + "/Duck/Duck.glb", duck);
  if (!e.ok()) GTEST_SKIP() << "no Duck: " << e.message;
  ASSERT_FALSE(duck.meshes.empty());
  const Mesh& m = duck.meshes[0].mesh;
  ASSERT_FALSE(m.uvs.empty());
  ChainParams cp;
  cp.nested = true;
  cp.level_count = 5;
  LodChain chain;
  ASSERT_TRUE(buildChain(m, cp, chain).ok());
  ASSERT_FALSE(chain.levels[1].mesh.uvs.empty());
  // a 64 x 64 checker of 8 x 8 texels: texture coordinates that differ show in the colour
  std::vector<uint8_t> texels(64 * 64 * 4);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      uint8_t* t = &texels[4 * (y * 64 + x)];
      const bool odd = ((x / 8) + (y / 8)) % 2;
      t[0] = odd ? 230 : 40;
      t[1] = odd ? 200 : 90;
      t[2] = odd ? 60 : 210;
      t[3] = 255;
    }
  MaterialDesc mat;
  mat.rgba8 = texels.data();
  mat.width = mat.height = 64;
  ASSERT_TRUE(renderer_.uploadMaterials({&mat, 1}).ok());
  std::vector<int32_t> groups(m.triangle_groups.empty() ? 1 : 1 + *std::max_element(m.triangle_groups.begin(), m.triangle_groups.end()), 0);
  ASSERT_TRUE(renderer_.uploadChains({chain}, {groups}).ok());
  expectFactorOneIsNextLevel(chain, "Duck");
}

}  // namespace
}  // namespace scenelod::gl
