// glTF import of what an engine draws with: UV sets, tangents, COLOR_0 as read, triangle groups,
// textures and images, KHR_texture_transform, skins and animations; bad attribute data; and
// flattenScene / optimizeMeshOrder carrying every attribute.
#include <sys/stat.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "scenelod/scene/gltf_io.h"
#include "scenelod/scene/mesh_order.h"
#include "gltf_test_support.h"

using namespace scenelod;
using namespace scenelod::scene;

namespace {

using test::contains;
using test::makeDir;

// a .gltf with one external buffer; accessors are appended with their data, the rest of the JSON
// (meshes, nodes, ...) is given by the test
class GltfBuilder {
 public:
  // appends `count` elements of `type` ("VEC2", ...) with component type `ctype`; returns the accessor
  int add(const void* data, size_t bytes, int ctype, size_t count, const std::string& type, bool normalized = false) {
    while (bin_.size() % 4) bin_.push_back(0);
    const size_t off = bin_.size();
    bin_.insert(bin_.end(), static_cast<const unsigned char*>(data), static_cast<const unsigned char*>(data) + bytes);
    views_ += (views_.empty() ? "" : ",") + std::string("{\"buffer\":0,\"byteOffset\":") + std::to_string(off) +
              ",\"byteLength\":" + std::to_string(bytes) + "}";
    const size_t view = count_++;
    accessors_ += (accessors_.empty() ? "" : ",") + std::string("{\"bufferView\":") + std::to_string(view) +
                  ",\"componentType\":" + std::to_string(ctype) + ",\"count\":" + std::to_string(count) + ",\"type\":\"" +
                  type + "\"" + (normalized ? ",\"normalized\":true" : "") + "}";
    return static_cast<int>(view);
  }
  int floats(const std::vector<float>& v, const std::string& type, size_t comps) {
    return add(v.data(), v.size() * 4, 5126, v.size() / comps, type);
  }

  std::string write(const std::string& dir, const std::string& rest) const {
    std::ofstream(dir + "/m.bin", std::ios::binary).write(reinterpret_cast<const char*>(bin_.data()), std::streamsize(bin_.size()));
    std::ofstream(dir + "/m.gltf") << "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"uri\":\"m.bin\",\"byteLength\":"
                                   << bin_.size() << "}],\"bufferViews\":[" << views_ << "],\"accessors\":[" << accessors_
                                   << "]," << rest << "}";
    return dir + "/m.gltf";
  }

 private:
  std::vector<unsigned char> bin_;
  std::string views_, accessors_;
  size_t count_ = 0;
};

const std::vector<float> kQuad = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
const std::vector<float> kQuadNormals = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
const std::vector<uint16_t> kQuadIndices = {0, 1, 2, 0, 2, 3};

// two primitives of one mesh: the first with two UV sets, TANGENT and COLOR_0 (material 0), the
// second with POSITION, NORMAL and one UV set (material 1)
std::string writeTwoPrimitives(const std::string& dir) {
  GltfBuilder b;
  const int pos = b.floats(kQuad, "VEC3", 3), nrm = b.floats(kQuadNormals, "VEC3", 3);
  const int uv0 = b.floats({0, 0, 1, 0, 1, 1, 0, 1}, "VEC2", 2), uv1 = b.floats({0.5f, 0.5f, 1, 0.5f, 1, 1, 0.5f, 1}, "VEC2", 2);
  const int tan = b.floats({1, 0, 0, -1, 1, 0, 0, -1, 1, 0, 0, -1, 1, 0, 0, -1}, "VEC4", 4);
  const int col = b.floats({0.25f, 0.5f, 0.75f, 1, 0.25f, 0.5f, 0.75f, 1, 1, 0, 0, 1, 0, 1, 0, 1}, "VEC4", 4);
  const int idx = b.add(kQuadIndices.data(), 12, 5123, 6, "SCALAR");
  const int pos2 = b.floats({0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1}, "VEC3", 3);
  const int uv2 = b.floats({0, 0, 1, 0, 1, 1, 0, 1}, "VEC2", 2);
  const std::string p = "\"attributes\":{\"POSITION\":" + std::to_string(pos) + ",\"NORMAL\":" + std::to_string(nrm) +
                        ",\"TEXCOORD_0\":" + std::to_string(uv0) + ",\"TEXCOORD_1\":" + std::to_string(uv1) +
                        ",\"TANGENT\":" + std::to_string(tan) + ",\"COLOR_0\":" + std::to_string(col) + "}";
  const std::string q = "\"attributes\":{\"POSITION\":" + std::to_string(pos2) + ",\"NORMAL\":" + std::to_string(nrm) +
                        ",\"TEXCOORD_0\":" + std::to_string(uv2) + "}";
  return b.write(dir, "\"materials\":[{\"name\":\"a\"},{\"name\":\"b\"}],\"meshes\":[{\"primitives\":[{" + p +
                          ",\"indices\":" + std::to_string(idx) + ",\"material\":0},{" + q + ",\"indices\":" +
                          std::to_string(idx) + ",\"material\":1}]}],\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}]");
}

}  // namespace

