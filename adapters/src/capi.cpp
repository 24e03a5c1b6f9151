// The C API (scenelod.h) over the C++ libraries. Every entry point catches everything: bad_alloc
// becomes SLOD_ERROR_OUT_OF_MEMORY, anything else SLOD_ERROR_UNKNOWN; the status and message are kept
// on the context and passed to its error callback.
//
// Objects live in a selection::ReplayScene (one root node per object), so that the selection a
// context makes and the one `scenelod replay` makes from its recording run through the same code:
// the same local matrices (applyMoves), the same world spheres, the same selector configuration.
#include "scenelod/scenelod.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <iterator>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "scenelod/lodcore/chain.h"
#include "scenelod/lodcore/mesh.h"
#include "scenelod/scene/bounding_sphere.h"
#include "scenelod/scene/gltf_io.h"
#include "scenelod/scene/pack.h"
#include "scenelod/selection/level_table.h"
#include "scenelod/selection/replay.h"
#include "scenelod/selection/replay_scene.h"
#include "scenelod/selection/selector.h"
#include "scenelod/selection/visibility.h"

using namespace scenelod;

namespace {

// Handles of a dense array kept compact by swap-remove: slot + 1 in the low 32 bits (0 stays null),
// the slot's generation in the next 31 and the kind of handle (object or chain) in the top bit, so a
// removed element's handle, or another kind's, is refused even after its slot is reused.
struct SlotMap {
  static constexpr uint64_t kKindBit = uint64_t{1} << 63;
  static constexpr uint32_t kGenerationMask = 0x7fffffffu;

  explicit SlotMap(uint64_t kind_bit) : kind(kind_bit) {}

  uint64_t kind;                     // 0 or kKindBit
  std::vector<uint32_t> generation;  // per slot
  std::vector<uint32_t> dense;       // per slot: dense index, UINT32_MAX when free
  std::vector<uint32_t> slot_of;     // per dense index
  std::vector<uint32_t> free_slots;

  uint64_t handle(uint32_t d) const {
    const uint32_t slot = slot_of[d];
    return kind | (static_cast<uint64_t>(generation[slot] & kGenerationMask) << 32) | (static_cast<uint64_t>(slot) + 1);
  }
  bool resolve(uint64_t h, uint32_t& d) const {
    const uint64_t low = h & 0xffffffffu;
    if (low == 0 || (h & kKindBit) != kind) return false;
    const uint32_t slot = static_cast<uint32_t>(low - 1);
    if (slot >= generation.size() || (generation[slot] & kGenerationMask) != ((h >> 32) & kGenerationMask)) return false;
    d = dense[slot];
    return d != UINT32_MAX;
  }
  // Gives the next dense index (slot_of.size()) a handle.
  uint64_t add() {
    uint32_t slot;
    if (!free_slots.empty()) {
      slot = free_slots.back();
      free_slots.pop_back();
    } else {
      slot = static_cast<uint32_t>(generation.size());
      generation.push_back(1);
      dense.push_back(UINT32_MAX);
    }
    dense[slot] = static_cast<uint32_t>(slot_of.size());
    slot_of.push_back(slot);
    return handle(dense[slot]);
  }
  // Frees dense index d's handle; the last dense index moves to d, as the caller's arrays do.
  void remove(uint32_t d) {
    const uint32_t slot = slot_of[d], last = static_cast<uint32_t>(slot_of.size() - 1);
    slot_of[d] = slot_of[last];
    slot_of.pop_back();
    if (d != last) dense[slot_of[d]] = d;
    dense[slot] = UINT32_MAX;
    generation[slot]++;
    free_slots.push_back(slot);
  }
};

// Moves v's last element to index i and drops the last.
template <class V>
void swapPop(V& v, size_t i) {
  if (i + 1 < v.size()) v[i] = std::move(v.back());
  v.pop_back();
}

// What slod_level_get hands out beside a chain's meshes: the index ranges of every level (triangles
// sorted by group, one range per group run) and level 0's identity source_vertex.
struct ChainOutputs {
  std::vector<std::vector<slod_index_range>> ranges;  // per level
  std::vector<uint32_t> identity;                     // 0 .. level 0's vertex count - 1
  uint32_t joint_count = 0;
};

}  // namespace

struct slod_context {
  slod_context_desc desc{};
  slod_status last_status = SLOD_OK;
  std::string last_message;

  std::vector<LodChain> chains;            // per dense chain index (= level table chain id)
  std::vector<ChainOutputs> outputs;       // per dense chain index
  SlotMap chain_handles{SlotMap::kKindBit};
  selection::ReplayScene objects;          // node i = object i (roots), chain spheres per chain
  SlotMap object_handles{0};
  std::vector<uint64_t> user_data;         // per object

  std::vector<glm::vec3> centers;
  std::vector<float> radii, scales;
  std::vector<int8_t> levels;
  std::vector<int8_t> previous_levels;  // transitions (slod_select)
  std::vector<float> morph, fade;
  std::vector<selection::View> views;  // slod_select_views' (capacity kept: no allocation after the first frame)
  bool spheres_dirty = true;

  selection::SelectorContext* selector = nullptr;
  size_t selector_rows = 0, selector_levels = 0;

  std::unique_ptr<selection::RayScene> rays;
  bool rays_chains_dirty = true;

  // recording
  bool recording = false;
  std::string replay_path;
  selection::Replay replay;
  std::vector<selection::ReplayMove> pending_moves;
  std::vector<selection::ReplayMove> move_scratch;
  uint64_t record_base = 0;                // selector frame number of the first recorded frame

  ~slod_context() { selection::destroySelectorContext(selector); }
};

namespace {

slod_status toC(Status s) {
  switch (s) {
    case Status::kOk: return SLOD_OK;
    case Status::kInvalidArgument: return SLOD_ERROR_INVALID_ARGUMENT;
    case Status::kInvalidMesh: return SLOD_ERROR_INVALID_MESH;
    case Status::kIoError: return SLOD_ERROR_IO;
    case Status::kParseError: return SLOD_ERROR_PARSE;
    case Status::kUnsupported: return SLOD_ERROR_UNSUPPORTED;
    case Status::kCorrupt: return SLOD_ERROR_CORRUPT;
    case Status::kOutOfMemory: return SLOD_ERROR_OUT_OF_MEMORY;
    case Status::kNotFound: return SLOD_ERROR_NOT_FOUND;
  }
  return SLOD_ERROR_UNKNOWN;
}

// the last failure of a call that had no context (slod_context_create), per thread
thread_local slod_status orphan_status = SLOD_OK;
thread_local std::string orphan_message;

slod_status fail(slod_context* ctx, slod_status s, const std::string& message) {
  if (!ctx) {
    orphan_status = s;
    orphan_message = message;
    return s;
  }
  ctx->last_status = s;
  ctx->last_message = message;
  if (ctx->desc.error_callback) ctx->desc.error_callback(ctx->desc.error_user, s, ctx->last_message.c_str());
  return s;
}

slod_status fail(slod_context* ctx, const Error& e) { return fail(ctx, toC(e.status), e.message); }

slod_status ok(slod_context* ctx) {
  if (ctx) ctx->last_status = SLOD_OK;
  return SLOD_OK;
}

// Runs `body` with every exception turned into a status.
template <class F>
slod_status guarded(slod_context* ctx, F&& body) {
  try {
    return body();
  } catch (const std::bad_alloc&) {
    return fail(ctx, SLOD_ERROR_OUT_OF_MEMORY, "out of memory");
  } catch (const std::exception& e) {
    return fail(ctx, SLOD_ERROR_UNKNOWN, std::string("internal error: ") + e.what());
  } catch (...) {
    return fail(ctx, SLOD_ERROR_UNKNOWN, "internal error");
  }
}

// Per size-tagged struct: its name and the smallest size accepted, the end of its first field after
// `size` (a caller's struct of any version covers it; 0 means the struct skipped its _init).
template <class T>
struct Abi;
#define SLOD_ABI(T, first_field)                                                          \
  template <>                                                                             \
  struct Abi<T> {                                                                         \
    static constexpr const char* name = #T;                                               \
    static constexpr size_t min_size = offsetof(T, first_field) + sizeof(T::first_field); \
  }
SLOD_ABI(slod_context_desc, max_objects);
SLOD_ABI(slod_mesh_desc, positions);
SLOD_ABI(slod_chain_desc, method);
SLOD_ABI(slod_level_data, cell_width);
SLOD_ABI(slod_object_desc, chain);
SLOD_ABI(slod_camera, eye);
SLOD_ABI(slod_frame_params, budget_ms);
SLOD_ABI(slod_frame_result, frame);
SLOD_ABI(slod_pick_result, object);
SLOD_ABI(slod_attribute_stream, kind);
SLOD_ABI(slod_view, eye);
#undef SLOD_ABI
constexpr size_t kSelectionMinStride = offsetof(slod_selection, object) + sizeof(slod_object);

// Checks a caller's struct (input or output): a failure naming it when it is null or its size is
// below the smallest accepted.
template <class T>
slod_status checkSize(slod_context* ctx, const char* fn, const T* p) {
  if (!p) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, std::string(fn) + ": " + Abi<T>::name + " is null");
  if (p->size < Abi<T>::min_size)
    return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT,
                std::string(fn) + ": " + Abi<T>::name + ".size is " + std::to_string(p->size) +
                    ", below its smallest size " + std::to_string(Abi<T>::min_size) + " (fill it with " +
                    Abi<T>::name + "_init)");
  return SLOD_OK;
}

