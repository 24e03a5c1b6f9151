// The C API's vertex attributes: streams, skin and index ranges go in through slod_mesh_desc and
// come back from slod_level_get / slod_level_attribute_get exactly as the chain's levels hold them
// (level 0 = the input), and bad input is refused with a message naming the mesh and the stream.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "scenelod/lodcore/chain.h"
#include "scenelod/scene/pack.h"
#include "scenelod/scenelod.h"
#include "test_support.h"

using namespace scenelod;

namespace {

// one interleaved vertex of an engine's buffer
struct Vertex {
  float position[3];
  float normal[3];
  float uv0[2];
  float color[4];
  float tangent[4];
  uint16_t joints[4];
  float weights[4];
};

// A textured, skinned n x n grid with bumps: two materials (left half of the quads, then the right
// half, as two index ranges), a second UV set apart, three joints in a chain.
struct TexturedGrid {
  std::vector<Vertex> vertices;
  std::vector<float> uv1;  // the second UV set, its own array
  std::vector<uint32_t> indices;
  std::vector<int32_t> joint_parents{-1, 0, 1};
  slod_index_range ranges[2] = {};
  slod_attribute_stream streams[5];
  slod_mesh_desc desc;

  explicit TexturedGrid(uint32_t n) {
    for (uint32_t y = 0; y <= n; ++y)
      for (uint32_t x = 0; x <= n; ++x) {
        const float u = float(x) / float(n), v = float(y) / float(n);
        Vertex w{};
        w.position[0] = u;
        w.position[1] = v;
        w.position[2] = 0.05f * std::sin(9.0f * u) * std::cos(7.0f * v);
        w.normal[2] = 1.0f;
        w.uv0[0] = u;
        w.uv0[1] = 1.0f - v;
        w.color[0] = u;
        w.color[1] = v;
        w.color[2] = 0.5f;
        w.color[3] = 1.0f;
        w.tangent[0] = 1.0f;
        w.tangent[3] = x % 2 ? 1.0f : -1.0f;
        w.joints[0] = uint16_t(x * 3 / (n + 1));
        w.joints[1] = uint16_t(std::min<uint32_t>(2, x * 3 / (n + 1) + 1));
        w.weights[0] = 0.75f;
        w.weights[1] = 0.25f;
        vertices.push_back(w);
        uv1.insert(uv1.end(), {2.0f * u, 2.0f * v});
      }
    for (uint32_t half = 0; half < 2; ++half) {
      ranges[half].first_index = uint32_t(indices.size());
      for (uint32_t y = 0; y < n; ++y)
        for (uint32_t x = half * n / 2; x < (half + 1) * n / 2; ++x) {
          const uint32_t a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
          indices.insert(indices.end(), {a, b, d, a, d, c});
        }
      ranges[half].index_count = uint32_t(indices.size()) - ranges[half].first_index;
      ranges[half].material = half ? 3u : 7u;
    }
    slod_mesh_desc_init(&desc);
    desc.name = "textured grid";
    desc.positions = vertices[0].position;
    desc.vertex_count = vertices.size();
    desc.position_stride = sizeof(Vertex);
    desc.indices = indices.data();
    desc.index_count = indices.size();
    const std::tuple<slod_attribute_kind, uint32_t, uint32_t, const float*, size_t> s[5] = {
        {SLOD_ATTRIBUTE_UV, 0, 2, vertices[0].uv0, sizeof(Vertex)},
        {SLOD_ATTRIBUTE_UV, 1, 2, uv1.data(), 0},
        {SLOD_ATTRIBUTE_NORMAL, 0, 3, vertices[0].normal, sizeof(Vertex)},
        {SLOD_ATTRIBUTE_COLOR, 0, 4, vertices[0].color, sizeof(Vertex)},
        {SLOD_ATTRIBUTE_TANGENT4, 0, 4, vertices[0].tangent, sizeof(Vertex)}};
    for (int i = 0; i < 5; ++i) {
      slod_attribute_stream_init(&streams[i]);
      std::tie(streams[i].kind, streams[i].set, streams[i].component_count, streams[i].data, streams[i].stride) = s[i];
      streams[i].count = vertices.size();
    }
    desc.attributes = streams;
    desc.attribute_count = 5;
    desc.joint_count = 3;
    desc.joints = vertices[0].joints;
    desc.joints_stride = sizeof(Vertex);
    desc.weights = vertices[0].weights;
    desc.weights_stride = sizeof(Vertex);
    desc.skin_count = vertices.size();
    desc.joint_parents = joint_parents.data();
    desc.ranges = ranges;
    desc.range_count = 2;
  }