TEST(GltfAttributes, UvSetsTangentsColoursAndGroupsPerPrimitive) {
  SceneData s;
  const Error e = importGltf(writeTwoPrimitives(makeDir("attr_two")), s);
  ASSERT_TRUE(e.ok()) << e.message;
  const MeshData& md = s.meshes[0];
  const Mesh& m = md.mesh;
  ASSERT_EQ(m.vertexCount(), 8u);
  EXPECT_EQ(md.primitive_materials, (std::vector<int32_t>{0, 1}));
  EXPECT_EQ(m.triangle_groups, (std::vector<uint32_t>{0, 0, 1, 1}));
  ASSERT_EQ(m.uvs.size(), 8u);
  EXPECT_EQ(m.uvs[2], glm::vec2(1, 1));
  EXPECT_EQ(m.uvs[6], glm::vec2(1, 1));
  ASSERT_EQ(m.extra_uvs.size(), 1u);
  ASSERT_EQ(m.extra_uvs[0].size(), 8u);
  EXPECT_EQ(m.extra_uvs[0][1], glm::vec2(1, 0.5f));
  EXPECT_EQ(m.extra_uvs[0][5], glm::vec2(0, 0));  // the second primitive has no TEXCOORD_1: 0
  // COLOR_0 as read (no material colour in it), white where a primitive has none
  ASSERT_EQ(m.colors.size(), 8u);
  EXPECT_EQ(m.colors[0], glm::vec3(0.25f, 0.5f, 0.75f));
  EXPECT_EQ(m.colors[2], glm::vec3(1, 0, 0));
  EXPECT_EQ(m.colors[5], glm::vec3(1, 1, 1));
  // tangents as read; the second primitive's from its UVs (u grows along +x, v along +y: w = +1)
  ASSERT_EQ(m.tangents.size(), 8u);
  EXPECT_EQ(m.tangents[0], glm::vec4(1, 0, 0, -1));
  for (size_t v = 4; v < 8; ++v) {
    EXPECT_NEAR(m.tangents[v].x, 1.0f, 1e-5f) << v;
    EXPECT_NEAR(std::fabs(m.tangents[v].y) + std::fabs(m.tangents[v].z), 0.0f, 1e-5f) << v;
    EXPECT_EQ(m.tangents[v].w, 1.0f) << v;
  }
  EXPECT_TRUE(m.joints.empty());
  EXPECT_TRUE(validateMesh(m, "two").ok());
}

