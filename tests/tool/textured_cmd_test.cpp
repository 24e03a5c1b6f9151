// `scenelod render` and `scenelod eval --image` on a textured glTF made in the test: a quad with a
// checker texture, moved by KHR_texture_transform or read through TEXCOORD_1, end to end through
// the importer, the material conversion and the renderer.
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <stb/stb_image_write.h>

#include "tool_runner.h"

namespace {

using scenelod::test::runTool;
using scenelod::test::ToolRun;

std::string base64(const std::vector<uint8_t>& in) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < in.size(); i += 3) {
    const uint32_t n = (uint32_t(in[i]) << 16) | (i + 1 < in.size() ? uint32_t(in[i + 1]) << 8 : 0) |
                       (i + 2 < in.size() ? uint32_t(in[i + 2]) : 0);
    out += k[(n >> 18) & 63];
    out += k[(n >> 12) & 63];
    out += i + 1 < in.size() ? k[(n >> 6) & 63] : '=';
    out += i + 2 < in.size() ? k[n & 63] : '=';
  }
  return out;
}

// a 4 x 4 block checker of 8-texel blocks, black and white, as PNG bytes
std::vector<uint8_t> checkerPng() {
  std::vector<uint8_t> px;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      const uint8_t v = ((x / 8 + y / 8) % 2) ? 255 : 0;
      px.insert(px.end(), {v, v, v, 255});
    }
  std::vector<uint8_t> png;
  stbi_write_png_to_func([](void* ctx, void* data, int size) {
    auto* out = static_cast<std::vector<uint8_t>*>(ctx);
    out->insert(out->end(), static_cast<uint8_t*>(data), static_cast<uint8_t*>(data) + size);
  }, &png, 32, 32, 4, px.data(), 32 * 4);
  return png;
}

// The quad [-1, 1]^2 facing +z; TEXCOORD_0 spans the texture, TEXCOORD_1 is all (0.1, 0.1) (a black
// block) unless `swap_sets`, which exchanges them. `texture_info` is the material's
// baseColorTexture JSON after "index": 0.
std::string writeQuadGltf(const std::string& name, const std::string& texture_info, bool swap_sets = false) {
  std::vector<float> data = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0,  // positions
                             0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};    // normals
  const std::vector<float> full = {0, 1, 1, 1, 1, 0, 0, 0}, flat = {0.1f, 0.1f, 0.1f, 0.1f, 0.1f, 0.1f, 0.1f, 0.1f};
  for (float f : swap_sets ? flat : full) data.push_back(f);
  for (float f : swap_sets ? full : flat) data.push_back(f);
  std::vector<uint8_t> bytes(data.size() * 4);
  std::memcpy(bytes.data(), data.data(), bytes.size());
  for (uint16_t i : {0, 1, 2, 0, 2, 3}) bytes.insert(bytes.end(), {uint8_t(i), 0});
  const std::string json = R"({"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_texture_transform"],
 "scenes": [{"nodes": [0]}], "scene": 0, "nodes": [{"mesh": 0}],
 "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2, "TEXCOORD_1": 3},
   "indices": 4, "material": 0}]}],
 "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0)" + texture_info + R"(}}}],
 "textures": [{"source": 0, "sampler": 0}], "samplers": [{"wrapS": 10497, "wrapT": 10497}],
 "images": [{"uri": "data:image/png;base64,)" + base64(checkerPng()) + R"("}],
 "buffers": [{"byteLength": )" + std::to_string(bytes.size()) + R"(, "uri": "data:application/octet-stream;base64,)" +
                           base64(bytes) + R"("}],
 "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 160}, {"buffer": 0, "byteOffset": 160, "byteLength": 12}],
 "accessors": [
  {"bufferView": 0, "byteOffset": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0]},
  {"bufferView": 0, "byteOffset": 48, "componentType": 5126, "count": 4, "type": "VEC3"},
  {"bufferView": 0, "byteOffset": 96, "componentType": 5126, "count": 4, "type": "VEC2"},
  {"bufferView": 0, "byteOffset": 128, "componentType": 5126, "count": 4, "type": "VEC2"},
  {"bufferView": 1, "byteOffset": 0, "componentType": 5123, "count": 6, "type": "SCALAR"}]})";
  const std::string path = scenelod::test::scratchDir() + "/" + name;
  std::ofstream(path) << json;
  return path;
}