// Reads a caller's struct into `out`: the bytes its size covers over the header's defaults (`init`),
// so an older caller's shorter struct gets defaults for the fields it lacks and a newer caller's
// longer one is read as far as this library knows it.
template <class T>
slod_status readStruct(slod_context* ctx, const char* fn, const T* in, void (*init)(T*), T& out) {
  if (slod_status s = checkSize(ctx, fn, in)) return s;
  init(&out);
  std::memcpy(&out, in, std::min<size_t>(in->size, sizeof(T)));
  return SLOD_OK;
}

// Writes `value` into a caller's struct that checkSize accepted: only the bytes its size covers, the
// caller's size field kept.
template <class T>
void writeStruct(T value, T* out) {
  value.size = out->size;
  std::memcpy(out, &value, std::min<size_t>(out->size, sizeof(T)));
}

bool finite(const float* v, int n) {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(v[i])) return false;
  return true;
}

selection::ReplayMove makeMove(uint32_t object, const float t[3], const float q[4], float s) {
  selection::ReplayMove m;
  m.object = object;
  m.translation = glm::vec3(t[0], t[1], t[2]);
  m.rotation = glm::quat(q[3], q[0], q[1], q[2]);
  m.scale = s;
  return m;
}

// World sphere of every object; objects are root nodes, so this is computeWorldSpheres' formula with
// the node's local matrix as its world matrix (the same float operations: replays match exactly).
void updateSpheres(slod_context* ctx) {
  const selection::ReplayScene& s = ctx->objects;
  const size_t n = s.objectCount();
  for (size_t o = 0; o < n; ++o) {
    const glm::mat4& m = s.node_local[static_cast<size_t>(s.object_node[o])];
    const Sphere& b = s.chain_bounds[s.object_chain[o]];
    const float sx = glm::length(glm::vec3(m[0])), sy = glm::length(glm::vec3(m[1])), sz = glm::length(glm::vec3(m[2]));
    const float scale = std::max(sx, std::max(sy, sz));
    ctx->centers[o] = glm::vec3(m * glm::vec4(b.center, 1.0f));
    ctx->radii[o] = b.radius * scale;
    ctx->scales[o] = scale > 0.0f ? scale : 1.0f;
  }
  ctx->spheres_dirty = false;
}

// (Re)creates the selector when the level table outgrew it, with the configuration runReplay uses.
Error ensureSelector(slod_context* ctx) {
  const size_t rows = ctx->objects.table.cell_width.size(), levels = ctx->objects.table.maxLevelsPerChain();
  if (ctx->selector && rows <= ctx->selector_rows && levels <= ctx->selector_levels) return {};
  selection::destroySelectorContext(ctx->selector);
  selection::SelectorConfig cfg;
  cfg.max_object_count = std::max<size_t>(ctx->desc.max_objects, 1);
  cfg.max_levels_per_chain = std::max<size_t>(levels, 1);
  cfg.max_level_rows = std::max<size_t>(rows, 1);
  cfg.max_view_groups = ctx->desc.max_view_groups;
  cfg.allocator.allocate = ctx->desc.allocator.allocate;
  cfg.allocator.free = ctx->desc.allocator.free;
  cfg.allocator.user = ctx->desc.allocator.user;
  ctx->selector = selection::createSelectorContext(cfg);
  ctx->selector_rows = rows;
  ctx->selector_levels = levels;
  if (!ctx->selector) return {Status::kOutOfMemory, "cannot create the selector context"};
  return {};
}

selection::Camera toCamera(const slod_camera& c) {
  selection::Camera cam;
  cam.eye = glm::vec3(c.eye[0], c.eye[1], c.eye[2]);
  cam.target = glm::vec3(c.target[0], c.target[1], c.target[2]);
  cam.up = glm::vec3(c.up[0], c.up[1], c.up[2]);
  cam.viewport_width_px = c.viewport_width;
  cam.viewport_height_px = c.viewport_height;
  // as runReplay converts the header's fov_y_deg (a double)
  cam.fov_y_rad = static_cast<float>(static_cast<double>(c.fov_y_deg) * 3.14159265358979 / 180.0);
  cam.near_plane = 0.05f;
  cam.far_plane = 1.0e6f;
  return cam;
}

// ---- slod_mesh_desc's attribute streams, skin and index ranges into a Mesh ----

const char* attributeKindName(int kind) {
  switch (kind) {
    case SLOD_ATTRIBUTE_UV: return "UV";
    case SLOD_ATTRIBUTE_COLOR: return "COLOR";
    case SLOD_ATTRIBUTE_NORMAL: return "NORMAL";
    case SLOD_ATTRIBUTE_TANGENT4: return "TANGENT4";
    case SLOD_ATTRIBUTE_GENERIC: return "GENERIC";
  }
  return "unknown kind";
}

// n vertices of Vec from caller memory `stride` bytes apart (unaligned reads), all finite
template <class Vec>
Error readVectors(const void* data, size_t stride, size_t n, const std::string& name, std::vector<Vec>& out) {
  out.resize(n);
  const char* p = static_cast<const char*>(data);
  for (size_t v = 0; v < n; ++v) {
    std::memcpy(&out[v], p + v * stride, sizeof(Vec));
    for (int c = 0; c < Vec::length(); ++c)
      if (!std::isfinite(out[v][c])) return {Status::kInvalidMesh, name + ": vertex " + std::to_string(v) + " has a NaN or infinite value"};
  }
  return {};
}

// stream i of the caller's array, whose elements are `stride` bytes apart (their common size)
Error readStream(const slod_mesh_desc& d, size_t i, uint32_t stride, const std::string& what, slod_attribute_stream& s, int& kind) {
  const char* at = reinterpret_cast<const char*>(d.attributes) + i * stride;
  uint32_t size;
  std::memcpy(&size, at, sizeof size);
  if (size != stride)
    return {Status::kInvalidArgument, what + ": attributes[" + std::to_string(i) + "].size is " + std::to_string(size) +
                                          ", attributes[0].size " + std::to_string(stride) +
                                          " (fill every stream with slod_attribute_stream_init)"};
  slod_attribute_stream_init(&s);
  std::memcpy(&s, at, std::min<size_t>(stride, sizeof s));
  // an enum field may hold any int a C caller stored: read as the int it is
  static_assert(sizeof(kind) == sizeof(s.kind), "slod_attribute_kind is stored as an int");
  std::memcpy(&kind, &s.kind, sizeof kind);
  return {};
}