TEST(GltfAttributes, TexturesSamplersAndTextureTransform) {
  const std::string dir = makeDir("attr_texture");
  // the 1 x 1 red PNG, base64
  const std::string png = "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR4nGP4z8DwHwAFAAH/iZk9HQAAAABJRU5ErkJggg==";
  GltfBuilder b;
  const int pos = b.floats(kQuad, "VEC3", 3), uv = b.floats({0, 0, 1, 0, 1, 1, 0, 1}, "VEC2", 2);
  const int idx = b.add(kQuadIndices.data(), 12, 5123, 6, "SCALAR");
  const std::string path = b.write(
      dir, "\"images\":[{\"name\":\"red\",\"uri\":\"data:image/png;base64," + png +
               "\"}],\"samplers\":[{\"wrapS\":33071,\"wrapT\":33648}],\"textures\":[{\"source\":0,\"sampler\":0}],"
               "\"extensionsUsed\":[\"KHR_texture_transform\"],\"extensionsRequired\":[\"KHR_texture_transform\"],"
               "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0,\"texCoord\":0,\"extensions\":"
               "{\"KHR_texture_transform\":{\"offset\":[0.5,0.25],\"rotation\":0.5,\"scale\":[2,3],\"texCoord\":1}}}}}],"
               "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(pos) + ",\"TEXCOORD_0\":" +
               std::to_string(uv) + "},\"indices\":" + std::to_string(idx) +
               ",\"material\":0}]}],\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}]");
  SceneData s;
  const Error e = importGltf(path, s);
  ASSERT_TRUE(e.ok()) << e.message;
  ASSERT_EQ(s.images.size(), 1u);
  EXPECT_EQ(s.images[0].name, "red");
  EXPECT_EQ(s.images[0].mime_type, "image/png");
  EXPECT_EQ(s.images[0].encoded.size(), 70u);
  ASSERT_EQ(s.images[0].rgba8.size(), 4u);
  EXPECT_EQ(s.images[0].rgba8[0], 255);
  EXPECT_EQ(s.images[0].rgba8[1], 0);
  ASSERT_EQ(s.textures.size(), 1u);
  EXPECT_EQ(s.textures[0].wrap_s, 33071);
  EXPECT_EQ(s.textures[0].wrap_t, 33648);
  const MaterialData& mat = s.materials[0];
  EXPECT_EQ(mat.base_color_texture, 0);
  EXPECT_EQ(mat.base_color_texcoord, 0u);
  EXPECT_EQ(mat.base_color_transform.offset, glm::vec2(0.5f, 0.25f));
  EXPECT_EQ(mat.base_color_transform.rotation, 0.5f);
  EXPECT_EQ(mat.base_color_transform.scale, glm::vec2(2, 3));
  EXPECT_EQ(mat.base_color_transform.texcoord, 1);
  EXPECT_NEAR(mat.average_texel_color.r, 1.0f, 1e-6f);
  EXPECT_NEAR(mat.average_texel_color.g, 0.0f, 1e-6f);
}

