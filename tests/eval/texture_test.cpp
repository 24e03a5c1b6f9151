// Textured renders and the textured image error: a quad filling the view, a checker made in code.
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "scenelod/eval/material.h"
#include "scenelod/eval/render.h"

namespace scenelod::eval {
namespace {

constexpr float kHalfPi = 1.57079632679f;

// n x n blocks of `block` texels each, black where (bx + by) is even, `light` elsewhere
Texture makeChecker(int n, int block, uint8_t light = 255) {
  Texture t;
  t.width = t.height = n * block;
  for (int y = 0; y < t.height; ++y)
    for (int x = 0; x < t.width; ++x) {
      const uint8_t v = ((x / block + y / block) % 2) ? light : 0;
      t.rgba8.insert(t.rgba8.end(), {v, v, v, 255});
    }
  return t;
}

// the square [-1, 1]^2 at z = 0 facing +z, uv (0, 0) at its top-left corner (-1, 1), (1, 1) at (1, -1)
Mesh makeQuad(float uv_scale = 1.0f) {
  Mesh m;
  m.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
  m.uvs = {{0, uv_scale}, {uv_scale, uv_scale}, {uv_scale, 0}, {0, 0}};
  m.triangles = {0, 1, 2, 0, 2, 3};
  return m;
}

// the quad seen head-on from +z, filling the picture: image x follows +x, image y follows -y
Image renderQuad(const Mesh& quad, const std::vector<Material>& materials, int size = 64) {
  RenderParams p;
  p.width = p.height = size;
  p.view = standardView(4);
  p.frame = Sphere{glm::vec3(0.0f), 1.0f};
  p.materials = materials;
  Image img;
  EXPECT_TRUE(renderMesh(quad, p, img).ok());
  return img;
}

// the grey level at the centre of cell (cx, cy) of a cells x cells grid over the picture
int cellValue(const Image& img, int cells, int cx, int cy) {
  const int x = (2 * cx + 1) * img.width / (2 * cells), y = (2 * cy + 1) * img.height / (2 * cells);
  return img.pixel(x, y)[0];
}

TEST(Texture, WrapModesRepeatClampAndMirror) {
  // 4 x 1 texels: 0, 80, 160, 240; sampled at texel centres, bilinear gives them exactly
  Texture t;
  t.width = 4;
  t.height = 1;
  for (uint8_t v : {0, 80, 160, 240}) t.rgba8.insert(t.rgba8.end(), {v, v, v, 255});
  auto at = [&](float u, Wrap w) { return sampleTexture(t, {u, 0.5f}, w, Wrap::kRepeat); };
  auto texel = [&](int i) { return sampleTexture(t, {(i + 0.5f) / 4.0f, 0.5f}, Wrap::kRepeat, Wrap::kRepeat); };
  EXPECT_NEAR(texel(1).r, std::pow((80 / 255.0f + 0.055f) / 1.055f, 2.4f), 1e-6f);  // sRGB made linear
  EXPECT_EQ(at(1.125f, Wrap::kRepeat), texel(0));
  EXPECT_EQ(at(-0.875f, Wrap::kRepeat), texel(0));
  EXPECT_EQ(at(1.125f, Wrap::kClampToEdge), texel(3));
  EXPECT_EQ(at(-7.0f, Wrap::kClampToEdge), texel(0));
  EXPECT_EQ(at(1.125f, Wrap::kMirroredRepeat), texel(3));  // just past the edge: the mirror image
  EXPECT_EQ(at(1.875f, Wrap::kMirroredRepeat), texel(0));
  EXPECT_EQ(at(2.125f, Wrap::kMirroredRepeat), texel(0));  // a whole mirrored period later
  EXPECT_EQ(at(1e9f + 0.125f, Wrap::kClampToEdge), texel(3));  // far away: no overflow
  const glm::vec4 far = at(-3e9f, Wrap::kRepeat);
  EXPECT_TRUE(std::isfinite(far.r));
  // halfway between texel centres 0 and 1: the mean of the linear values
  EXPECT_NEAR(at(0.25f, Wrap::kRepeat).r, 0.5f * (texel(0).r + texel(1).r), 1e-6f);
  EXPECT_EQ(wrapFromGl(33071), Wrap::kClampToEdge);
  EXPECT_EQ(wrapFromGl(33648), Wrap::kMirroredRepeat);
  EXPECT_EQ(wrapFromGl(10497), Wrap::kRepeat);
  EXPECT_EQ(wrapFromGl(0), Wrap::kRepeat);
}

TEST(Texture, TransformFollowsTheExtensionsExample) {
  // KHR_texture_transform's example: offset (0, 1), rotation 90 degrees, scale 0.5 shows the
  // image's lower-left quadrant (u in [0, 0.5], v in [0.5, 1]), turned clockwise
  const glm::mat3 m = textureTransform({0.0f, 1.0f}, kHalfPi, {0.5f, 0.5f});
  auto apply = [&](glm::vec2 uv) { return glm::vec2(m * glm::vec3(uv, 1.0f)); };
  const glm::vec2 corners[4] = {apply({0, 0}), apply({1, 0}), apply({1, 1}), apply({0, 1})};
  const glm::vec2 want[4] = {{0.0f, 1.0f}, {0.0f, 0.5f}, {0.5f, 0.5f}, {0.5f, 1.0f}};
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(corners[i].x, want[i].x, 1e-6f) << i;
    EXPECT_NEAR(corners[i].y, want[i].y, 1e-6f) << i;
  }
  const glm::mat3 id = textureTransform({0.0f, 0.0f}, 0.0f, {1.0f, 1.0f});
  EXPECT_EQ(id, glm::mat3(1.0f));
}

TEST(TexturedRender, QuadShowsTheChecker) {
  const Texture checker = makeChecker(4, 8);
  std::vector<Material> mats(1);
  mats[0].texture = &checker;
  const Image img = renderQuad(makeQuad(), mats);
  for (int cy = 0; cy < 4; ++cy)
    for (int cx = 0; cx < 4; ++cx) EXPECT_EQ(cellValue(img, 4, cx, cy), (cx + cy) % 2 ? 255 : 0) << cx << " " << cy;
}

TEST(TexturedRender, WrapModesAndTransformMoveTheChecker) {
  const Texture checker = makeChecker(2, 8);
  std::vector<Material> mats(1);
  mats[0].texture = &checker;
  // uv 0..2: REPEAT shows the 2 x 2 checker twice per axis
  const Image repeat = renderQuad(makeQuad(2.0f), mats);
  for (int cy = 0; cy < 4; ++cy)
    for (int cx = 0; cx < 4; ++cx) EXPECT_EQ(cellValue(repeat, 4, cx, cy), (cx + cy) % 2 ? 255 : 0);
  // CLAMP_TO_EDGE: beyond 1 the edge texels repeat, so the right half copies the last column
  mats[0].wrap_s = mats[0].wrap_t = Wrap::kClampToEdge;
  const Image clamp = renderQuad(makeQuad(2.0f), mats);
  EXPECT_EQ(cellValue(clamp, 4, 0, 0), 0);
  EXPECT_EQ(cellValue(clamp, 4, 1, 0), 255);
  EXPECT_EQ(cellValue(clamp, 4, 2, 0), 255);
  EXPECT_EQ(cellValue(clamp, 4, 3, 0), 255);
  EXPECT_EQ(cellValue(clamp, 4, 3, 3), 0);
  // MIRRORED_REPEAT: the second copy is the mirror image, so cells 1 and 2 agree
  mats[0].wrap_s = mats[0].wrap_t = Wrap::kMirroredRepeat;
  const Image mirror = renderQuad(makeQuad(2.0f), mats);
  const int row[4] = {0, 255, 255, 0};
  for (int cx = 0; cx < 4; ++cx) EXPECT_EQ(cellValue(mirror, 4, cx, 0), row[cx]) << cx;
  // an offset of half the image (one block) swaps black and white
  mats[0].wrap_s = mats[0].wrap_t = Wrap::kRepeat;
  mats[0].uv_transform = textureTransform({0.5f, 0.0f}, 0.0f, {1.0f, 1.0f});
  const Image shifted = renderQuad(makeQuad(), mats);
  for (int cy = 0; cy < 2; ++cy)
    for (int cx = 0; cx < 2; ++cx) EXPECT_EQ(cellValue(shifted, 2, cx, cy), (cx + cy) % 2 ? 0 : 255);
}

TEST(TexturedRender, TexcoordSetFactorAndColor0) {
  const Texture checker = makeChecker(2, 8);
  Mesh quad = makeQuad();
  quad.extra_uvs = {quad.uvs};
  quad.uvs.assign(4, glm::vec2(0.25f, 0.25f));  // set 0 reads the black block everywhere
  std::vector<Material> mats(1);
  mats[0].texture = &checker;
  mats[0].texcoord = 1;
  const Image set1 = renderQuad(quad, mats);
  EXPECT_EQ(cellValue(set1, 2, 1, 0), 255);
  EXPECT_EQ(cellValue(set1, 2, 0, 0), 0);
  mats[0].texcoord = 0;
  EXPECT_EQ(cellValue(renderQuad(quad, mats), 2, 1, 0), 0);
  // factor (1, 1, 0) x COLOR_0 (1, 0, 1) x a white texel = red
  mats[0].texcoord = 1;
  quad.colors.assign(4, glm::vec3(1.0f, 0.0f, 1.0f));
  mats[0].base_color = glm::vec4(1.0f, 1.0f, 0.0f, 1.0f);
  const Image tinted = renderQuad(quad, mats);
  const uint8_t* p = tinted.pixel(48, 16);  // the white block at the top right
  EXPECT_EQ(p[0], 255);
  EXPECT_EQ(p[1], 0);
  EXPECT_EQ(p[2], 0);
}

TEST(TexturedRender, MissingMaterialIsWhiteAndMissingUvsShowTheMean) {
  const Texture checker = makeChecker(2, 8);
  std::vector<Material> mats(1);
  mats[0].texture = &checker;
  Mesh quad = makeQuad();
  quad.triangle_groups = {0xffffffffu, 0xffffffffu};  // kNoMaterial
  EXPECT_EQ(cellValue(renderQuad(quad, mats), 2, 0, 0), 255);
  quad.triangle_groups.clear();
  quad.uvs.clear();
  // half the texels black, half white: the linear mean 0.5 is sRGB 188
  const Image mean = renderQuad(quad, mats);
  EXPECT_EQ(cellValue(mean, 2, 0, 0), 188);
  EXPECT_EQ(cellValue(mean, 2, 1, 1), 188);
  // without materials the renderer draws as before: grey triangles
  const Image grey = renderQuad(makeQuad(), {});
  EXPECT_EQ(grey.pixel(32, 32)[0], grey.pixel(10, 50)[0]);
  EXPECT_NE(grey.pixel(32, 32)[0], 0);
}

// A checker of single texels, about 5 texels to a pixel: drawn through the mip levels it is the even
// grey a GPU shows (linear mean 0.5, sRGB 188), not an aliased pattern of black and white pixels.
TEST(TexturedRender, MinifiedTexturesAreFilteredLikeMipmaps) {
  const Texture fine = makeChecker(256, 1);
  std::vector<Material> mats(1);
  mats[0].texture = &fine;
  const Image img = renderQuad(makeQuad(), mats, 50);
  int lo = 255, hi = 0;
  for (int y = 4; y < 46; ++y)
    for (int x = 4; x < 46; ++x) lo = std::min<int>(lo, img.pixel(x, y)[0]), hi = std::max<int>(hi, img.pixel(x, y)[0]);
  EXPECT_GE(lo, 186);
  EXPECT_LE(hi, 190);
  // the filter follows the footprint: the same texture over 8 blocks of 32 texels is sharp again
  const Texture coarse = makeChecker(8, 32);
  mats[0].texture = &coarse;
  const Image sharp = renderQuad(makeQuad(), mats, 64);
  EXPECT_EQ(cellValue(sharp, 8, 0, 0), 0);
  EXPECT_EQ(cellValue(sharp, 8, 1, 0), 255);
  // levels of a non-square, non-power-of-two texture end in one texel holding about the mean
  Texture odd = makeChecker(3, 5);
  odd.width = 15;
  odd.height = 15;
  const FilteredTexture chain(odd);
  EXPECT_EQ(chain.levelCount(), 4);  // 15, 7, 3, 1
  const glm::vec4 top = chain.sample({0.5f, 0.5f}, 10.0f, Wrap::kRepeat, Wrap::kRepeat);
  EXPECT_NEAR(top.r, meanTextureColor(odd).r, 0.15f);
}

TEST(TexturedRender, BadTextureIsAnError) {
  Texture broken;
  broken.width = 4;
  broken.height = 4;
  broken.rgba8.assign(10, 0);
  std::vector<Material> mats(1);
  mats[0].texture = &broken;
  RenderParams p;
  p.materials = mats;
  Image img;
  const Error e = renderMesh(makeQuad(), p, img);
  EXPECT_EQ(e.status, Status::kInvalidArgument);
  EXPECT_NE(e.message.find("material 0"), std::string::npos) << e.message;
  ImageErrorParams ip;
  ip.simplified_materials = mats;
  ImageErrorResult r;
  EXPECT_FALSE(measureImageError(makeQuad(), makeQuad(), ip, r).ok());
}

TEST(TexturedImageError, CountsPixelsWhoseTextureMoved) {
  const Texture checker = makeChecker(4, 8);
  std::vector<Material> mats(1);
  mats[0].texture = &checker;
  ImageErrorParams p;
  p.resolution = 64;
  p.original_materials = mats;
  p.simplified_materials = mats;
  ImageErrorResult same;
  ASSERT_TRUE(measureImageError(makeQuad(), makeQuad(), p, same).ok());
  EXPECT_GT(same.both_px, 0u);
  EXPECT_EQ(same.color_off_px, 0u);
  EXPECT_EQ(same.color_mad, 0.0);
  // one block further: every block changes colour, except where the quad is seen edge-on or the
  // view is at a grazing angle and the shading is dark; most pixels hit by both are off
  std::vector<Material> moved = mats;
  moved[0].uv_transform = textureTransform({0.25f, 0.0f}, 0.0f, {1.0f, 1.0f});
  p.simplified_materials = moved;
  ImageErrorResult off;
  ASSERT_TRUE(measureImageError(makeQuad(), makeQuad(), p, off).ok());
  EXPECT_EQ(off.silhouette, 0.0);
  EXPECT_GT(off.color_off, 0.8);
  EXPECT_GT(off.color_mad, 50.0);
  // the same level with its uvs dropped shows the mean grey: off on both black and white blocks
  Mesh no_uv = makeQuad();
  no_uv.uvs.clear();
  p.simplified_materials = mats;
  ImageErrorResult grey;
  ASSERT_TRUE(measureImageError(makeQuad(), no_uv, p, grey).ok());
  EXPECT_GT(grey.color_off, 0.8);
}

}  // namespace
}  // namespace scenelod::eval