// The streams of `d` into `m` (vertex count set): one per kind and set, UV sets without gaps.
Error readStreams(const slod_mesh_desc& d, const std::string& what, Mesh& m) {
  if (d.attribute_count == 0) return {};
  if (!d.attributes) return {Status::kInvalidArgument, what + ": attributes is null but attribute_count is " + std::to_string(d.attribute_count)};
  uint32_t stride;
  std::memcpy(&stride, d.attributes, sizeof stride);
  if (stride < Abi<slod_attribute_stream>::min_size)
    return {Status::kInvalidArgument, what + ": attributes[0].size is " + std::to_string(stride) + ", below its smallest size " +
                                          std::to_string(Abi<slod_attribute_stream>::min_size) + " (fill it with slod_attribute_stream_init)"};
  const size_t n = m.vertexCount();
  std::vector<std::vector<glm::vec2>> uv_sets;
  std::vector<char> uv_given;
  char kind_given[SLOD_ATTRIBUTE_TANGENT4 + 1] = {};
  for (size_t i = 0; i < d.attribute_count; ++i) {
    slod_attribute_stream s;
    int kind = 0;
    if (Error e = readStream(d, i, stride, what, s, kind); !e.ok()) return e;
    const std::string name = what + ": attributes[" + std::to_string(i) + "] (" + attributeKindName(kind) +
                             (kind == SLOD_ATTRIBUTE_UV ? " set " + std::to_string(s.set) : std::string()) + ")";
    if (kind == SLOD_ATTRIBUTE_GENERIC)
      return {Status::kUnsupported, name + ": generic streams are not supported yet; carry them through each level's "
                                           "source_vertex (slod_level_data)"};
    if (kind < SLOD_ATTRIBUTE_UV || kind > SLOD_ATTRIBUTE_TANGENT4)
      return {Status::kInvalidArgument, name + ": unknown kind " + std::to_string(kind)};
    const uint32_t expected = kind == SLOD_ATTRIBUTE_UV ? 2 : kind == SLOD_ATTRIBUTE_TANGENT4 ? 4 : 3;
    const bool rgba = kind == SLOD_ATTRIBUTE_COLOR && s.component_count == 4;
    if (s.component_count != expected && !rgba)
      return {Status::kInvalidArgument, name + ": component_count is " + std::to_string(s.component_count) + ", expected " +
                                            std::to_string(expected) + (kind == SLOD_ATTRIBUTE_COLOR ? " or 4" : "")};
    if (kind != SLOD_ATTRIBUTE_UV && s.set != 0)
      return {Status::kInvalidArgument, name + ": set is " + std::to_string(s.set) + "; only UV streams have sets"};
    if (kind == SLOD_ATTRIBUTE_UV && s.set > 64) return {Status::kInvalidArgument, name + ": more than 64 UV sets"};
    const size_t stride_bytes = s.stride ? s.stride : s.component_count * sizeof(float);
    if (stride_bytes < s.component_count * sizeof(float))
      return {Status::kInvalidArgument, name + ": stride " + std::to_string(s.stride) + " is below its " +
                                            std::to_string(s.component_count * sizeof(float)) + " bytes per vertex"};
    if (s.count < n)
      return {Status::kInvalidMesh, name + ": holds " + std::to_string(s.count) + " vertices for " + std::to_string(n)};
    if (n > 0 && !s.data) return {Status::kInvalidArgument, name + ": data is null"};
    const bool taken = kind == SLOD_ATTRIBUTE_UV ? s.set < uv_given.size() && uv_given[s.set] : kind_given[kind] != 0;
    if (taken) return {Status::kInvalidArgument, name + ": a second stream of this kind and set"};
    kind_given[kind] = 1;
    Error e;
    if (kind == SLOD_ATTRIBUTE_UV) {
      if (s.set >= uv_sets.size()) uv_sets.resize(s.set + 1), uv_given.resize(s.set + 1, 0);
      uv_given[s.set] = 1;
      e = readVectors(s.data, stride_bytes, n, name, uv_sets[s.set]);
    } else if (kind == SLOD_ATTRIBUTE_NORMAL) {
      e = readVectors(s.data, stride_bytes, n, name, m.normals);
    } else if (kind == SLOD_ATTRIBUTE_TANGENT4) {
      e = readVectors(s.data, stride_bytes, n, name, m.tangents);
    } else if (!rgba) {
      e = readVectors(s.data, stride_bytes, n, name, m.colors);
    } else {
      std::vector<glm::vec4> rgba_values;
      e = readVectors(s.data, stride_bytes, n, name, rgba_values);
      for (size_t v = 0; v < rgba_values.size() && e.ok(); ++v) {
        if (rgba_values[v].a != 1.0f)
          e = {Status::kUnsupported, name + ": vertex " + std::to_string(v) + " has alpha " + std::to_string(rgba_values[v].a) +
                                         "; colour alpha is not carried yet (pass 3 components or alpha 1)"};
        m.colors.push_back(glm::vec3(rgba_values[v]));
      }
    }
    if (!e.ok()) return e;
  }
  for (size_t set = 0; set < uv_given.size(); ++set)
    if (!uv_given[set])
      return {Status::kInvalidArgument, what + ": UV set " + std::to_string(set) + " is missing below set " +
                                            std::to_string(uv_given.size() - 1) + " (number the sets 0, 1, ... without gaps)"};
  if (!uv_sets.empty()) {
    m.uvs = std::move(uv_sets[0]);
    m.extra_uvs.assign(std::make_move_iterator(uv_sets.begin() + 1), std::make_move_iterator(uv_sets.end()));
  }
  return {};
}

// The skin of `d` into `m` (vertex count set): joints below joint_count, finite non-negative weights
// summing to more than 0, the skeleton's parents (checked for range and cycles by validateMesh).
Error readSkin(const slod_mesh_desc& d, const std::string& what, Mesh& m) {
  if (!d.joints && !d.weights) {
    if (d.joint_parents && d.joint_count > 0) m.joint_parents.assign(d.joint_parents, d.joint_parents + d.joint_count);
    return {};
  }
  if (!d.joints || !d.weights) return {Status::kInvalidArgument, what + (d.joints ? ": joints without weights" : ": weights without joints")};
  if (d.joint_count == 0) return {Status::kInvalidArgument, what + ": joints are given but joint_count is 0"};
  const size_t n = m.vertexCount();
  if (d.skin_count < n)
    return {Status::kInvalidMesh, what + ": the skin (joints, weights) holds " + std::to_string(d.skin_count) + " vertices for " + std::to_string(n)};
  const size_t joints_stride = d.joints_stride ? d.joints_stride : 4 * sizeof(uint16_t);
  m.joints.resize(n);
  for (size_t v = 0; v < n; ++v) {
    std::memcpy(&m.joints[v], reinterpret_cast<const char*>(d.joints) + v * joints_stride, sizeof(glm::u16vec4));
    for (int c = 0; c < 4; ++c)
      if (m.joints[v][c] >= d.joint_count)
        return {Status::kInvalidMesh, what + ": skin joints: vertex " + std::to_string(v) + " uses joint " +
                                          std::to_string(m.joints[v][c]) + " but joint_count is " + std::to_string(d.joint_count)};
  }
  if (Error e = readVectors(d.weights, d.weights_stride ? d.weights_stride : 4 * sizeof(float), n, what + ": skin weights", m.weights); !e.ok())
    return e;
  for (size_t v = 0; v < n; ++v) {
    const glm::vec4& w = m.weights[v];
    if (!(w.x >= 0 && w.y >= 0 && w.z >= 0 && w.w >= 0) || !(w.x + w.y + w.z + w.w > 0))
      return {Status::kInvalidMesh, what + ": skin weights: vertex " + std::to_string(v) + " has a negative weight or weights summing to 0"};
  }
  if (d.joint_parents) m.joint_parents.assign(d.joint_parents, d.joint_parents + d.joint_count);
  return {};
}

std::string rangeText(size_t i, const slod_index_range& r) {
  return "ranges[" + std::to_string(i) + "] [" + std::to_string(r.first_index) + ", " +
         std::to_string(uint64_t(r.first_index) + r.index_count) + ")";
}

// The index ranges of `d` into m.triangle_groups (range i = group i) and each range's material:
// multiples of 3, inside the indices, covering every index once.
Error readRanges(const slod_mesh_desc& d, const std::string& what, Mesh& m, std::vector<uint32_t>& material_of) {
  if (d.range_count == 0) return {};
  if (!d.ranges) return {Status::kInvalidArgument, what + ": ranges is null but range_count is " + std::to_string(d.range_count)};
  std::vector<uint32_t> order(d.range_count);
  for (uint32_t i = 0; i < d.range_count; ++i) {
    const slod_index_range& r = d.ranges[i];
    if (r.first_index % 3 != 0 || r.index_count % 3 != 0)
      return {Status::kInvalidMesh, what + ": " + rangeText(i, r) + " does not start and end on a triangle (multiples of 3)"};
    if (uint64_t(r.first_index) + r.index_count > d.index_count)
      return {Status::kInvalidMesh, what + ": " + rangeText(i, r) + " is out of bounds of the " + std::to_string(d.index_count) + " indices"};
    order[i] = i;
    material_of.push_back(r.material);
  }
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return d.ranges[a].first_index < d.ranges[b].first_index; });
  uint64_t covered = 0;  // indices [0, covered) are in a range
  for (uint32_t i : order) {
    const slod_index_range& r = d.ranges[i];
    if (r.first_index < covered && r.index_count > 0) {
      const uint32_t* other = std::find_if(order.data(), order.data() + order.size(), [&](uint32_t o) {
        return o != i && d.ranges[o].first_index <= r.first_index && uint64_t(d.ranges[o].first_index) + d.ranges[o].index_count > r.first_index;
      });
      return {Status::kInvalidMesh, what + ": " + rangeText(i, r) + " overlaps " + rangeText(*other, d.ranges[*other])};
    }
    if (r.first_index > covered)
      return {Status::kInvalidMesh, what + ": indices [" + std::to_string(covered) + ", " + std::to_string(r.first_index) + ") are in no range"};
    covered = std::max<uint64_t>(covered, uint64_t(r.first_index) + r.index_count);
  }
  if (covered < d.index_count)
    return {Status::kInvalidMesh, what + ": indices [" + std::to_string(covered) + ", " + std::to_string(d.index_count) + ") are in no range"};
  m.triangle_groups.assign(d.index_count / 3, 0);
  for (uint32_t i = 0; i < d.range_count; ++i)
    std::fill_n(m.triangle_groups.begin() + d.ranges[i].first_index / 3, d.ranges[i].index_count / 3, i);
  return {};
}