namespace {

// a skinned quad: nodes 0 root (mesh, skin 0, translated by 5: ignored), 1 joint A (child of 2),
// 2 joint B (a root), 3 joint C (child of 1 through the non-joint 4); skin joints [A, B, C];
// one animation with a sampler per interpolation. `joints`/`weights` override the vertex data.
std::string writeSkinned(const std::string& dir, std::vector<uint8_t> joints = {}, std::vector<float> weights = {}) {
  if (joints.empty()) joints = {0, 1, 0, 0, 1, 0, 0, 0, 2, 1, 0, 0, 2, 0, 0, 0};
  if (weights.empty()) weights = {0.5f, 0.5f, 0, 0, 1, 0, 0, 0, 0.25f, 0.75f, 0, 0, 1, 0, 0, 0};
  GltfBuilder b;
  const int pos = b.floats(kQuad, "VEC3", 3);
  const int jnt = b.add(joints.data(), joints.size(), 5121, joints.size() / 4, "VEC4");
  const int wgt = b.floats(weights, "VEC4", 4);
  const int idx = b.add(kQuadIndices.data(), 12, 5123, 6, "SCALAR");
  std::vector<float> ibm;
  for (int j = 0; j < 3; ++j) {
    const float m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, float(-j), 0, 0, 1};
    ibm.insert(ibm.end(), m, m + 16);
  }
  const int inv = b.floats(ibm, "MAT4", 16);
  const int times = b.floats({0, 0.5f, 1}, "SCALAR", 1);
  const int trans = b.floats({0, 0, 0, 1, 0, 0, 2, 0, 0}, "VEC3", 3);
  const int rot = b.floats({0, 0, 0, 1, 0, 0, 0.7071068f, 0.7071068f, 0, 0, 1, 0}, "VEC4", 4);
  std::vector<float> cubic;  // in-tangent, value, out-tangent per key
  for (int k = 0; k < 3; ++k)
    for (int part = 0; part < 3; ++part) cubic.insert(cubic.end(), {float(part), float(k), 1});
  const int scl = b.floats(cubic, "VEC3", 3);
  const std::string n = std::to_string(pos);
  return b.write(
      dir, "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":" + n + ",\"JOINTS_0\":" + std::to_string(jnt) +
               ",\"WEIGHTS_0\":" + std::to_string(wgt) + "},\"indices\":" + std::to_string(idx) + "}]}],"
               "\"nodes\":[{\"name\":\"body\",\"mesh\":0,\"skin\":0,\"translation\":[5,0,0],\"children\":[5]},"
               "{\"name\":\"A\",\"children\":[4]},{\"name\":\"B\",\"children\":[1]},{\"name\":\"C\"},"
               "{\"name\":\"between\",\"children\":[3]},{\"name\":\"attached\"}],"
               "\"skins\":[{\"joints\":[1,2,3],\"inverseBindMatrices\":" + std::to_string(inv) + ",\"skeleton\":2}],"
               "\"animations\":[{\"name\":\"walk\",\"samplers\":[{\"input\":" + std::to_string(times) + ",\"output\":" +
               std::to_string(trans) + "},{\"input\":" + std::to_string(times) + ",\"output\":" + std::to_string(rot) +
               ",\"interpolation\":\"STEP\"},{\"input\":" + std::to_string(times) + ",\"output\":" + std::to_string(scl) +
               ",\"interpolation\":\"CUBICSPLINE\"}],\"channels\":[{\"sampler\":0,\"target\":{\"node\":1,\"path\":"
               "\"translation\"}},{\"sampler\":1,\"target\":{\"node\":2,\"path\":\"rotation\"}},{\"sampler\":2,"
               "\"target\":{\"node\":3,\"path\":\"scale\"}}]}],\"scenes\":[{\"nodes\":[0,2]}]");
}

}  // namespace