  // the same mesh as lodcore sees it
  Mesh mesh() const {
    Mesh m;
    for (size_t i = 0; i < vertices.size(); ++i) {
      const Vertex& w = vertices[i];
      m.positions.push_back({w.position[0], w.position[1], w.position[2]});
      m.normals.push_back({w.normal[0], w.normal[1], w.normal[2]});
      m.colors.push_back({w.color[0], w.color[1], w.color[2]});
      m.uvs.push_back({w.uv0[0], w.uv0[1]});
      m.tangents.push_back({w.tangent[0], w.tangent[1], w.tangent[2], w.tangent[3]});
      m.joints.push_back({w.joints[0], w.joints[1], w.joints[2], w.joints[3]});
      m.weights.push_back({w.weights[0], w.weights[1], w.weights[2], w.weights[3]});
    }
    m.extra_uvs.assign(1, {});
    for (size_t i = 0; i < vertices.size(); ++i) m.extra_uvs[0].push_back({uv1[2 * i], uv1[2 * i + 1]});
    m.joint_parents = joint_parents;
    m.triangles = indices;
    m.triangle_groups.assign(ranges[0].index_count / 3, 0u);
    m.triangle_groups.resize(indices.size() / 3, 1u);
    return m;
  }
};

struct Context {
  slod_context* ctx = nullptr;
  Context() {
    slod_context_desc d;
    slod_context_desc_init(&d);
    EXPECT_EQ(slod_context_create(&d, &ctx), SLOD_OK);
  }
  ~Context() { slod_context_destroy(ctx); }
  std::string message() const { return slod_last_error_message(ctx); }
};

slod_chain_desc chainDesc() {
  slod_chain_desc c;
  slod_chain_desc_init(&c);
  c.level_count = 4;
  return c;
}

// a chain of 4 simplified levels from `mesh`, which must be accepted
slod_chain build(const Context& c, const slod_mesh_desc& mesh, slod_method method = SLOD_METHOD_FLOATING) {
  slod_chain chain = SLOD_NULL_CHAIN;
  slod_chain_desc cd = chainDesc();
  cd.method = method;
  EXPECT_EQ(slod_chain_build(c.ctx, &mesh, &cd, &chain), SLOD_OK) << c.message();
  return chain;
}

// what a level's stream of `kind` and `set` must hold: the level mesh's array, as floats
std::vector<float> expectedStream(const Mesh& m, slod_attribute_kind kind, uint32_t set) {
  auto floats = [](const auto& v) {
    std::vector<float> out(v.size() * sizeof(v[0]) / sizeof(float));
    if (!v.empty()) std::memcpy(out.data(), v.data(), out.size() * sizeof(float));
    return out;
  };
  switch (kind) {
    case SLOD_ATTRIBUTE_UV: return set == 0 ? floats(m.uvs) : set <= m.extra_uvs.size() ? floats(m.extra_uvs[set - 1]) : std::vector<float>{};
    case SLOD_ATTRIBUTE_COLOR: return floats(m.colors);
    case SLOD_ATTRIBUTE_NORMAL: return floats(m.normals);
    case SLOD_ATTRIBUTE_TANGENT4: return floats(m.tangents);
    default: return {};
  }
}

// the streams a level reports, each as (kind, set) -> floats
std::vector<std::tuple<int, uint32_t, std::vector<float>>> levelStreams(const Context& c, slod_chain chain, uint32_t level,
                                                                        const slod_level_data& d) {
  std::vector<std::tuple<int, uint32_t, std::vector<float>>> out;
  for (uint32_t i = 0; i < d.attribute_count; ++i) {
    slod_attribute_stream s;
    slod_attribute_stream_init(&s);
    EXPECT_EQ(slod_level_attribute_get(c.ctx, chain, level, i, &s), SLOD_OK) << c.message();
    EXPECT_EQ(s.count, d.vertex_count);
    EXPECT_EQ(s.stride, s.component_count * sizeof(float));
    out.emplace_back(int(s.kind), s.set, std::vector<float>(s.data, s.data + s.count * s.component_count));
  }
  return out;
}

}  // namespace