// Sorts a level's triangles by group (stable) and returns one range per group run: the range's
// material is material_of[group] (the group itself when material_of is empty), its source range the
// group. No ranges when the level has no groups.
std::vector<slod_index_range> groupRuns(Mesh& m, const std::vector<uint32_t>& material_of) {
  std::vector<slod_index_range> runs;
  if (m.triangle_groups.empty()) return runs;
  const size_t n = m.triangleCount();
  std::vector<uint32_t> order(n), tri(m.triangles.size());
  for (uint32_t t = 0; t < n; ++t) order[t] = t;
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return m.triangle_groups[a] < m.triangle_groups[b]; });
  for (size_t i = 0; i < n; ++i) std::memcpy(&tri[3 * i], &m.triangles[3 * size_t(order[i])], 3 * sizeof(uint32_t));
  m.triangles.swap(tri);
  std::sort(m.triangle_groups.begin(), m.triangle_groups.end());
  for (size_t t = 0; t < n; ++t) {
    const uint32_t g = m.triangle_groups[t];
    if (runs.empty() || runs.back().source_range != g) {
      const uint32_t material = material_of.empty() ? g : (g < material_of.size() ? material_of[g] : g);
      runs.push_back(slod_index_range{static_cast<uint32_t>(3 * t), 0, material, g});
    }
    runs.back().index_count += 3;
  }
  return runs;
}

// Builds a chain and appends it at the next dense index (= its level table chain id). `material_of`
// gives each triangle group's material (empty: the group is the material), `joint_count` the skeleton's
// size as the caller gave it.
Error addChain(slod_context* ctx, const Mesh& mesh, const slod_chain_desc& d, const std::string& what, slod_chain& handle,
               const std::vector<uint32_t>& material_of = {}, uint32_t joint_count = 0) {
  ChainParams params;
  // a C caller may store any int in the enum field, and C++ may not load an enum holding a value
  // outside its enumerators: the field is read as the int it is
  int method = 0;
  static_assert(sizeof(method) == sizeof(d.method), "slod_method is stored as an int");
  std::memcpy(&method, &d.method, sizeof(method));
  switch (method) {
    case SLOD_METHOD_FLOATING: break;
    case SLOD_METHOD_UNIFORM: params.cluster.method = LodMethod::kUniform; break;
    case SLOD_METHOD_ZHANG: params.cluster.method = LodMethod::kZhang; break;
    case SLOD_METHOD_SCROOGE: params.cluster.method = LodMethod::kScrooge; break;
    default: return {Status::kInvalidArgument, what + ": unknown method " + std::to_string(method)};
  }
  if (d.level_count > 62) return {Status::kInvalidArgument, what + ": level_count " + std::to_string(d.level_count) + " is above 62"};
  params.level_count = d.level_count;
  // 0 is automatic; a denormal width would make the grid's 1 / width infinite
  if (d.first_cell_width != 0.0f && !(std::isnormal(d.first_cell_width) && d.first_cell_width > 0.0f))
    return {Status::kInvalidArgument, what + ": first_cell_width " + std::to_string(d.first_cell_width) +
                                          " is not 0 (automatic) or a finite positive number of at least 1.2e-38"};
  params.first_cell_width = d.first_cell_width;
  LodChain chain;
  if (Error e = buildChain(mesh, params, chain); !e.ok()) return e;
  if (chain.levels.empty()) return {Status::kInvalidMesh, what + ": the mesh is empty"};
  ChainOutputs outputs;
  for (LodLevel& level : chain.levels) outputs.ranges.push_back(groupRuns(level.mesh, material_of));
  outputs.identity.resize(chain.levels[0].mesh.vertexCount());
  for (uint32_t v = 0; v < outputs.identity.size(); ++v) outputs.identity[v] = v;
  outputs.joint_count = joint_count;
  const Sphere bounds = scene::computeChainBounds(chain);
  ctx->objects.table.addChain(chain);
  ctx->objects.chain_bounds.push_back(bounds);
  ctx->objects.chain_names.push_back(what);
  ctx->chains.push_back(std::move(chain));
  ctx->outputs.push_back(std::move(outputs));
  handle = ctx->chain_handles.add();
  ctx->rays_chains_dirty = true;
  return {};
}

// Removes dense chain c, which no object uses: the last chain takes its index (objects follow), and
// the level table is rebuilt so that its chain ids stay the dense indices.
void removeChain(slod_context* ctx, uint32_t c) {
  selection::ReplayScene& s = ctx->objects;
  const uint32_t last = static_cast<uint32_t>(ctx->chains.size() - 1);
  for (uint32_t& oc : s.object_chain)
    if (oc == last) oc = c;
  swapPop(ctx->chains, c);
  swapPop(ctx->outputs, c);
  swapPop(s.chain_bounds, c);
  swapPop(s.chain_names, c);
  ctx->chain_handles.remove(c);
  s.table = selection::LevelTableData{};
  for (const LodChain& chain : ctx->chains) s.table.addChain(chain);
  ctx->spheres_dirty = true;
  ctx->rays_chains_dirty = true;
}

// The selector's levels as the caller's array of slod_selection, out_stride bytes apart.
void writeSelections(const slod_context* ctx, void* out, size_t out_stride) {
  const size_t bytes = std::min(out_stride, sizeof(slod_selection));
  for (size_t i = 0; i < ctx->levels.size(); ++i) {
    slod_selection e{};
    e.object = ctx->object_handles.handle(static_cast<uint32_t>(i));
    e.user_data = ctx->user_data[i];
    e.level = ctx->levels[i];
    const bool transitions = i < ctx->fade.size();
    e.morph = transitions ? ctx->morph[i] : 0.0f;
    e.previous_level = transitions ? ctx->previous_levels[i] : e.level;
    e.fade = transitions ? ctx->fade[i] : 1.0f;
    std::memcpy(static_cast<char*>(out) + i * out_stride, &e, bytes);
  }
}

void recordFrame(slod_context* ctx, const selection::Camera& cam, const slod_camera& camera,
                 const slod_frame_params& params, uint64_t frame) {
  selection::ReplayFrame f;
  if (ctx->replay.frames.empty()) ctx->record_base = frame;
  f.frame = ctx->replay.frames.size();
  f.time_s = static_cast<double>(f.frame) / 60.0;
  f.eye = cam.eye;
  f.target = cam.target;
  f.up = cam.up;
  f.moves.swap(ctx->pending_moves);
  ctx->replay.frames.push_back(std::move(f));
  const bool budget = params.budget_ms > 0.0f;
  ctx->replay.header.has_budget = budget;
  ctx->replay.header.budget_ms = budget ? params.budget_ms : 0.0;
  ctx->replay.header.pixels_per_cell = params.pixels_per_cell;
  ctx->replay.header.viewport_width_px = camera.viewport_width;
  ctx->replay.header.viewport_height_px = camera.viewport_height;
  ctx->replay.header.fov_y_deg = camera.fov_y_deg;
}

// The level `level` of chain handle `chain` (dense chain index c), or a failure naming `fn`.
slod_status findLevel(slod_context* ctx, const char* fn, slod_chain chain, uint32_t level, uint32_t& c, const LodLevel*& out) {
  if (!ctx->chain_handles.resolve(chain, c)) return fail(ctx, SLOD_ERROR_NOT_FOUND, std::string(fn) + ": stale or unknown chain handle");
  const LodChain& lc = ctx->chains[c];
  if (level >= lc.levels.size())
    return fail(ctx, SLOD_ERROR_NOT_FOUND, std::string(fn) + ": chain '" + ctx->objects.chain_names[c] + "' has " +
                                               std::to_string(lc.levels.size()) + " levels, not level " + std::to_string(level));
  out = &lc.levels[level];
  return SLOD_OK;
}