TEST(GltfAttributes, SkinsJointsWeightsAndAnimations) {
  SceneData s;
  const Error e = importGltf(writeSkinned(makeDir("attr_skin")), s);
  ASSERT_TRUE(e.ok()) << e.message;
  const Mesh& m = s.meshes[0].mesh;
  ASSERT_EQ(m.joints.size(), 4u);
  EXPECT_EQ(m.joints[2], glm::u16vec4(2, 1, 0, 0));
  EXPECT_EQ(m.weights[2], glm::vec4(0.25f, 0.75f, 0, 0));
  // joint parents by the nearest ancestor that is a joint: A -> B (1), B root, C -> A through "between"
  EXPECT_EQ(m.joint_parents, (std::vector<int32_t>{1, -1, 0}));
  EXPECT_EQ(s.nodes[0].skin, 0);
  ASSERT_EQ(s.skins.size(), 1u);
  EXPECT_EQ(s.skins[0].joints, (std::vector<int32_t>{1, 2, 3}));
  EXPECT_EQ(s.skins[0].skeleton, 2);
  ASSERT_EQ(s.skins[0].inverse_bind.size(), 3u);
  EXPECT_EQ(s.skins[0].inverse_bind[2][3], glm::vec4(-2, 0, 0, 1));
  // glTF ignores the skinned mesh node's transform; its child keeps it
  const std::vector<glm::mat4> world = worldTransforms(s);
  EXPECT_EQ(world[0], glm::mat4(1.0f));
  EXPECT_EQ(glm::vec3(world[5][3]), glm::vec3(5, 0, 0));
  EXPECT_EQ(flattenScene(s).positions[1], glm::vec3(1, 0, 0));
  ASSERT_EQ(s.animations.size(), 1u);
  const AnimationData& a = s.animations[0];
  EXPECT_EQ(a.name, "walk");
  ASSERT_EQ(a.samplers.size(), 3u);
  EXPECT_EQ(a.samplers[0].interpolation, AnimationData::Interpolation::kLinear);
  EXPECT_EQ(a.samplers[1].interpolation, AnimationData::Interpolation::kStep);
  EXPECT_EQ(a.samplers[2].interpolation, AnimationData::Interpolation::kCubicSpline);
  EXPECT_EQ(a.samplers[0].times, (std::vector<float>{0, 0.5f, 1}));
  EXPECT_EQ(a.samplers[0].values[2], glm::vec4(2, 0, 0, 0));
  EXPECT_EQ(a.samplers[1].values[1], glm::vec4(0, 0, 0.7071068f, 0.7071068f));
  ASSERT_EQ(a.samplers[2].values.size(), 9u);
  EXPECT_EQ(a.samplers[2].values[4], glm::vec4(1, 1, 1, 0));  // key 1's value
  ASSERT_EQ(a.channels.size(), 3u);
  EXPECT_EQ(a.channels[1].node, 2);
  EXPECT_EQ(a.channels[1].path, AnimationData::Path::kRotation);
  EXPECT_EQ(a.channels[2].sampler, 2);
}

TEST(GltfAttributes, NormalizedIntegerWeightsReadAsFloats) {
  const std::string dir = makeDir("attr_uweights");
  GltfBuilder b;
  const int pos = b.floats(kQuad, "VEC3", 3);
  const std::vector<uint8_t> j = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  const std::vector<uint8_t> w = {255, 0, 0, 0, 128, 127, 0, 0, 255, 0, 0, 0, 51, 204, 0, 0};
  const int jnt = b.add(j.data(), j.size(), 5121, 4, "VEC4"), wgt = b.add(w.data(), w.size(), 5121, 4, "VEC4", true);
  const int idx = b.add(kQuadIndices.data(), 12, 5123, 6, "SCALAR");
  SceneData s;
  const Error e = importGltf(b.write(dir, "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(pos) +
                                              ",\"JOINTS_0\":" + std::to_string(jnt) + ",\"WEIGHTS_0\":" + std::to_string(wgt) +
                                              "},\"indices\":" + std::to_string(idx) + "}]}],\"nodes\":[{\"mesh\":0}]"),
                             s);
  ASSERT_TRUE(e.ok()) << e.message;
  EXPECT_FLOAT_EQ(s.meshes[0].mesh.weights[0].x, 1.0f);
  EXPECT_FLOAT_EQ(s.meshes[0].mesh.weights[1].x, 128.0f / 255.0f);
  EXPECT_FLOAT_EQ(s.meshes[0].mesh.weights[3].y, 0.8f);
  EXPECT_TRUE(s.meshes[0].mesh.joint_parents.empty());  // no skin uses the mesh
}