TEST(CapiAttributes, LevelZeroReturnsTheInputStreamsExactly) {
  Context c;
  TexturedGrid g(16);
  const slod_chain chain = build(c, g.desc);
  ASSERT_NE(chain, SLOD_NULL_CHAIN);
  slod_level_data d;
  slod_level_data_init(&d);
  ASSERT_EQ(slod_level_get(c.ctx, chain, 0, &d), SLOD_OK);
  ASSERT_EQ(d.vertex_count, g.vertices.size());
  ASSERT_EQ(d.attribute_count, 5u);
  const Mesh m = g.mesh();
  const auto streams = levelStreams(c, chain, 0, d);
  const std::vector<std::pair<int, uint32_t>> order = {
      {SLOD_ATTRIBUTE_NORMAL, 0}, {SLOD_ATTRIBUTE_COLOR, 0}, {SLOD_ATTRIBUTE_UV, 0}, {SLOD_ATTRIBUTE_UV, 1}, {SLOD_ATTRIBUTE_TANGENT4, 0}};
  for (size_t i = 0; i < order.size(); ++i) {
    EXPECT_EQ(std::get<0>(streams[i]), order[i].first);
    EXPECT_EQ(std::get<1>(streams[i]), order[i].second);
    EXPECT_EQ(std::get<2>(streams[i]), expectedStream(m, slod_attribute_kind(order[i].first), order[i].second)) << "stream " << i;
  }
  // the colour came in as RGBA with alpha 1 and goes out as RGB
  EXPECT_EQ(std::get<2>(streams[1])[3], g.vertices[1].color[0]);
  EXPECT_EQ(std::vector<uint32_t>(d.triangles, d.triangles + 3 * d.triangle_count), g.indices);
  ASSERT_EQ(d.range_count, 2u);
  for (int r = 0; r < 2; ++r) {
    EXPECT_EQ(d.ranges[r].first_index, g.ranges[r].first_index);
    EXPECT_EQ(d.ranges[r].index_count, g.ranges[r].index_count);
    EXPECT_EQ(d.ranges[r].material, g.ranges[r].material);
    EXPECT_EQ(d.ranges[r].source_range, uint32_t(r));
  }
  ASSERT_NE(d.source_vertex, nullptr);
  for (uint32_t v = 0; v < d.vertex_count; ++v) ASSERT_EQ(d.source_vertex[v], v);
  ASSERT_NE(d.joints, nullptr);
  ASSERT_NE(d.weights, nullptr);
  for (uint32_t v = 0; v < d.vertex_count; ++v)
    for (int k = 0; k < 4; ++k) {
      ASSERT_EQ(d.joints[4 * v + k], g.vertices[v].joints[k]);
      ASSERT_EQ(d.weights[4 * v + k], g.vertices[v].weights[k]);
    }
  EXPECT_EQ(d.joint_count, 3u);
  ASSERT_NE(d.joint_parents, nullptr);
  EXPECT_EQ(std::vector<int32_t>(d.joint_parents, d.joint_parents + 3), g.joint_parents);
  // past the last stream
  slod_attribute_stream s;
  slod_attribute_stream_init(&s);
  EXPECT_EQ(slod_level_attribute_get(c.ctx, chain, 0, 5, &s), SLOD_ERROR_NOT_FOUND);
  EXPECT_NE(c.message().find("level 0 has 5 attribute streams, not stream 5"), std::string::npos) << c.message();
}