// A level's attribute streams in slod_level_attribute_get's order: normals, colours, UV sets, tangents.
std::vector<slod_attribute_stream> levelStreams(const Mesh& m) {
  std::vector<slod_attribute_stream> streams;
  auto add = [&](slod_attribute_kind kind, uint32_t set, uint32_t components, const float* data) {
    slod_attribute_stream s;
    slod_attribute_stream_init(&s);
    s.kind = kind;
    s.set = set;
    s.component_count = components;
    s.data = data;
    s.stride = components * sizeof(float);
    s.count = m.vertexCount();
    streams.push_back(s);
  };
  if (!m.normals.empty()) add(SLOD_ATTRIBUTE_NORMAL, 0, 3, &m.normals[0].x);
  if (!m.colors.empty()) add(SLOD_ATTRIBUTE_COLOR, 0, 3, &m.colors[0].x);
  if (!m.uvs.empty()) add(SLOD_ATTRIBUTE_UV, 0, 2, &m.uvs[0].x);
  for (size_t set = 0; set < m.extra_uvs.size(); ++set)
    if (!m.extra_uvs[set].empty()) add(SLOD_ATTRIBUTE_UV, static_cast<uint32_t>(set + 1), 2, &m.extra_uvs[set][0].x);
  if (!m.tangents.empty()) add(SLOD_ATTRIBUTE_TANGENT4, 0, 4, &m.tangents[0].x);
  return streams;
}

}  // namespace

extern "C" {

slod_status slod_context_create(const slod_context_desc* desc, slod_context** out) {
  if (!out) return fail(nullptr, SLOD_ERROR_INVALID_ARGUMENT, "slod_context_create: out is null");
  *out = nullptr;
  return guarded(nullptr, [&] {
    slod_context_desc d;
    if (slod_status s = readStruct(nullptr, "slod_context_create", desc, slod_context_desc_init, d)) return s;
    if (d.max_objects == 0) return fail(nullptr, SLOD_ERROR_INVALID_ARGUMENT, "slod_context_create: max_objects is 0");
    if (d.max_view_groups > selection::kMaxViews)
      return fail(nullptr, SLOD_ERROR_INVALID_ARGUMENT, "slod_context_create: max_view_groups is " +
                                                            std::to_string(d.max_view_groups) + ", above 8");
    if ((d.allocator.allocate == nullptr) != (d.allocator.free == nullptr))
      return fail(nullptr, SLOD_ERROR_INVALID_ARGUMENT, "slod_context_create: allocator has only one of allocate and free");
    auto ctx = std::make_unique<slod_context>();
    ctx->desc = d;
    ctx->objects.name = "slod_context";
    *out = ctx.release();
    return ok(nullptr);
  });
}

void slod_context_destroy(slod_context* ctx) {
  try {
    delete ctx;
  } catch (...) {
  }
}

slod_status slod_last_error(const slod_context* ctx) { return ctx ? ctx->last_status : orphan_status; }
const char* slod_last_error_message(const slod_context* ctx) {
  if (!ctx) return orphan_status != SLOD_OK ? orphan_message.c_str() : "";
  return ctx->last_status != SLOD_OK ? ctx->last_message.c_str() : "";
}

const char* slod_status_name(slod_status s) {
  switch (s) {
    case SLOD_OK: return "ok";
    case SLOD_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case SLOD_ERROR_INVALID_MESH: return "invalid mesh";
    case SLOD_ERROR_IO: return "i/o error";
    case SLOD_ERROR_PARSE: return "parse error";
    case SLOD_ERROR_UNSUPPORTED: return "unsupported";
    case SLOD_ERROR_CORRUPT: return "corrupt data";
    case SLOD_ERROR_OUT_OF_MEMORY: return "out of memory";
    case SLOD_ERROR_NOT_FOUND: return "not found";
    case SLOD_ERROR_CAPACITY: return "capacity exceeded";
    case SLOD_ERROR_UNKNOWN: return "unknown error";
    case SLOD_ERROR_IN_USE: return "in use";
  }
  return "unknown status";
}

#define SLOD_STRINGIFY2(x) #x
#define SLOD_STRINGIFY(x) SLOD_STRINGIFY2(x)
const char* slod_version_string(void) {
  return "scenelod " SLOD_STRINGIFY(SLOD_VERSION_MAJOR) "." SLOD_STRINGIFY(SLOD_VERSION_MINOR) "." SLOD_STRINGIFY(
      SLOD_VERSION_PATCH);
}

slod_status slod_chain_build(slod_context* ctx, const slod_mesh_desc* mesh_in, const slod_chain_desc* desc_in,
                             slod_chain* out_chain) {
  if (!ctx) return SLOD_ERROR_INVALID_ARGUMENT;
  return guarded(ctx, [&] {
    slod_mesh_desc mesh;
    slod_chain_desc desc;
    if (slod_status s = readStruct(ctx, "slod_chain_build", mesh_in, slod_mesh_desc_init, mesh)) return s;
    if (slod_status s = readStruct(ctx, "slod_chain_build", desc_in, slod_chain_desc_init, desc)) return s;
    if (!out_chain) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_chain_build: out_chain is null");
    const std::string what = mesh.name ? mesh.name : "mesh";
    if (mesh.vertex_count > 0 && !mesh.positions) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, what + ": positions is null");
    if (mesh.index_count > 0 && !mesh.indices) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, what + ": indices is null");
    if (mesh.index_count % 3 != 0)
      return fail(ctx, SLOD_ERROR_INVALID_MESH, what + ": index count " + std::to_string(mesh.index_count) + " is not a multiple of 3");
    MeshView view;
    view.positions = StridedSpan<const glm::vec3>(reinterpret_cast<const glm::vec3*>(mesh.positions), mesh.vertex_count,
                                                  mesh.position_stride ? mesh.position_stride : sizeof(float) * 3);
    view.triangles = Span<const uint32_t>(mesh.indices, mesh.index_count);
    Mesh m;
    std::vector<uint32_t> material_of;
    if (Error e = meshFromView(view, m, what); !e.ok()) return fail(ctx, e);
    if (Error e = readStreams(mesh, what, m); !e.ok()) return fail(ctx, e);
    if (Error e = readSkin(mesh, what, m); !e.ok()) return fail(ctx, e);
    if (Error e = readRanges(mesh, what, m, material_of); !e.ok()) return fail(ctx, e);
    if (Error e = validateMesh(m, what); !e.ok()) return fail(ctx, e);
    if (Error e = addChain(ctx, m, desc, what, *out_chain, material_of, mesh.joint_count); !e.ok()) return fail(ctx, e);
    return ok(ctx);
  });
}

slod_status slod_chain_load_file(slod_context* ctx, const char* path, const slod_chain_desc* desc_in, slod_chain* out_chain) {
  if (!ctx) return SLOD_ERROR_INVALID_ARGUMENT;
  return guarded(ctx, [&] {
    slod_chain_desc desc;
    if (slod_status s = readStruct(ctx, "slod_chain_load_file", desc_in, slod_chain_desc_init, desc)) return s;
    if (!path || !out_chain) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_chain_load_file: null argument");
    scene::SceneData data;
    if (Error e = scene::loadScene(path, data); !e.ok()) return fail(ctx, e);
    scene::bakeMaterialColors(data);  // a chain of one mesh has no materials: colours carry them
    const Mesh m = scene::flattenScene(data);
    if (Error e = addChain(ctx, m, desc, path, *out_chain); !e.ok()) return fail(ctx, e);
    return ok(ctx);
  });
}

slod_status slod_chain_destroy(slod_context* ctx, slod_chain chain) {
  if (!ctx) return SLOD_ERROR_INVALID_ARGUMENT;
  return guarded(ctx, [&] {
    uint32_t c;
    if (!ctx->chain_handles.resolve(chain, c))
      return fail(ctx, SLOD_ERROR_NOT_FOUND, "slod_chain_destroy: stale or unknown chain handle");
    if (ctx->recording) return fail(ctx, SLOD_ERROR_UNSUPPORTED, "slod_chain_destroy: chains cannot be destroyed while recording");
    const std::vector<uint32_t>& users = ctx->objects.object_chain;
    const size_t n = static_cast<size_t>(std::count(users.begin(), users.end(), c));
    if (n > 0)
      return fail(ctx, SLOD_ERROR_IN_USE, "slod_chain_destroy: chain '" + ctx->objects.chain_names[c] + "' is used by " +
                                              std::to_string(n) + " objects; remove them first");
    removeChain(ctx, c);
    return ok(ctx);
  });
}

uint32_t slod_chain_count(const slod_context* ctx) { return ctx ? static_cast<uint32_t>(ctx->chains.size()) : 0; }

uint32_t slod_chain_level_count(const slod_context* ctx, slod_chain chain) {
  uint32_t c;
  if (!ctx || !ctx->chain_handles.resolve(chain, c)) return 0;
  return static_cast<uint32_t>(ctx->chains[c].levels.size());
}