// every bad attribute gets an error naming the file, the mesh, the primitive and the attribute
TEST(GltfAttributes, BadAttributeDataIsNamed) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  struct Case {
    const char* name;
    std::vector<uint8_t> joints;
    std::vector<float> weights;
    const char* attribute;
    const char* problem;
  };
  const Case cases[] = {
      {"nan_weight", {}, {nan, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0}, "WEIGHTS_0", "NaN"},
      {"zero_weights", {}, {1, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0}, "WEIGHTS_0", "summing to 0"},
      {"negative_weight", {}, {1, 0, 0, 0, 2, -1, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0}, "WEIGHTS_0", "negative"},
      {"joint_oob", {0, 0, 0, 0, 3, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}, {}, "JOINTS_0", "3 joints of skin 0"},
      {"short_weights", {}, {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0}, "WEIGHTS_0", "3 elements, POSITION 4"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string path = writeSkinned(makeDir(std::string("attr_bad_") + c.name), c.joints, c.weights);
    SceneData s;
    const Error e = importGltf(path, s);
    ASSERT_FALSE(e.ok());
    EXPECT_TRUE(contains(e.message, path)) << e.message;
    EXPECT_TRUE(contains(e.message, "mesh 0 primitive 0")) << e.message;
    EXPECT_TRUE(contains(e.message, c.attribute)) << e.message;
    EXPECT_TRUE(contains(e.message, c.problem)) << e.message;
  }
}

TEST(GltfAttributes, ShortOrNanUvsAreNamed) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<std::vector<float>> uvs = {{0, 0, 1, 0, 1, 1}, {0, 0, 1, nan, 1, 1, 0, 1}};
  const char* const problems[] = {"TEXCOORD_0 has 3 elements, POSITION 4", "TEXCOORD_0: element 1 is NaN"};
  for (size_t k = 0; k < uvs.size(); ++k) {
    GltfBuilder b;
    const int pos = b.floats(kQuad, "VEC3", 3), uv = b.floats(uvs[k], "VEC2", 2);
    const int idx = b.add(kQuadIndices.data(), 12, 5123, 6, "SCALAR");
    const std::string path =
        b.write(makeDir("attr_bad_uv" + std::to_string(k)),
                "\"meshes\":[{\"name\":\"cloth\",\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(pos) +
                    ",\"TEXCOORD_0\":" + std::to_string(uv) + "},\"indices\":" + std::to_string(idx) + "}]}],\"nodes\":[{\"mesh\":0}]");
    SceneData s;
    const Error e = importGltf(path, s);
    ASSERT_FALSE(e.ok());
    EXPECT_TRUE(contains(e.message, path + ": mesh 0 'cloth' primitive 0")) << e.message;
    EXPECT_TRUE(contains(e.message, problems[k])) << e.message;
  }
}

TEST(GltfAttributes, ValidateSceneDataChecksJointsAgainstTheSkin) {
  SceneData s;
  ASSERT_TRUE(importGltf(writeSkinned(makeDir("attr_validate")), s).ok());
  s.skins[0].joints.pop_back();
  s.skins[0].inverse_bind.pop_back();
  s.meshes[0].mesh.joint_parents.clear();
  const Error e = validateSceneData(s, "edited");
  ASSERT_FALSE(e.ok());
  EXPECT_TRUE(contains(e.message, "edited mesh 0 JOINTS_0")) << e.message;
  EXPECT_TRUE(contains(e.message, "uses joint 2")) << e.message;
}

TEST(GltfAttributes, FlattenCarriesAttributesAndMaterialGroups) {
  SceneData s;
  ASSERT_TRUE(importGltf(writeTwoPrimitives(makeDir("attr_flatten")), s).ok());
  s.materials.pop_back();
  s.meshes[0].primitive_materials[1] = -1;
  // a second, mirrored instance (x -> -x)
  NodeData mirror;
  mirror.mesh = 0;
  mirror.local = glm::mat4(1.0f);
  mirror.local[0][0] = -1.0f;
  s.nodes.push_back(mirror);
  s.roots.push_back(1);
  const Mesh flat = flattenScene(s);
  ASSERT_EQ(flat.vertexCount(), 16u);
  EXPECT_EQ(flat.triangle_groups, (std::vector<uint32_t>{0, 0, kNoMaterial, kNoMaterial, 0, 0, kNoMaterial, kNoMaterial}));
  ASSERT_EQ(flat.extra_uvs.size(), 1u);
  EXPECT_EQ(flat.extra_uvs[0][9], glm::vec2(1, 0.5f));
  EXPECT_EQ(flat.uvs[10], glm::vec2(1, 1));
  ASSERT_EQ(flat.tangents.size(), 16u);
  EXPECT_EQ(flat.tangents[0], glm::vec4(1, 0, 0, -1));
  EXPECT_EQ(flat.tangents[8], glm::vec4(-1, 0, 0, 1));  // mirrored: direction mirrored, sign flipped
  EXPECT_TRUE(flat.joints.empty());
  EXPECT_TRUE(validateMesh(flat, "flat").ok());
}