namespace {

// every level of a chain built through the C API with `method` against the chain lodcore builds from
// the same mesh with the same parameters (`lod_method`; deterministic)
void checkLevelsAgainstLodcore(slod_method method, LodMethod lod_method) {
  Context c;
  TexturedGrid g(24);
  const slod_chain chain = build(c, g.desc, method);
  ASSERT_NE(chain, SLOD_NULL_CHAIN);
  LodChain expected;
  ChainParams params;
  params.level_count = 4;
  params.cluster.method = lod_method;
  ASSERT_TRUE(buildChain(g.mesh(), params, expected).ok());
  ASSERT_EQ(slod_chain_level_count(c.ctx, chain), expected.levels.size());
  for (uint32_t l = 0; l < expected.levels.size(); ++l) {
    SCOPED_TRACE("level " + std::to_string(l));
    const LodLevel& level = expected.levels[l];
    const Mesh& m = level.mesh;
    slod_level_data d;
    slod_level_data_init(&d);
    ASSERT_EQ(slod_level_get(c.ctx, chain, l, &d), SLOD_OK);
    ASSERT_EQ(d.vertex_count, m.vertexCount());
    ASSERT_EQ(d.triangle_count, m.triangleCount());
    // every stream the mesh holds, no other
    size_t held = 0;
    for (const auto& [kind, set, values] : levelStreams(c, chain, l, d)) {
      EXPECT_EQ(values, expectedStream(m, slod_attribute_kind(kind), set)) << "kind " << kind << " set " << set;
      EXPECT_FALSE(values.empty());
    }
    held = size_t(!m.normals.empty()) + size_t(!m.colors.empty()) + size_t(!m.uvs.empty()) + m.extra_uvs.size() +
           size_t(!m.tangents.empty());
    EXPECT_EQ(d.attribute_count, held);
    // the geomorph targets, as the chain's level holds them (none on the last level, nor for SCROOGE)
    const LevelMorph& morph = level.morph;
    auto same = [&](const float* got, const auto& want, size_t components) {
      if (want.empty()) return got == nullptr;
      return got != nullptr && std::memcmp(got, &want[0].x, want.size() * components * sizeof(float)) == 0;
    };
    EXPECT_TRUE(same(d.morph_positions, morph.positions, 3));
    EXPECT_TRUE(same(d.morph_normals, morph.normals, 3));
    EXPECT_TRUE(same(d.morph_colors, morph.colors, 3));
    EXPECT_TRUE(same(d.morph_uvs, morph.uvs, 2));
    EXPECT_TRUE(same(d.morph_tangents, morph.tangents, 4));
    const bool last = l + 1 == expected.levels.size();
    EXPECT_EQ(d.morph_positions != nullptr, !last && lod_method != LodMethod::kScrooge);
    if (!last && lod_method != LodMethod::kScrooge) EXPECT_EQ(morph.positions.size(), m.vertexCount());
    // a textured input's simplified level returns its texture coordinates whenever the level has them
    if (l == 1 && !m.uvs.empty()) {
      bool uv = false;
      for (const auto& [kind, set, values] : levelStreams(c, chain, l, d)) uv = uv || (kind == SLOD_ATTRIBUTE_UV && set == 0);
      EXPECT_TRUE(uv);
    }
    // the same triangles with the same groups, sorted into one range per group still present
    std::multiset<std::tuple<uint32_t, uint32_t, uint32_t, uint32_t>> want, got;
    for (size_t t = 0; t < m.triangleCount(); ++t)
      want.insert({m.triangleGroup(t), m.triangles[3 * t], m.triangles[3 * t + 1], m.triangles[3 * t + 2]});
    if (!m.triangle_groups.empty()) {
      std::set<uint32_t> groups(m.triangle_groups.begin(), m.triangle_groups.end());
      ASSERT_EQ(d.range_count, groups.size());
      uint32_t next = 0;
      for (uint32_t r = 0; r < d.range_count; ++r) {
        const slod_index_range& range = d.ranges[r];
        EXPECT_EQ(range.first_index, next);
        next += range.index_count;
        EXPECT_TRUE(groups.count(range.source_range));
        EXPECT_EQ(range.material, g.ranges[range.source_range].material);
        for (uint32_t i = range.first_index; i < range.first_index + range.index_count; i += 3)
          got.insert({range.source_range, d.triangles[i], d.triangles[i + 1], d.triangles[i + 2]});
      }
      EXPECT_EQ(next, 3 * d.triangle_count);
      EXPECT_EQ(got, want);
    } else {
      EXPECT_EQ(d.range_count, 0u);
      EXPECT_EQ(d.ranges, nullptr);
    }
    // source vertices: level 0 the identity, other levels what the generator recorded
    const std::vector<uint32_t>& sv = l == 0 ? std::vector<uint32_t>() : level.source_vertex;
    if (l > 0 && sv.empty()) {
      EXPECT_EQ(d.source_vertex, nullptr);
    }
    for (size_t v = 0; v < sv.size(); ++v) EXPECT_EQ(d.source_vertex[v], sv[v]);
    // skins: present as the level holds them, joints below the joint count, weights summing to 1
    EXPECT_EQ(d.joints != nullptr, !m.joints.empty());
    EXPECT_EQ(d.weights != nullptr, !m.weights.empty());
    for (size_t v = 0; d.joints && v < m.vertexCount(); ++v) {
      float sum = 0.0f;
      for (int k = 0; k < 4; ++k) {
        EXPECT_LT(d.joints[4 * v + k], d.joint_count);
        EXPECT_EQ(d.weights[4 * v + k], m.weights[v][k]);
        sum += d.weights[4 * v + k];
      }
      EXPECT_NEAR(sum, 1.0f, 1e-4f);
    }
  }
}

}  // namespace