slod_status slod_level_get(const slod_context* cctx, slod_chain chain, uint32_t level, slod_level_data* out) {
  slod_context* ctx = const_cast<slod_context*>(cctx);
  if (!ctx) return SLOD_ERROR_INVALID_ARGUMENT;
  return guarded(ctx, [&] {
    if (slod_status s = checkSize(ctx, "slod_level_get", out)) return s;
    const LodLevel* found = nullptr;
    uint32_t c = 0;
    if (slod_status s = findLevel(ctx, "slod_level_get", chain, level, c, found)) return s;
    const LodLevel& l = *found;
    slod_level_data d{};
    d.cell_width = l.cell_width;
    d.max_error = l.max_error;
    d.vertex_count = static_cast<uint32_t>(l.mesh.vertexCount());
    d.triangle_count = static_cast<uint32_t>(l.mesh.triangleCount());
    d.edge_count = static_cast<uint32_t>(l.mesh.edgeCount());
    d.point_count = static_cast<uint32_t>(l.mesh.pointCount());
    d.positions = l.mesh.positions.empty() ? nullptr : &l.mesh.positions[0].x;
    d.normals = l.mesh.normals.empty() ? nullptr : &l.mesh.normals[0].x;
    d.triangles = l.mesh.triangles.empty() ? nullptr : l.mesh.triangles.data();
    d.edges = l.mesh.edges.empty() ? nullptr : l.mesh.edges.data();
    d.edge_thickness = l.mesh.edge_thickness.empty() ? nullptr : l.mesh.edge_thickness.data();
    d.points = l.mesh.points.empty() ? nullptr : l.mesh.points.data();
    const ChainOutputs& o = ctx->outputs[c];
    d.attribute_count = static_cast<uint32_t>(levelStreams(l.mesh).size());
    d.range_count = static_cast<uint32_t>(o.ranges[level].size());
    d.ranges = o.ranges[level].empty() ? nullptr : o.ranges[level].data();
    const std::vector<uint32_t>& source = level == 0 ? o.identity : l.source_vertex;
    d.source_vertex = source.empty() ? nullptr : source.data();
    d.joints = l.mesh.joints.empty() ? nullptr : &l.mesh.joints[0].x;
    d.weights = l.mesh.weights.empty() ? nullptr : &l.mesh.weights[0].x;
    d.joint_count = o.joint_count;
    d.joint_parents = l.mesh.joint_parents.empty() ? nullptr : l.mesh.joint_parents.data();
    const LevelMorph& morph = l.morph;
    auto floats = [](const auto& v) { return v.empty() ? nullptr : &v[0].x; };
    d.morph_positions = floats(morph.positions);
    d.morph_normals = floats(morph.normals);
    d.morph_colors = floats(morph.colors);
    d.morph_uvs = floats(morph.uvs);
    d.morph_tangents = floats(morph.tangents);
    writeStruct(d, out);
    return ok(ctx);
  });
}

slod_status slod_level_attribute_get(const slod_context* cctx, slod_chain chain, uint32_t level, uint32_t index,
                                     slod_attribute_stream* out) {
  slod_context* ctx = const_cast<slod_context*>(cctx);
  if (!ctx) return SLOD_ERROR_INVALID_ARGUMENT;
  return guarded(ctx, [&] {
    if (slod_status s = checkSize(ctx, "slod_level_attribute_get", out)) return s;
    const LodLevel* l = nullptr;
    uint32_t c = 0;
    if (slod_status s = findLevel(ctx, "slod_level_attribute_get", chain, level, c, l)) return s;
    const std::vector<slod_attribute_stream> streams = levelStreams(l->mesh);
    if (index >= streams.size())
      return fail(ctx, SLOD_ERROR_NOT_FOUND, "slod_level_attribute_get: level " + std::to_string(level) + " has " +
                                                 std::to_string(streams.size()) + " attribute streams, not stream " + std::to_string(index));
    writeStruct(streams[index], out);
    return ok(ctx);
  });
}

slod_status slod_object_add(slod_context* ctx, const slod_object_desc* desc, slod_object* out) {
  if (!ctx) return SLOD_ERROR_INVALID_ARGUMENT;
  return guarded(ctx, [&] {
    slod_object_desc d;
    if (slod_status s = readStruct(ctx, "slod_object_add", desc, slod_object_desc_init, d)) return s;
    if (!out) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_object_add: out is null");
    if (ctx->recording) return fail(ctx, SLOD_ERROR_UNSUPPORTED, "slod_object_add: objects cannot be added while recording");
    uint32_t chain;
    if (!ctx->chain_handles.resolve(d.chain, chain))
      return fail(ctx, SLOD_ERROR_NOT_FOUND, "slod_object_add: stale or unknown chain handle");
    if (!finite(d.translation, 3) || !finite(d.rotation, 4) || !(d.scale > 0.0f) || !std::isfinite(d.scale))
      return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_object_add: transform has a non-finite value or a scale <= 0");
    if (!(d.importance >= 0.0f) || !std::isfinite(d.importance))
      return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_object_add: importance must be finite and >= 0");
    const size_t n = ctx->objects.objectCount();
    if (n >= ctx->desc.max_objects)
      return fail(ctx, SLOD_ERROR_CAPACITY, "slod_object_add: the context holds max_objects = " + std::to_string(ctx->desc.max_objects));
    selection::ReplayScene& s = ctx->objects;
    s.node_parent.push_back(-1);
    s.node_local.push_back(glm::mat4(1.0f));
    s.object_node.push_back(static_cast<int32_t>(n));
    s.object_chain.push_back(chain);
    s.importance.push_back(d.importance);
    s.must_draw.push_back(d.must_draw ? 1 : 0);
    ctx->move_scratch.assign(1, makeMove(static_cast<uint32_t>(n), d.translation, d.rotation, d.scale));
    if (Error e = selection::applyMoves(s, ctx->move_scratch, "slod_object_add"); !e.ok()) return fail(ctx, e);
    ctx->user_data.push_back(d.user_data);
    ctx->centers.resize(n + 1);
    ctx->radii.resize(n + 1);
    ctx->scales.resize(n + 1);
    ctx->levels.resize(n + 1, -1);
    ctx->spheres_dirty = true;
    *out = ctx->object_handles.add();
    return ok(ctx);
  });
}

slod_status slod_object_remove(slod_context* ctx, slod_object h) {
  if (!ctx) return SLOD_ERROR_INVALID_ARGUMENT;
  return guarded(ctx, [&] {
    uint32_t dense;
    if (!ctx->object_handles.resolve(h, dense))
      return fail(ctx, SLOD_ERROR_NOT_FOUND, "slod_object_remove: stale or unknown object handle");
    if (ctx->recording) return fail(ctx, SLOD_ERROR_UNSUPPORTED, "slod_object_remove: objects cannot be removed while recording");
    selection::ReplayScene& s = ctx->objects;
    // swap-remove; node i stays object i's node
    swapPop(s.node_local, dense);
    s.node_parent.pop_back();
    s.object_node.pop_back();
    swapPop(s.object_chain, dense);
    swapPop(s.importance, dense);
    swapPop(s.must_draw, dense);
    swapPop(ctx->user_data, dense);
    swapPop(ctx->levels, dense);
    ctx->object_handles.remove(dense);
    ctx->centers.pop_back();
    ctx->radii.pop_back();
    ctx->scales.pop_back();
    ctx->spheres_dirty = true;
    if (ctx->selector) selection::resetSelectorHistory(ctx->selector);  // dense indices changed
    return ok(ctx);
  });
}

slod_status slod_object_set_trs(slod_context* ctx, slod_object h, const float t[3], const float q[4], float scale) {
  if (!ctx) return SLOD_ERROR_INVALID_ARGUMENT;
  return guarded(ctx, [&] {
    uint32_t dense;
    if (!ctx->object_handles.resolve(h, dense))
      return fail(ctx, SLOD_ERROR_NOT_FOUND, "slod_object_set_trs: stale or unknown object handle");
    if (!t || !q) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_object_set_trs: null argument");
    if (!finite(t, 3) || !finite(q, 4) || !(scale > 0.0f) || !std::isfinite(scale))
      return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_object_set_trs: non-finite value or scale <= 0");
    ctx->move_scratch.resize(1);
    ctx->move_scratch[0] = makeMove(dense, t, q, scale);
    if (Error e = selection::applyMoves(ctx->objects, ctx->move_scratch, "slod_object_set_trs"); !e.ok()) return fail(ctx, e);
    if (ctx->recording) ctx->pending_moves.push_back(ctx->move_scratch[0]);
    ctx->spheres_dirty = true;
    return ok(ctx);
  });
}