TEST(GltfAttributes, MeshOrderCarriesEveryAttributeAndGroup) {
  SceneData s;
  ASSERT_TRUE(importGltf(writeTwoPrimitives(makeDir("attr_order")), s).ok());
  Mesh m = s.meshes[0].mesh;
  // interleave the groups so that reordering has something to move, and give every vertex a skin
  std::swap(m.triangle_groups[1], m.triangle_groups[2]);
  for (int k = 0; k < 3; ++k) std::swap(m.triangles[3 + k], m.triangles[6 + k]);
  for (size_t v = 0; v < m.vertexCount(); ++v) {
    m.joints.push_back(glm::u16vec4(uint16_t(v), 0, 0, 0));
    m.weights.push_back(glm::vec4(1, 0, 0, 0));
  }
  const Mesh before = m;
  optimizeMeshOrder(m);
  ASSERT_TRUE(validateMesh(m, "ordered").ok());
  EXPECT_EQ(m.triangle_groups, (std::vector<uint32_t>{0, 0, 1, 1}));
  // every triangle keeps its group and each corner every attribute of its source vertex
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    bool found = false;
    for (size_t u = 0; u < before.triangleCount() && !found; ++u) {
      bool same = before.triangle_groups[u] == m.triangle_groups[t];
      for (int k = 0; k < 3 && same; ++k) {
        const uint32_t a = m.triangles[3 * t + size_t(k)], b = before.triangles[3 * u + size_t(k)];
        same = m.positions[a] == before.positions[b] && m.uvs[a] == before.uvs[b] &&
               m.extra_uvs[0][a] == before.extra_uvs[0][b] && m.tangents[a] == before.tangents[b] &&
               m.colors[a] == before.colors[b] && m.joints[a] == before.joints[b] && m.weights[a] == before.weights[b];
      }
      found = same;
    }
    EXPECT_TRUE(found) << "triangle " << t;
  }
}

TEST(GltfAttributes, BadSkinAnimationAndImageReferencesAreNamed) {
  const std::string dir = makeDir("attr_bad_refs");
  const std::string path = writeSkinned(dir);
  std::string json;
  {
    std::ifstream f(path);
    json.assign(std::istreambuf_iterator<char>(f), {});
  }
  struct Case {
    const char* from;
    const char* to;
    const char* message;
  };
  const Case cases[] = {
      {"\"joints\":[1,2,3]", "\"joints\":[1,2,9]", "skin 0: joint 9 is not a node (the file has 6)"},
      {"{\"node\":3,\"path\":\"scale\"}", "{\"node\":6,\"path\":\"scale\"}",
       "animation 0 channel 2 targets node 6, which does not exist (the file has 6 nodes)"},
      {"\"meshes\":", "\"images\":[{\"uri\":\"missing.png\"}],\"meshes\":", "image 0: cannot read 'missing.png'"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.message);
    const size_t at = json.find(c.from);
    ASSERT_NE(at, std::string::npos);
    std::string edited = json;
    edited.replace(at, std::string(c.from).size(), c.to);
    std::ofstream(dir + "/edited.gltf") << edited;
    SceneData s;
    const Error e = importGltf(dir + "/edited.gltf", s);
    ASSERT_FALSE(e.ok());
    EXPECT_TRUE(contains(e.message, dir + "/edited.gltf: " + c.message)) << e.message;
  }
}