TEST(CapiAttributes, EveryLevelReturnsWhatItsMeshHolds) {
  ChainParams floating;  // the C API's SLOD_METHOD_FLOATING: the clustering defaults
  const std::pair<slod_method, LodMethod> methods[] = {{SLOD_METHOD_FLOATING, floating.cluster.method},
                                                       {SLOD_METHOD_UNIFORM, LodMethod::kUniform},
                                                       {SLOD_METHOD_ZHANG, LodMethod::kZhang},
                                                       {SLOD_METHOD_SCROOGE, LodMethod::kScrooge}};
  for (const auto& [method, lod_method] : methods) {
    SCOPED_TRACE("method " + std::to_string(int(method)));
    checkLevelsAgainstLodcore(method, lod_method);
  }
}

// a 1.1 caller's slod_level_data ends before the geomorph fields: nothing is written past it
TEST(CapiAttributes, CallersBeforeGeomorphsGetNothingPastTheirStruct) {
  Context c;
  TexturedGrid g(16);
  const slod_chain chain = build(c, g.desc);
  ASSERT_NE(chain, SLOD_NULL_CHAIN);
  struct {
    slod_level_data d;
    unsigned char guard[8];
  } out;
  std::memset(&out, 0xab, sizeof out);
  out.d.size = uint32_t(offsetof(slod_level_data, morph_positions));
  ASSERT_EQ(slod_level_get(c.ctx, chain, 0, &out.d), SLOD_OK);
  EXPECT_GT(out.d.vertex_count, 0u);
  const unsigned char* tail = reinterpret_cast<const unsigned char*>(&out.d) + offsetof(slod_level_data, morph_positions);
  for (size_t i = 0; i < sizeof out - offsetof(slod_level_data, morph_positions); ++i) ASSERT_EQ(tail[i], 0xab) << i;
  slod_level_data now;
  slod_level_data_init(&now);
  ASSERT_EQ(slod_level_get(c.ctx, chain, 0, &now), SLOD_OK);
  EXPECT_NE(now.morph_positions, nullptr);
}

TEST(CapiAttributes, MeshWithoutAttributesReturnsNone) {
  Context c;
  TexturedGrid g(8);
  slod_mesh_desc plain;
  slod_mesh_desc_init(&plain);
  plain.positions = g.desc.positions;
  plain.position_stride = g.desc.position_stride;
  plain.vertex_count = g.desc.vertex_count;
  plain.indices = g.desc.indices;
  plain.index_count = g.desc.index_count;
  const slod_chain chain = build(c, plain);
  ASSERT_NE(chain, SLOD_NULL_CHAIN);
  slod_level_data d;
  slod_level_data_init(&d);
  ASSERT_EQ(slod_level_get(c.ctx, chain, 1, &d), SLOD_OK);
  EXPECT_EQ(d.range_count, 0u);
  EXPECT_EQ(d.joints, nullptr);
  EXPECT_EQ(d.joint_parents, nullptr);
  EXPECT_EQ(d.attribute_count, d.normals ? 1u : 0u);  // the levels' own normals, if the generator makes them
}