slod_status slod_object_set_importance(slod_context* ctx, slod_object h, float importance) {
  if (!ctx) return SLOD_ERROR_INVALID_ARGUMENT;
  return guarded(ctx, [&] {
    uint32_t dense;
    if (!ctx->object_handles.resolve(h, dense))
      return fail(ctx, SLOD_ERROR_NOT_FOUND, "slod_object_set_importance: stale or unknown object handle");
    if (!(importance >= 0.0f) || !std::isfinite(importance))
      return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_object_set_importance: importance must be finite and >= 0");
    if (ctx->recording) return fail(ctx, SLOD_ERROR_UNSUPPORTED, "slod_object_set_importance: replays cannot record importance changes");
    ctx->objects.importance[dense] = importance;
    return ok(ctx);
  });
}

uint32_t slod_object_count(const slod_context* ctx) { return ctx ? static_cast<uint32_t>(ctx->objects.objectCount()) : 0; }

namespace {

// out, out_stride and capacity of a selection for the context's n objects; SLOD_OK when usable.
slod_status checkOut(slod_context* ctx, const char* fn, const void* out, size_t out_stride, size_t capacity, size_t n) {
  if (n > 0 && !out) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, std::string(fn) + ": out is null");
  if (out_stride < kSelectionMinStride)
    return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, std::string(fn) + ": out_stride " + std::to_string(out_stride) +
                                                      " is below slod_selection's smallest size " +
                                                      std::to_string(kSelectionMinStride) + " (pass sizeof(slod_selection))");
  if (capacity < n)
    return fail(ctx, SLOD_ERROR_CAPACITY, std::string(fn) + ": out holds " + std::to_string(capacity) + " entries for " +
                                              std::to_string(n) + " objects");
  return SLOD_OK;
}

// A job over the context's objects (spheres brought up to date), without camera or views.
selection::SelectionJob objectsJob(slod_context* ctx, const slod_frame_params& params) {
  if (ctx->spheres_dirty) updateSpheres(ctx);
  const size_t n = ctx->objects.objectCount();
  selection::SelectionJob job;
  job.params.pixels_per_cell = params.pixels_per_cell;
  const bool budget = params.budget_ms > 0.0f;
  job.params.mode = budget ? selection::SelectionMode::kBudget : selection::SelectionMode::kDistance;
  job.params.budget_ms = budget ? params.budget_ms : 1.0f;
  job.params.transitions = static_cast<selection::Transitions>(params.transitions);
  job.params.dt_ms = params.dt_ms;
  job.params.fade_ms = params.fade_ms;
  job.params.morph_band = params.morph_band;
  job.params.fade_budget_share = params.fade_budget_share;
  job.params.min_drop_px = params.min_drop_px;
  job.levels = ctx->objects.table.view();
  job.centers = Span<const glm::vec3>(ctx->centers.data(), n);
  job.radii = Span<const float>(ctx->radii.data(), n);
  job.max_scales = Span<const float>(ctx->scales.data(), n);
  job.chains = Span<const uint32_t>(ctx->objects.object_chain.data(), n);
  job.importance = Span<const float>(ctx->objects.importance.data(), n);
  job.must_draw = Span<const uint8_t>(ctx->objects.must_draw.data(), n);
  job.levels_out = Span<int8_t>(ctx->levels.data(), n);
  job.context = ctx->selector;
  return job;
}

// After a run: the selections to out and the frame's result (when asked for).
void writeFrame(slod_context* ctx, const selection::SelectionStats& st, void* out, size_t out_stride,
                slod_frame_result* result) {
  writeSelections(ctx, out, out_stride);
  if (!result) return;
  slod_frame_result r{};
  r.frame = st.frame;
  r.predicted_ms = static_cast<float>(st.predicted_ms);
  r.drawn_count = st.drawn_count;
  r.culled_count = st.culled_count;
  r.dropped_count = st.dropped_count;
  r.switch_count = st.switch_count;
  r.over_budget = (st.flags & selection::kFlagOverBudget) ? 1 : 0;
  r.group_count = st.group_count;
  writeStruct(r, result);
}

// The caller's views (stepped by views[0].size) as the selector's; SLOD_OK when every one is readable.
slod_status readViews(slod_context* ctx, const slod_view* views, size_t count, std::vector<selection::View>& out) {
  const char* fn = "slod_select_views";
  if (count == 0 || count > selection::kMaxViews)
    return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, std::string(fn) + ": view_count is " + std::to_string(count) + ", not 1..8");
  if (slod_status s = checkSize(ctx, fn, views)) return s;
  const uint32_t stride = views[0].size;
  for (size_t i = 0; i < count; ++i) {
    const char* at = reinterpret_cast<const char*>(views) + i * stride;
    slod_view v;
    slod_view_init(&v);
    uint32_t size;
    std::memcpy(&size, at, sizeof size);
    if (size != stride)
      return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, std::string(fn) + ": views[" + std::to_string(i) + "].size is " +
                                                        std::to_string(size) + ", views[0].size " + std::to_string(stride));
    std::memcpy(&v, at, std::min<size_t>(stride, sizeof v));
    if (v.kind < SLOD_VIEW_PRIMARY || v.kind > SLOD_VIEW_SECONDARY)
      return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, std::string(fn) + ": views[" + std::to_string(i) + "].kind is " +
                                                        std::to_string(v.kind) + ", not a slod_view_kind");
    selection::View sv;
    slod_camera c;
    slod_camera_init(&c);
    std::copy(v.eye, v.eye + 3, c.eye);
    std::copy(v.target, v.target + 3, c.target);
    std::copy(v.up, v.up + 3, c.up);
    c.fov_y_deg = v.fov_y_deg;
    c.viewport_width = v.viewport_width;
    c.viewport_height = v.viewport_height;
    sv.camera = toCamera(c);
    sv.camera.near_plane = v.near_plane;
    sv.camera.far_plane = v.far_plane;
    if (v.ortho_height > 0.0f) {
      sv.camera.projection = selection::Projection::kOrthographic;
      sv.camera.ortho_height = v.ortho_height;
    }
    sv.kind = static_cast<selection::ViewKind>(v.kind);
    sv.group = v.group;
    sv.pixels_per_cell = v.pixels_per_cell;
    sv.lod_bias = v.lod_bias;
    out.push_back(sv);
  }
  return SLOD_OK;
}

}  // namespace

slod_status slod_select(slod_context* ctx, const slod_camera* camera_in, const slod_frame_params* params_in, void* out,
                        size_t out_stride, size_t capacity, slod_frame_result* result) {
  if (!ctx) return SLOD_ERROR_INVALID_ARGUMENT;
  return guarded(ctx, [&] {
    slod_camera camera;
    slod_frame_params params;
    if (slod_status s = readStruct(ctx, "slod_select", camera_in, slod_camera_init, camera)) return s;
    if (slod_status s = readStruct(ctx, "slod_select", params_in, slod_frame_params_init, params)) return s;
    if (result)
      if (slod_status s = checkSize(ctx, "slod_select", result)) return s;
    if (slod_status s = checkOut(ctx, "slod_select", out, out_stride, capacity, ctx->objects.objectCount())) return s;
    if (!finite(camera.eye, 3) || !finite(camera.target, 3) || !finite(camera.up, 3) || !(camera.fov_y_deg > 0.0f) ||
        !(camera.fov_y_deg < 180.0f) || camera.viewport_width == 0 || camera.viewport_height == 0)
      return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_select: camera has a non-finite value, a field of view outside "
                                                    "(0, 180) degrees or an empty viewport");
    if (!(params.pixels_per_cell > 0.0f) || !std::isfinite(params.budget_ms))
      return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_select: pixels_per_cell must be > 0 and budget_ms finite");
    if (Error e = ensureSelector(ctx); !e.ok()) return fail(ctx, e);
    const selection::Camera cam = toCamera(camera);
    if (params.transitions < SLOD_TRANSITIONS_NONE || params.transitions > SLOD_TRANSITIONS_MORPH)
      return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_select: transitions is " + std::to_string(params.transitions) +
                                                        ", not a slod_transitions value");
    selection::SelectionJob job = objectsJob(ctx, params);
    job.camera = &cam;
    const size_t n = ctx->objects.objectCount();
    ctx->morph.resize(n);
    ctx->previous_levels.resize(n);
    ctx->fade.resize(n);
    job.morph_out = Span<float>(ctx->morph.data(), n);
    job.previous_levels_out = Span<int8_t>(ctx->previous_levels.data(), n);
    job.fade_out = Span<float>(ctx->fade.data(), n);
    if (const char* e = job.error()) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, std::string("slod_select: ") + e);
    selection::SelectionStats st;
    job.stats = &st;
    if (!job.run()) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_select: the selector refused the frame (degenerate camera?)");
    writeFrame(ctx, st, out, out_stride, result);
    if (ctx->recording) recordFrame(ctx, cam, camera, params, st.frame);
    return ok(ctx);
  });
}