double jsonValue(const std::string& json, const std::string& key) {
  const size_t k = json.find("\"" + key + "\":");
  if (k == std::string::npos) return NAN;
  return std::strtod(json.c_str() + k + key.size() + 3, nullptr);
}

class TexturedCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    if (std::string(SCENELOD_TOOL_PATH).empty()) GTEST_SKIP() << "the scenelod tool is not built";
  }
  // colour off between two files, drawn textured
  double colourOff(const std::string& a, const std::string& b) {
    const ToolRun r = runTool("eval " + a + " " + b + " --image --json --samples 1000 --resolution 64");
    EXPECT_EQ(r.code, 0) << r.output;
    EXPECT_NE(r.output.find("\"textured\": true"), std::string::npos) << r.output;
    return jsonValue(r.output, "color_off");
  }
};

TEST_F(TexturedCommand, TransformTexcoordAndPlainAreHonoured) {
  const std::string plain = writeQuadGltf("quad.gltf", "");
  EXPECT_EQ(colourOff(plain, plain), 0.0);
  // one block along u (a quarter of the texture) swaps black and white everywhere
  const std::string moved =
      writeQuadGltf("quad_moved.gltf", R"(, "extensions": {"KHR_texture_transform": {"offset": [0.25, 0]}})");
  EXPECT_GT(colourOff(plain, moved), 0.8);
  // a whole texture along u changes nothing under REPEAT
  const std::string wrapped =
      writeQuadGltf("quad_wrapped.gltf", R"(, "extensions": {"KHR_texture_transform": {"offset": [1, 0]}})");
  EXPECT_LT(colourOff(plain, wrapped), 0.01);
  // texCoord 1 reads the other set: with the sets swapped the picture is the same
  const std::string set1 = writeQuadGltf("quad_set1.gltf", R"(, "texCoord": 1)", true);
  EXPECT_LT(colourOff(plain, set1), 0.01);
  // the transform's texCoord overrides the reference's
  const std::string override_set =
      writeQuadGltf("quad_override.gltf", R"(, "extensions": {"KHR_texture_transform": {"texCoord": 1}})", true);
  EXPECT_LT(colourOff(plain, override_set), 0.01);
  // render writes a picture with both black and white blocks; --plain draws it untextured
  const std::string png = scenelod::test::scratchDir() + "/quad.png";
  ToolRun r = runTool("render " + plain + " -o " + png + " --view axis 4 --size 64 64");
  EXPECT_EQ(r.code, 0) << r.output;
  r = runTool("render " + plain + " -o " + png + " --view axis 4 --size 64 64 --plain");
  EXPECT_EQ(r.code, 0) << r.output;
}

std::vector<char> fileBytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::vector<char>(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

// `render --stored` draws the levels a file holds: lods' level 0 is the textured input itself, so its
// picture is the input's, texture included; a file without levels is refused by name
TEST_F(TexturedCommand, StoredLevelsAreDrawnWithTheirMaterials) {
  const std::string quad = writeQuadGltf("quad_for_lods.gltf", "");
  const std::string dir = scenelod::test::scratchDir();
  ToolRun r = runTool("lods " + quad + " -o " + dir + "/quad_lods.glb --levels 2");
  ASSERT_EQ(r.code, 0) << r.output;
  r = runTool("render " + quad + " -o " + dir + "/quad_built.png --show 0 --size 64 64 --view axis 4");
  ASSERT_EQ(r.code, 0) << r.output;
  r = runTool("render " + dir + "/quad_lods.glb -o " + dir + "/quad_stored.png --stored --show 0 --size 64 64 --view axis 4");
  ASSERT_EQ(r.code, 0) << r.output;
  const std::vector<char> built = fileBytes(dir + "/quad_built.png"), stored = fileBytes(dir + "/quad_stored.png");
  EXPECT_FALSE(built.empty());
  EXPECT_EQ(built, stored);
  // eval measures a stored level: level 0 is the input
  r = runTool("eval " + quad + " " + dir + "/quad_lods.glb --stored-level 0 --json --samples 1000 --resolution 32");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_LT(jsonValue(r.output, "hausdorff"), 1e-6) << r.output;  // float noise of the sampling
  r = runTool("eval " + quad + " " + dir + "/quad_lods.glb --stored-level 40");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("quad_lods.glb: holds levels 0.."), std::string::npos) << r.output;
  r = runTool("render " + quad + " -o " + dir + "/quad_none.png --stored --level 1");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("quad_for_lods.gltf: holds no LOD levels (no MSFT_lod)"), std::string::npos) << r.output;
}

}  // namespace