namespace {

// builds g's mesh after `edit` and expects `status` with `text` (and the mesh's name) in the message
void expectRefused(std::function<void(TexturedGrid&)> edit, slod_status status, const std::string& text) {
  Context c;
  TexturedGrid g(4);
  edit(g);
  slod_chain chain = SLOD_NULL_CHAIN;
  const slod_chain_desc cd = chainDesc();
  EXPECT_EQ(slod_chain_build(c.ctx, &g.desc, &cd, &chain), status) << c.message();
  EXPECT_NE(c.message().find("textured grid"), std::string::npos) << c.message();
  EXPECT_NE(c.message().find(text), std::string::npos) << c.message();
  EXPECT_EQ(slod_chain_count(c.ctx), 0u);
}

}  // namespace

TEST(CapiAttributes, ShortStreamsAndSkinsAreRefused) {
  expectRefused([](TexturedGrid& g) { g.streams[1].count = 24; }, SLOD_ERROR_INVALID_MESH,
                "attributes[1] (UV set 1): holds 24 vertices for 25");
  expectRefused([](TexturedGrid& g) { g.desc.skin_count = 3; }, SLOD_ERROR_INVALID_MESH,
                "the skin (joints, weights) holds 3 vertices for 25");
  expectRefused([](TexturedGrid& g) { g.streams[2].data = nullptr; }, SLOD_ERROR_INVALID_ARGUMENT, "attributes[2] (NORMAL): data is null");
  expectRefused([](TexturedGrid& g) { g.desc.weights = nullptr; }, SLOD_ERROR_INVALID_ARGUMENT, "joints without weights");
  expectRefused([](TexturedGrid& g) { g.desc.joint_count = 0; }, SLOD_ERROR_INVALID_ARGUMENT, "joint_count is 0");
}

TEST(CapiAttributes, NanUvsWeightsAndBadSkinsAreRefused) {
  expectRefused([](TexturedGrid& g) { g.vertices[7].uv0[1] = std::nanf(""); }, SLOD_ERROR_INVALID_MESH,
                "attributes[0] (UV set 0): vertex 7 has a NaN or infinite value");
  expectRefused([](TexturedGrid& g) { g.vertices[3].weights[2] = std::nanf(""); }, SLOD_ERROR_INVALID_MESH,
                "skin weights: vertex 3 has a NaN or infinite value");
  expectRefused([](TexturedGrid& g) { g.vertices[5].joints[1] = 3; }, SLOD_ERROR_INVALID_MESH,
                "skin joints: vertex 5 uses joint 3 but joint_count is 3");
  expectRefused([](TexturedGrid& g) { g.vertices[9].weights[0] = g.vertices[9].weights[1] = 0.0f; }, SLOD_ERROR_INVALID_MESH,
                "skin weights: vertex 9 has a negative weight or weights summing to 0");
  expectRefused([](TexturedGrid& g) { g.joint_parents[0] = 2; }, SLOD_ERROR_INVALID_MESH, "joint parents form a cycle");
  expectRefused([](TexturedGrid& g) { g.vertices[4].tangent[3] = 0.5f; }, SLOD_ERROR_INVALID_MESH, "tangent sign");
}

TEST(CapiAttributes, BadRangesAreRefused) {
  expectRefused([](TexturedGrid& g) { g.ranges[1].first_index -= 6; }, SLOD_ERROR_INVALID_MESH,
                "ranges[1] [42, 90) overlaps ranges[0] [0, 48)");
  expectRefused([](TexturedGrid& g) { g.ranges[1].index_count += 3; }, SLOD_ERROR_INVALID_MESH,
                "ranges[1] [48, 99) is out of bounds of the 96 indices");
  expectRefused([](TexturedGrid& g) { g.ranges[0].index_count -= 6; }, SLOD_ERROR_INVALID_MESH, "indices [42, 48) are in no range");
  expectRefused([](TexturedGrid& g) { g.ranges[1].index_count -= 6; }, SLOD_ERROR_INVALID_MESH, "indices [90, 96) are in no range");
  expectRefused([](TexturedGrid& g) { g.ranges[1].first_index += 1; }, SLOD_ERROR_INVALID_MESH, "(multiples of 3)");
  expectRefused([](TexturedGrid& g) { g.ranges[1].first_index = 0xfffffffcu; }, SLOD_ERROR_INVALID_MESH, "out of bounds");
  expectRefused([](TexturedGrid& g) { g.desc.ranges = nullptr; }, SLOD_ERROR_INVALID_ARGUMENT, "ranges is null but range_count is 2");
}