slod_status slod_select_views(slod_context* ctx, const slod_view* views, size_t view_count,
                              const slod_frame_params* params_in, void* out, size_t out_stride, size_t capacity,
                              int8_t* levels, size_t levels_capacity, slod_frame_result* result) {
  if (!ctx) return SLOD_ERROR_INVALID_ARGUMENT;
  return guarded(ctx, [&] {
    const char* fn = "slod_select_views";
    slod_frame_params params;
    if (slod_status s = readStruct(ctx, fn, params_in, slod_frame_params_init, params)) return s;
    if (result)
      if (slod_status s = checkSize(ctx, fn, result)) return s;
    const size_t n = ctx->objects.objectCount();
    if (slod_status s = checkOut(ctx, fn, out, out_stride, capacity, n)) return s;
    if (ctx->recording) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, std::string(fn) + ": a recording takes slod_select frames only");
    if (!std::isfinite(params.budget_ms)) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, std::string(fn) + ": budget_ms must be finite");
    std::vector<selection::View>& sv = ctx->views;
    sv.clear();
    sv.reserve(selection::kMaxViews);
    if (slod_status s = readViews(ctx, views, view_count, sv)) return s;
    size_t groups = 0;
    for (size_t v = 0; v < sv.size(); ++v) {
      bool first = true;
      for (size_t u = 0; u < v; ++u) first &= sv[u].group != sv[v].group;
      groups += first ? 1 : 0;
    }
    if (levels_capacity < groups * n || (n > 0 && !levels))
      return fail(ctx, SLOD_ERROR_CAPACITY, std::string(fn) + ": levels holds " + std::to_string(levels_capacity) +
                                                " entries for " + std::to_string(groups) + " groups of " + std::to_string(n) + " objects");
    if (Error e = ensureSelector(ctx); !e.ok()) return fail(ctx, e);
    if (params.transitions != SLOD_TRANSITIONS_NONE)
      return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, std::string(fn) + ": transitions need slod_select (one camera)");
    selection::SelectionJob job = objectsJob(ctx, params);
    job.views = Span<const selection::View>(sv.data(), sv.size());
    ctx->fade.clear();  // out says: no transition
    job.group_levels_out = Span<int8_t>(levels, groups * n);
    selection::SelectionStats st;
    job.stats = &st;
    if (const char* e = job.error()) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, std::string(fn) + ": " + e);
    job.run();
    writeFrame(ctx, st, out, out_stride, result);
    return ok(ctx);
  });
}

slod_status slod_report_frame_time(slod_context* ctx, uint64_t frame, float measured_ms) {
  if (!ctx) return SLOD_ERROR_INVALID_ARGUMENT;
  // lock-free: no message is built and no context state but the selector's mailbox is touched, so
  // this stays safe beside a running slod_select (except while recording: see scenelod.h)
  if (!ctx->selector || !(measured_ms >= 0.0f) || !std::isfinite(measured_ms)) return SLOD_ERROR_INVALID_ARGUMENT;
  selection::reportFrameTime(ctx->selector, frame, measured_ms);
  if (ctx->recording && frame >= ctx->record_base && frame - ctx->record_base < ctx->replay.frames.size()) {
    selection::ReplayFrame& f = ctx->replay.frames[frame - ctx->record_base];
    f.has_measured = true;
    f.measured_ms = measured_ms;
  }
  return SLOD_OK;
}

slod_status slod_pick(slod_context* ctx, const slod_camera* camera_in, float x, float y, slod_pick_result* out) {
  if (!ctx) return SLOD_ERROR_INVALID_ARGUMENT;
  return guarded(ctx, [&] {
    slod_camera camera;
    if (slod_status s = readStruct(ctx, "slod_pick", camera_in, slod_camera_init, camera)) return s;
    if (slod_status s = checkSize(ctx, "slod_pick", out)) return s;
    slod_pick_result r{};
    r.level = -1;
    const size_t n = ctx->objects.objectCount();
    if (ctx->chains.empty()) {
      writeStruct(r, out);
      return ok(ctx);
    }
    if (ctx->rays_chains_dirty || !ctx->rays) {
      ctx->rays = std::make_unique<selection::RayScene>();
      std::vector<const LodChain*> ptrs;
      for (const LodChain& c : ctx->chains) ptrs.push_back(&c);
      if (Error e = ctx->rays->init(Span<const LodChain* const>(ptrs.data(), ptrs.size())); !e.ok()) return fail(ctx, e);
      ctx->rays_chains_dirty = false;
    }
    std::vector<int32_t> drawn(ctx->levels.begin(), ctx->levels.end());
    if (Error e = ctx->rays->setObjects(Span<const glm::mat4>(ctx->objects.node_local.data(), n),
                                        Span<const uint32_t>(ctx->objects.object_chain.data(), n),
                                        Span<const int32_t>(drawn.data(), n)); !e.ok())
      return fail(ctx, e);
    ctx->rays->commit();
    const selection::PickHit hit = ctx->rays->pick(toCamera(camera), glm::vec2(x, y));
    if (hit.object >= 0 && static_cast<size_t>(hit.object) < n) {
      r.object = ctx->object_handles.handle(static_cast<uint32_t>(hit.object));
      r.level = hit.level;
      r.point[0] = hit.point.x;
      r.point[1] = hit.point.y;
      r.point[2] = hit.point.z;
      r.distance = hit.distance;
    }
    writeStruct(r, out);
    return ok(ctx);
  });
}

slod_status slod_record_start(slod_context* ctx, const char* replay_path, const char* pack_path) {
  if (!ctx) return SLOD_ERROR_INVALID_ARGUMENT;
  return guarded(ctx, [&] {
    if (!replay_path || !pack_path) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_record_start: null path");
    if (ctx->recording) return fail(ctx, SLOD_ERROR_UNSUPPORTED, "slod_record_start: already recording");
    if (ctx->chains.empty()) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_record_start: no chains to record");
    // the scene as it is now: one mesh per chain (its level 0), one root node per object
    const selection::ReplayScene& s = ctx->objects;
    scene::SceneData data;
    for (size_t c = 0; c < ctx->chains.size(); ++c) {
      scene::MeshData md;
      md.name = s.chain_names[c];
      md.mesh = ctx->chains[c].levels[0].mesh;
      data.meshes.push_back(std::move(md));
    }
    scene::PackWriteOptions opts;
    opts.optimize_order = false;  // keep the vertex counts the selector predicts from
    for (size_t o = 0; o < s.objectCount(); ++o) {
      scene::NodeData node;
      node.name = "object " + std::to_string(o);
      node.local = s.node_local[o];
      node.mesh = static_cast<int32_t>(s.object_chain[o]);
      data.nodes.push_back(std::move(node));
      data.roots.push_back(static_cast<int32_t>(o));
      opts.importance.push_back(s.importance[o]);
      opts.must_draw.push_back(s.must_draw[o]);
      opts.user_data.push_back(ctx->user_data[o]);
    }
    if (Error e = scene::writePack(pack_path, data, ctx->chains, s.chain_bounds, opts); !e.ok()) return fail(ctx, e);
    // a replay starts cold: forget last frame's levels and restart the cost model from its prior
    if (Error e = ensureSelector(ctx); !e.ok()) return fail(ctx, e);
    selection::resetSelectorHistory(ctx->selector);
    selection::setSelectorCostModel(ctx->selector, selection::CostCoefficients{});
    ctx->replay = selection::Replay{};
    char resolved[4096];
    ctx->replay.header.scene = ::realpath(pack_path, resolved) ? std::string(resolved) : std::string(pack_path);
    ctx->replay_path = replay_path;
    ctx->pending_moves.clear();
    ctx->recording = true;
    return ok(ctx);
  });
}

slod_status slod_record_stop(slod_context* ctx) {
  if (!ctx) return SLOD_ERROR_INVALID_ARGUMENT;
  return guarded(ctx, [&] {
    if (!ctx->recording) return fail(ctx, SLOD_ERROR_UNSUPPORTED, "slod_record_stop: not recording");
    ctx->recording = false;
    if (Error e = selection::writeReplay(ctx->replay_path, ctx->replay); !e.ok()) return fail(ctx, e);
    return ok(ctx);
  });
}

}  // extern "C"
