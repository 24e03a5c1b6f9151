// The C API driven by the input: a context with a bounded capacity, then a sequence of calls chosen
// and filled from the bytes (chain builds from a small mesh with arbitrary floats and indices and
// optional attribute streams, skin and index ranges of arbitrary kinds, counts, strides and values,
// object add/move/remove with arbitrary numbers and handles, selections with arbitrary cameras,
// frame params, strides and capacities, levels and their streams read back and walked, chain
// destruction). Every call must return a known status.
#include <cstdlib>
#include <cstring>
#include <vector>

#include "fuzz_input.h"
#include "scenelod/scenelod.h"

namespace {

using scenelod::fuzz::Cursor;

constexpr size_t kMaxHandles = 8;
constexpr int kMaxChainBuilds = 3;
constexpr int kMaxCalls = 64;

void check(slod_status s) {
  if (static_cast<unsigned>(s) > SLOD_ERROR_IN_USE) std::abort();
}

// a handle the context gave out (often), or arbitrary bits (stale, forged, null)
uint64_t pickHandle(Cursor& in, const std::vector<uint64_t>& known) {
  uint8_t b = in.byte();
  if (!known.empty() && b < 224) return known[b % known.size()];
  return b % 2 ? in.u64() : 0;
}

void remember(std::vector<uint64_t>& known, uint64_t h) {
  if (known.size() < kMaxHandles) known.push_back(h);
  else known[h % kMaxHandles] = h;
}

// a struct size: the right one mostly, sometimes too small or larger (another caller version)
uint32_t structSize(Cursor& in, uint32_t right) {
  uint8_t b = in.byte();
  if (b < 240) return right;
  return b % 2 ? static_cast<uint32_t>(b % 16) : right + 8;
}

// Caller memory for a mesh's attributes: every stream holds the count it claims at its stride.
struct Attributes {
  std::vector<slod_attribute_stream> streams;
  std::vector<std::vector<float>> stream_data;
  std::vector<uint16_t> joints;
  std::vector<float> weights;
  std::vector<int32_t> parents;
  std::vector<slod_index_range> ranges;
};

void fillAttributes(Cursor& in, size_t vertex_count, size_t index_count, Attributes& a, slod_mesh_desc& mesh) {
  const size_t stream_count = in.byte() % 5;
  a.streams.resize(stream_count);
  a.stream_data.resize(stream_count);
  for (size_t i = 0; i < stream_count; ++i) {
    slod_attribute_stream& s = a.streams[i];
    slod_attribute_stream_init(&s);
    int kind = in.byte() % 6;  // 5 is none of the kinds
    std::memcpy(&s.kind, &kind, sizeof kind);
    s.set = in.byte() % 3;
    s.component_count = 1 + in.byte() % 4;
    s.stride = in.byte() < 200 ? 0 : (s.component_count + in.byte() % 2) * sizeof(float);
    s.count = vertex_count - (in.byte() < 240 ? 0 : 1);
    const size_t floats_per_vertex = s.stride ? s.stride / sizeof(float) : s.component_count;
    a.stream_data[i].resize(floats_per_vertex * s.count + 1);
    for (float& f : a.stream_data[i]) f = in.byte() < 224 ? static_cast<float>(in.byte() % 3) : in.f32();
    s.data = a.stream_data[i].data();
  }
  mesh.attributes = stream_count ? a.streams.data() : nullptr;
  mesh.attribute_count = static_cast<uint32_t>(stream_count);
  if (in.byte() < 128) {
    mesh.joint_count = in.byte() % 5;
    a.joints.resize(4 * vertex_count);
    a.weights.resize(4 * vertex_count);
    for (uint16_t& j : a.joints) j = in.byte() % 6;
    for (float& w : a.weights) w = in.byte() < 240 ? static_cast<float>(in.byte() % 3) : in.f32();
    mesh.joints = a.joints.data();
    mesh.weights = a.weights.data();
    mesh.skin_count = vertex_count;
    a.parents.resize(mesh.joint_count);
    for (int32_t& p : a.parents) p = static_cast<int32_t>(in.byte() % 6) - 1;
    mesh.joint_parents = in.byte() < 128 ? a.parents.data() : nullptr;
  }
  if (in.byte() < 128) {
    a.ranges.resize(1 + in.byte() % 3);
    for (slod_index_range& r : a.ranges) {
      r.first_index = in.byte() < 240 ? 3u * (in.byte() % 8) : in.u32();
      r.index_count = in.byte() < 240 ? 3u * (in.byte() % 8) : in.u32();
      r.material = in.u32();
    }
    if (index_count >= 3) a.ranges[0] = slod_index_range{0, static_cast<uint32_t>(index_count / 3 * 3), 1, 0};
    mesh.ranges = a.ranges.data();
    mesh.range_count = static_cast<uint32_t>(a.ranges.size());
  }
}

struct State {
  slod_context* ctx = nullptr;
  std::vector<uint64_t> chains;
  std::vector<uint64_t> objects;
  int chain_builds = 0;
};

void buildChain(Cursor& in, State& st) {
  if (st.chain_builds++ >= kMaxChainBuilds) return;
  size_t vertex_count = 3 + in.byte() % 14;
  std::vector<float> positions(vertex_count * 3);
  for (float& p : positions) p = in.byte() < 200 ? static_cast<float>(in.byte() % 16) : in.f32();
  size_t triangles = 1 + in.byte() % 16;
  std::vector<uint32_t> indices(triangles * 3);
  for (uint32_t& i : indices) {
    uint8_t b = in.byte();
    i = b < 250 ? b % vertex_count : in.u32();
  }
  slod_mesh_desc mesh;
  slod_mesh_desc_init(&mesh);
  mesh.size = structSize(in, mesh.size);
  mesh.positions = positions.data();
  mesh.vertex_count = vertex_count;
  mesh.position_stride = in.byte() < 240 ? 0 : 12;
  mesh.indices = indices.data();
  mesh.index_count = indices.size() - (in.byte() < 240 ? 0 : 1);
  mesh.name = "fuzz";
  Attributes attributes;
  if (in.byte() < 160) fillAttributes(in, vertex_count, mesh.index_count, attributes, mesh);
  slod_chain_desc desc;
  slod_chain_desc_init(&desc);
  desc.size = structSize(in, desc.size);
  // as a C caller can: any int in the enum field (4 is none of its values)
  int method = in.byte() % 5;
  std::memcpy(&desc.method, &method, sizeof(method));
  desc.level_count = in.byte() % 5;
  desc.first_cell_width = in.byte() < 128 ? 0.0f : in.f32();
  slod_chain chain = SLOD_NULL_CHAIN;
  slod_status s = slod_chain_build(st.ctx, &mesh, &desc, &chain);
  check(s);
  if (s == SLOD_OK) remember(st.chains, chain);
}

void addObject(Cursor& in, State& st) {
  slod_object_desc desc;
  slod_object_desc_init(&desc);
  desc.size = structSize(in, desc.size);
  desc.chain = pickHandle(in, st.chains);
  if (in.byte() >= 128) {
    for (float& t : desc.translation) t = in.f32();
    for (float& r : desc.rotation) r = in.f32();
    desc.scale = in.f32();
    desc.importance = in.f32();
  }
  desc.must_draw = in.byte() % 2;
  desc.user_data = in.u64();
  slod_object object = SLOD_NULL_OBJECT;
  slod_status s = slod_object_add(st.ctx, &desc, &object);
  check(s);
  if (s == SLOD_OK) remember(st.objects, object);
}

void moveObject(Cursor& in, State& st) {
  uint64_t object = pickHandle(in, st.objects);
  float t[3], r[4];
  for (float& v : t) v = in.f32();
  for (float& v : r) v = in.f32();
  float scale = in.f32();
  check(slod_object_set_trs(st.ctx, object, in.byte() < 250 ? t : nullptr, r, scale));
  check(slod_object_set_importance(st.ctx, object, in.f32()));
}

void select(Cursor& in, State& st) {
  slod_camera camera;
  slod_camera_init(&camera);
  camera.size = structSize(in, camera.size);
  if (in.byte() >= 64) {
    for (float& v : camera.eye) v = in.f32();
    for (float& v : camera.target) v = in.f32();
    for (float& v : camera.up) v = in.f32();
    camera.fov_y_deg = in.f32();
    camera.viewport_width = in.u32() % 5000;
    camera.viewport_height = in.u32() % 5000;
  }
  slod_frame_params params;
  slod_frame_params_init(&params);
  params.size = structSize(in, params.size);
  if (in.byte() >= 128) {
    params.budget_ms = in.f32();
    params.pixels_per_cell = in.f32();
  }
  static const size_t kStrides[] = {sizeof(slod_selection), 8, 12, 16, sizeof(slod_selection) + 8, 0, 4};
  size_t stride = kStrides[in.byte() % 7];
  size_t capacity = in.byte() % 12;
  std::vector<unsigned char> out(stride * capacity + 1);
  slod_frame_result result;
  slod_frame_result_init(&result);
  result.size = structSize(in, result.size);
  bool with_result = in.byte() < 240;
  slod_status s = slod_select(st.ctx, &camera, &params, out.data(), stride, capacity,
                              with_result ? &result : nullptr);
  check(s);
  if (s == SLOD_OK && with_result) check(slod_report_frame_time(st.ctx, result.frame, in.f32()));
}

// a level and all its streams read back, every array walked as an engine uploading it would
void readLevel(Cursor& in, State& st) {
  const uint64_t chain = pickHandle(in, st.chains);
  const uint32_t level = in.byte() % 6;
  slod_level_data d;
  slod_level_data_init(&d);
  d.size = structSize(in, d.size);
  slod_status s = slod_level_get(st.ctx, chain, level, &d);
  check(s);
  if (s != SLOD_OK || d.size < sizeof d) return;
  volatile float sum = 0.0f;
  for (uint32_t r = 0; r < d.range_count; ++r)
    for (uint32_t i = d.ranges[r].first_index; i < d.ranges[r].first_index + d.ranges[r].index_count; ++i)
      sum = sum + d.positions[3 * d.triangles[i]];
  for (uint32_t v = 0; v < d.vertex_count; ++v) {
    if (d.source_vertex) sum = sum + static_cast<float>(d.source_vertex[v] % 7);
    for (int k = 0; k < 4 && d.joints; ++k) sum = sum + d.weights[4 * v + k] + (d.joints[4 * v + k] < d.joint_count ? 0.0f : 1.0f);
  }
  for (uint32_t j = 0; j < d.joint_count && d.joint_parents; ++j) sum = sum + static_cast<float>(d.joint_parents[j]);
  for (uint32_t i = 0; i <= d.attribute_count; ++i) {
    slod_attribute_stream a;
    slod_attribute_stream_init(&a);
    s = slod_level_attribute_get(st.ctx, chain, level, i, &a);
    check(s);
    if (s != SLOD_OK) continue;
    for (size_t v = 0; v < a.count * a.component_count; ++v) sum = sum + a.data[v];
  }
}

void step(Cursor& in, State& st) {
  switch (in.byte() % 7) {
    case 0: buildChain(in, st); break;
    case 1: addObject(in, st); break;
    case 2: moveObject(in, st); break;
    case 3: check(slod_object_remove(st.ctx, pickHandle(in, st.objects))); break;
    case 4: select(in, st); break;
    case 5: readLevel(in, st); break;
    default: check(slod_chain_destroy(st.ctx, pickHandle(in, st.chains))); break;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Cursor in(data, size);
  slod_context_desc cd;
  slod_context_desc_init(&cd);
  cd.size = structSize(in, cd.size);
  cd.max_objects = in.byte() % 33;
  State st;
  slod_status s = slod_context_create(&cd, &st.ctx);
  check(s);
  if (s != SLOD_OK) return 0;
  for (int i = 0; i < kMaxCalls && !in.empty(); ++i) step(in, st);
  // a frame after everything, so that the last moves and removals reach the selector
  slod_camera camera;
  slod_camera_init(&camera);
  slod_frame_params params;
  slod_frame_params_init(&params);
  std::vector<slod_selection> out(cd.max_objects + 1);
  check(slod_select(st.ctx, &camera, &params, out.data(), sizeof(slod_selection), out.size(), nullptr));
  slod_context_destroy(st.ctx);
  return 0;
}