TEST(CapiAttributes, BadStreamDescriptionsAreRefused) {
  expectRefused([](TexturedGrid& g) { g.streams[4].kind = SLOD_ATTRIBUTE_GENERIC; }, SLOD_ERROR_UNSUPPORTED,
                "attributes[4] (GENERIC): generic streams are not supported yet");
  expectRefused([](TexturedGrid& g) { g.streams[1].set = 2; }, SLOD_ERROR_INVALID_ARGUMENT, "UV set 1 is missing below set 2");
  expectRefused([](TexturedGrid& g) { g.streams[1].set = 0; }, SLOD_ERROR_INVALID_ARGUMENT,
                "attributes[1] (UV set 0): a second stream of this kind and set");
  expectRefused([](TexturedGrid& g) { g.streams[2].component_count = 4; }, SLOD_ERROR_INVALID_ARGUMENT,
                "attributes[2] (NORMAL): component_count is 4, expected 3");
  expectRefused([](TexturedGrid& g) { g.streams[4].set = 1; }, SLOD_ERROR_INVALID_ARGUMENT, "only UV streams have sets");
  expectRefused([](TexturedGrid& g) { g.streams[0].stride = 4; }, SLOD_ERROR_INVALID_ARGUMENT, "stride 4 is below its 8 bytes");
  expectRefused([](TexturedGrid& g) { g.vertices[2].color[3] = 0.5f; }, SLOD_ERROR_UNSUPPORTED,
                "vertex 2 has alpha 0.5");
  expectRefused([](TexturedGrid& g) { g.streams[3].size = 12; }, SLOD_ERROR_INVALID_ARGUMENT,
                "attributes[3].size is 12, attributes[0].size");
  expectRefused([](TexturedGrid& g) { g.streams[0].size = 4; }, SLOD_ERROR_INVALID_ARGUMENT, "attributes[0].size is 4, below its smallest size");
  expectRefused([](TexturedGrid& g) { std::memcpy(&g.streams[2].kind, "\x09\0\0\0", 4); }, SLOD_ERROR_INVALID_ARGUMENT, "unknown kind 9");
}

TEST(CapiAttributes, NewerCallersLongerStreamsAreReadAsFarAsKnown) {
  // a newer header's stream: one more field at the end, the array stepped by its size
  struct NewerStream {
    slod_attribute_stream s;
    double future;
  };
  Context c;
  TexturedGrid g(4);
  std::vector<NewerStream> newer(5);
  for (int i = 0; i < 5; ++i) {
    newer[i].s = g.streams[i];
    newer[i].s.size = sizeof(NewerStream);
    newer[i].future = std::nan("");
  }
  g.desc.attributes = &newer[0].s;
  const slod_chain chain = build(c, g.desc);
  ASSERT_NE(chain, SLOD_NULL_CHAIN);
  slod_level_data d;
  slod_level_data_init(&d);
  ASSERT_EQ(slod_level_get(c.ctx, chain, 0, &d), SLOD_OK);
  EXPECT_EQ(d.attribute_count, 5u);
  // and an output stream written at a newer caller's size leaves its extra field alone
  NewerStream out;
  out.future = 42.0;
  slod_attribute_stream_init(&out.s);
  out.s.size = sizeof(NewerStream);
  ASSERT_EQ(slod_level_attribute_get(c.ctx, chain, 0, 2, &out.s), SLOD_OK);
  EXPECT_EQ(out.s.kind, SLOD_ATTRIBUTE_UV);
  EXPECT_EQ(out.s.size, sizeof(NewerStream));
  EXPECT_EQ(out.future, 42.0);
}

TEST(CapiAttributes, RecordingsKeepTheAttributesInTheirPack) {
  Context c;
  TexturedGrid g(8);
  const slod_chain chain = build(c, g.desc);
  slod_object_desc od;
  slod_object_desc_init(&od);
  od.chain = chain;
  slod_object object;
  ASSERT_EQ(slod_object_add(c.ctx, &od, &object), SLOD_OK) << c.message();
  const std::string dir = ::testing::TempDir();
  const std::string replay = dir + "capi_attributes.jsonl", pack_path = dir + "capi_attributes.slodpack";
  ASSERT_EQ(slod_record_start(c.ctx, replay.c_str(), pack_path.c_str()), SLOD_OK) << c.message();
  ASSERT_EQ(slod_record_stop(c.ctx), SLOD_OK) << c.message();
  scene::Pack pack;
  const Error e = scene::Pack::load(pack_path, pack);
  ASSERT_TRUE(e.ok()) << e.message;
  ASSERT_EQ(pack.chainCount(), 1u);
  ASSERT_EQ(pack.levelCount(0), slod_chain_level_count(c.ctx, chain));
  // the recording keeps the context's order (no reordering): level 0 is the input
  const scene::PackLevelView v = pack.level(0, 0);
  const Mesh m = g.mesh();
  EXPECT_EQ(std::vector<glm::vec2>(v.uvs.begin(), v.uvs.end()), m.uvs);
  EXPECT_EQ(std::vector<glm::vec2>(v.extra_uvs.begin(), v.extra_uvs.end()), m.extra_uvs[0]);
  EXPECT_EQ(std::vector<glm::vec4>(v.tangents.begin(), v.tangents.end()), m.tangents);
  EXPECT_EQ(std::vector<glm::vec4>(v.weights.begin(), v.weights.end()), m.weights);
  EXPECT_EQ(std::vector<int32_t>(v.joint_parents.begin(), v.joint_parents.end()), g.joint_parents);
  EXPECT_EQ(std::vector<uint32_t>(v.triangle_groups.begin(), v.triangle_groups.end()), m.triangle_groups);
  // every simplified level as the context hands it out: skin, source vertices, texture coordinates
  for (uint32_t l = 1; l < pack.levelCount(0); ++l) {
    const scene::PackLevelView pl = pack.level(0, l);
    slod_level_data d;
    slod_level_data_init(&d);
    ASSERT_EQ(slod_level_get(c.ctx, chain, l, &d), SLOD_OK);
    ASSERT_EQ(pl.positions.size(), d.vertex_count);
    EXPECT_EQ(pl.source_vertex.empty(), d.source_vertex == nullptr);
    EXPECT_TRUE(std::equal(pl.source_vertex.begin(), pl.source_vertex.end(), d.source_vertex));
    EXPECT_EQ(pl.weights.empty(), d.weights == nullptr);
    EXPECT_TRUE(pl.weights.empty() || std::memcmp(pl.weights.data, d.weights, 16 * d.vertex_count) == 0);
    EXPECT_EQ(pl.triangles.size(), 3 * size_t(d.triangle_count));
    EXPECT_TRUE(std::equal(pl.triangles.begin(), pl.triangles.end(), d.triangles));
  }
}

TEST(CapiAttributes, FileChainsHaveOneRangePerMaterial) {
  SCENELOD_REQUIRE_SHARED_MODELS();
  // four meshes, one material each: the flattened chain's groups are the materials
  const std::string file = test::sharedModelsDir() + "/SheenChair/SheenChair.gltf";
  Context c;
  slod_chain chain = SLOD_NULL_CHAIN;
  const slod_chain_desc cd = chainDesc();
  ASSERT_EQ(slod_chain_load_file(c.ctx, file.c_str(), &cd, &chain), SLOD_OK) << c.message();
  for (uint32_t l = 0; l < slod_chain_level_count(c.ctx, chain); ++l) {
    SCOPED_TRACE("level " + std::to_string(l));
    slod_level_data d;
    slod_level_data_init(&d);
    ASSERT_EQ(slod_level_get(c.ctx, chain, l, &d), SLOD_OK);
    if (l == 0) {
      EXPECT_EQ(d.range_count, 4u);
      EXPECT_EQ(d.triangle_count, 39936u);
    }
    uint32_t next = 0;
    for (uint32_t r = 0; r < d.range_count; ++r) {
      EXPECT_EQ(d.ranges[r].first_index, next);
      EXPECT_EQ(d.ranges[r].material, d.ranges[r].source_range);
      EXPECT_LT(d.ranges[r].material, 6u);
      EXPECT_GT(d.ranges[r].index_count, 0u);
      next += d.ranges[r].index_count;
    }
    EXPECT_EQ(next, d.range_count ? 3 * d.triangle_count : 0u);
  }
}
