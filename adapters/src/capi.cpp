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
#include <cstdio>
#include <cstdlib>
#include <exception>
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

struct slod_context {
  slod_context_desc desc{};
  slod_status last_status = SLOD_OK;
  std::string last_message;

  std::vector<LodChain> chains;
  selection::ReplayScene objects;          // node i = object i (roots), chain spheres per chain
  std::vector<uint32_t> slot_generation;   // per slot
  std::vector<uint32_t> slot_dense;        // per slot: dense index, UINT32_MAX when free
  std::vector<uint32_t> dense_slot;        // per dense index
  std::vector<uint64_t> user_data;         // per dense index
  std::vector<uint32_t> free_slots;

  std::vector<glm::vec3> centers;
  std::vector<float> radii, scales;
  std::vector<int8_t> levels;
  bool spheres_dirty = true;

  selection::SelectorContext* selector = nullptr;
  size_t selector_rows = 0;

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

slod_status fail(slod_context* ctx, slod_status s, const std::string& message) {
  if (ctx) {
    ctx->last_status = s;
    ctx->last_message = message;
    if (ctx->desc.error_callback) ctx->desc.error_callback(ctx->desc.error_user, s, ctx->last_message.c_str());
  }
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

slod_object makeHandle(uint32_t slot, uint32_t generation) {
  return (static_cast<uint64_t>(generation) << 32) | (static_cast<uint64_t>(slot) + 1);  // 0 stays null
}

bool resolve(const slod_context* ctx, slod_object h, uint32_t& dense) {
  const uint64_t low = h & 0xffffffffu;
  if (low == 0) return false;
  const uint32_t slot = static_cast<uint32_t>(low - 1);
  if (slot >= ctx->slot_generation.size() || ctx->slot_generation[slot] != static_cast<uint32_t>(h >> 32)) return false;
  dense = ctx->slot_dense[slot];
  return dense != UINT32_MAX;
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
  const size_t rows = ctx->objects.table.cell_width.size();
  if (ctx->selector && rows <= ctx->selector_rows) return {};
  selection::destroySelectorContext(ctx->selector);
  selection::SelectorConfig cfg;
  cfg.max_object_count = std::max<size_t>(ctx->desc.max_objects, 1);
  cfg.max_levels_per_chain = std::max<size_t>(ctx->objects.table.maxLevelsPerChain(), 1);
  cfg.max_level_rows = std::max<size_t>(rows, 1);
  cfg.allocator.allocate = ctx->desc.allocator.allocate;
  cfg.allocator.free = ctx->desc.allocator.free;
  cfg.allocator.user = ctx->desc.allocator.user;
  ctx->selector = selection::createSelectorContext(cfg);
  ctx->selector_rows = rows;
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

Error addChain(slod_context* ctx, const Mesh& mesh, const slod_chain_desc& d, const std::string& what, uint32_t& id) {
  ChainParams params;
  switch (d.method) {
    case SLOD_METHOD_FLOATING: break;
    case SLOD_METHOD_UNIFORM: params.cluster.method = LodMethod::kUniform; break;
    case SLOD_METHOD_ZHANG: params.cluster.method = LodMethod::kZhang; break;
    case SLOD_METHOD_SCROOGE: params.cluster.method = LodMethod::kScrooge; break;
    default: return {Status::kInvalidArgument, what + ": unknown method " + std::to_string(static_cast<int>(d.method))};
  }
  if (d.level_count > 62) return {Status::kInvalidArgument, what + ": level_count " + std::to_string(d.level_count) + " is above 62"};
  params.level_count = d.level_count;
  params.first_cell_width = d.first_cell_width;
  LodChain chain;
  if (Error e = buildChain(mesh, params, chain)) return e;
  if (chain.levels.empty()) return {Status::kInvalidMesh, what + ": the mesh is empty"};
  const Sphere bounds = scene::computeChainBounds(chain);
  id = ctx->objects.table.addChain(chain);
  ctx->objects.chain_bounds.push_back(bounds);
  ctx->objects.chain_names.push_back(what);
  ctx->chains.push_back(std::move(chain));
  ctx->rays_chains_dirty = true;
  return {};
}

}  // namespace

extern "C" {

void slod_context_desc_init(slod_context_desc* d) {
  if (!d) return;
  *d = slod_context_desc{};
  d->max_objects = 1024;
}

slod_status slod_context_create(const slod_context_desc* desc, slod_context** out) {
  if (!out) return SLOD_ERROR_INVALID_ARGUMENT;
  *out = nullptr;
  if (!desc || desc->max_objects == 0) return SLOD_ERROR_INVALID_ARGUMENT;
  if ((desc->allocator.allocate == nullptr) != (desc->allocator.free == nullptr)) return SLOD_ERROR_INVALID_ARGUMENT;
  try {
    auto* ctx = new slod_context();
    ctx->desc = *desc;
    ctx->objects.name = "slod_context";
    *out = ctx;
    return SLOD_OK;
  } catch (const std::bad_alloc&) {
    return SLOD_ERROR_OUT_OF_MEMORY;
  } catch (...) {
    return SLOD_ERROR_UNKNOWN;
  }
}

void slod_context_destroy(slod_context* ctx) {
  try {
    delete ctx;
  } catch (...) {
  }
}

slod_status slod_last_error(const slod_context* ctx) { return ctx ? ctx->last_status : SLOD_ERROR_INVALID_ARGUMENT; }
const char* slod_last_error_message(const slod_context* ctx) {
  return ctx && ctx->last_status != SLOD_OK ? ctx->last_message.c_str() : "";
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
  }
  return "unknown status";
}

const char* slod_version_string(void) { return "scenelod 0.1.0"; }

void slod_mesh_desc_init(slod_mesh_desc* d) {
  if (d) *d = slod_mesh_desc{};
}

void slod_chain_desc_init(slod_chain_desc* d) {
  if (!d) return;
  *d = slod_chain_desc{};
  d->method = SLOD_METHOD_FLOATING;
  d->level_count = 8;
}

slod_status slod_chain_build(slod_context* ctx, const slod_mesh_desc* mesh, const slod_chain_desc* desc, uint32_t* out_chain) {
  if (!ctx) return SLOD_ERROR_INVALID_ARGUMENT;
  return guarded(ctx, [&] {
    if (!mesh || !desc || !out_chain) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_chain_build: null argument");
    const std::string what = mesh->name ? mesh->name : "mesh";
    if (mesh->vertex_count > 0 && !mesh->positions) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, what + ": positions is null");
    if (mesh->index_count > 0 && !mesh->indices) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, what + ": indices is null");
    if (mesh->index_count % 3 != 0)
      return fail(ctx, SLOD_ERROR_INVALID_MESH, what + ": index count " + std::to_string(mesh->index_count) + " is not a multiple of 3");
    MeshView view;
    view.positions = StridedSpan<const glm::vec3>(reinterpret_cast<const glm::vec3*>(mesh->positions), mesh->vertex_count,
                                                  mesh->position_stride ? mesh->position_stride : sizeof(float) * 3);
    view.triangles = Span<const uint32_t>(mesh->indices, mesh->index_count);
    Mesh m;
    if (Error e = meshFromView(view, m, what)) return fail(ctx, e);
    uint32_t id = 0;
    if (Error e = addChain(ctx, m, *desc, what, id)) return fail(ctx, e);
    *out_chain = id;
    return ok(ctx);
  });
}

slod_status slod_chain_load_file(slod_context* ctx, const char* path, const slod_chain_desc* desc, uint32_t* out_chain) {
  if (!ctx) return SLOD_ERROR_INVALID_ARGUMENT;
  return guarded(ctx, [&] {
    if (!path || !desc || !out_chain) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_chain_load_file: null argument");
    scene::SceneData data;
    if (Error e = scene::loadScene(path, data)) return fail(ctx, e);
    const Mesh m = scene::flattenScene(data);
    uint32_t id = 0;
    if (Error e = addChain(ctx, m, *desc, path, id)) return fail(ctx, e);
    *out_chain = id;
    return ok(ctx);
  });
}

uint32_t slod_chain_count(const slod_context* ctx) { return ctx ? static_cast<uint32_t>(ctx->chains.size()) : 0; }

uint32_t slod_chain_level_count(const slod_context* ctx, uint32_t chain) {
  return ctx && chain < ctx->chains.size() ? static_cast<uint32_t>(ctx->chains[chain].levels.size()) : 0;
}

slod_status slod_level_get(const slod_context* cctx, uint32_t chain, uint32_t level, slod_level_data* out) {
  slod_context* ctx = const_cast<slod_context*>(cctx);
  if (!ctx) return SLOD_ERROR_INVALID_ARGUMENT;
  return guarded(ctx, [&] {
    if (!out) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_level_get: out is null");
    if (chain >= ctx->chains.size()) return fail(ctx, SLOD_ERROR_NOT_FOUND, "slod_level_get: no chain " + std::to_string(chain));
    const LodChain& c = ctx->chains[chain];
    if (level >= c.levels.size())
      return fail(ctx, SLOD_ERROR_NOT_FOUND, "slod_level_get: chain " + std::to_string(chain) + " has " +
                                                 std::to_string(c.levels.size()) + " levels, not level " + std::to_string(level));
    const LodLevel& l = c.levels[level];
    *out = slod_level_data{};
    out->cell_width = l.cell_width;
    out->max_error = l.max_error;
    out->vertex_count = static_cast<uint32_t>(l.mesh.vertexCount());
    out->triangle_count = static_cast<uint32_t>(l.mesh.triangleCount());
    out->edge_count = static_cast<uint32_t>(l.mesh.edgeCount());
    out->point_count = static_cast<uint32_t>(l.mesh.pointCount());
    out->positions = l.mesh.positions.empty() ? nullptr : &l.mesh.positions[0].x;
    out->normals = l.mesh.normals.empty() ? nullptr : &l.mesh.normals[0].x;
    out->triangles = l.mesh.triangles.empty() ? nullptr : l.mesh.triangles.data();
    out->edges = l.mesh.edges.empty() ? nullptr : l.mesh.edges.data();
    out->edge_thickness = l.mesh.edge_thickness.empty() ? nullptr : l.mesh.edge_thickness.data();
    out->points = l.mesh.points.empty() ? nullptr : l.mesh.points.data();
    return ok(ctx);
  });
}

void slod_object_desc_init(slod_object_desc* d) {
  if (!d) return;
  *d = slod_object_desc{};
  d->rotation[3] = 1.0f;
  d->scale = 1.0f;
  d->importance = 1.0f;
}

slod_status slod_object_add(slod_context* ctx, const slod_object_desc* d, slod_object* out) {
  if (!ctx) return SLOD_ERROR_INVALID_ARGUMENT;
  return guarded(ctx, [&] {
    if (!d || !out) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_object_add: null argument");
    if (ctx->recording) return fail(ctx, SLOD_ERROR_UNSUPPORTED, "slod_object_add: objects cannot be added while recording");
    if (d->chain >= ctx->chains.size())
      return fail(ctx, SLOD_ERROR_NOT_FOUND, "slod_object_add: no chain " + std::to_string(d->chain));
    if (!finite(d->translation, 3) || !finite(d->rotation, 4) || !(d->scale > 0.0f) || !std::isfinite(d->scale))
      return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_object_add: transform has a non-finite value or a scale <= 0");
    if (!(d->importance >= 0.0f) || !std::isfinite(d->importance))
      return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_object_add: importance must be finite and >= 0");
    const size_t n = ctx->objects.objectCount();
    if (n >= ctx->desc.max_objects)
      return fail(ctx, SLOD_ERROR_CAPACITY, "slod_object_add: the context holds max_objects = " + std::to_string(ctx->desc.max_objects));
    uint32_t slot;
    if (!ctx->free_slots.empty()) {
      slot = ctx->free_slots.back();
      ctx->free_slots.pop_back();
    } else {
      slot = static_cast<uint32_t>(ctx->slot_generation.size());
      ctx->slot_generation.push_back(1);
      ctx->slot_dense.push_back(UINT32_MAX);
    }
    selection::ReplayScene& s = ctx->objects;
    s.node_parent.push_back(-1);
    s.node_local.push_back(glm::mat4(1.0f));
    s.object_node.push_back(static_cast<int32_t>(n));
    s.object_chain.push_back(d->chain);
    s.importance.push_back(d->importance);
    s.must_draw.push_back(d->must_draw ? 1 : 0);
    ctx->move_scratch.assign(1, makeMove(static_cast<uint32_t>(n), d->translation, d->rotation, d->scale));
    if (Error e = selection::applyMoves(s, ctx->move_scratch, "slod_object_add")) return fail(ctx, e);
    ctx->slot_dense[slot] = static_cast<uint32_t>(n);
    ctx->dense_slot.push_back(slot);
    ctx->user_data.push_back(d->user_data);
    ctx->centers.resize(n + 1);
    ctx->radii.resize(n + 1);
    ctx->scales.resize(n + 1);
    ctx->levels.resize(n + 1, -1);
    ctx->spheres_dirty = true;
    *out = makeHandle(slot, ctx->slot_generation[slot]);
    return ok(ctx);
  });
}

slod_status slod_object_remove(slod_context* ctx, slod_object h) {
  if (!ctx) return SLOD_ERROR_INVALID_ARGUMENT;
  return guarded(ctx, [&] {
    uint32_t dense;
    if (!resolve(ctx, h, dense)) return fail(ctx, SLOD_ERROR_NOT_FOUND, "slod_object_remove: stale or unknown object handle");
    if (ctx->recording) return fail(ctx, SLOD_ERROR_UNSUPPORTED, "slod_object_remove: objects cannot be removed while recording");
    selection::ReplayScene& s = ctx->objects;
    const size_t last = s.objectCount() - 1;
    // swap-remove; node i stays object i's node
    auto swapPop = [&](auto& v) {
      v[dense] = v[last];
      v.pop_back();
    };
    swapPop(s.node_local);
    s.node_parent.pop_back();
    s.object_node.pop_back();
    swapPop(s.object_chain);
    swapPop(s.importance);
    swapPop(s.must_draw);
    swapPop(ctx->user_data);
    swapPop(ctx->levels);
    const uint32_t slot = ctx->dense_slot[dense], moved_slot = ctx->dense_slot[last];
    swapPop(ctx->dense_slot);
    if (dense != last) ctx->slot_dense[moved_slot] = dense;
    ctx->slot_dense[slot] = UINT32_MAX;
    ctx->slot_generation[slot]++;
    ctx->free_slots.push_back(slot);
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
    if (!resolve(ctx, h, dense)) return fail(ctx, SLOD_ERROR_NOT_FOUND, "slod_object_set_trs: stale or unknown object handle");
    if (!t || !q) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_object_set_trs: null argument");
    if (!finite(t, 3) || !finite(q, 4) || !(scale > 0.0f) || !std::isfinite(scale))
      return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_object_set_trs: non-finite value or scale <= 0");
    if (ctx->move_scratch.empty()) ctx->move_scratch.resize(1);
    ctx->move_scratch.resize(1);
    ctx->move_scratch[0] = makeMove(dense, t, q, scale);
    if (Error e = selection::applyMoves(ctx->objects, ctx->move_scratch, "slod_object_set_trs")) return fail(ctx, e);
    if (ctx->recording) ctx->pending_moves.push_back(ctx->move_scratch[0]);
    ctx->spheres_dirty = true;
    return ok(ctx);
  });
}

slod_status slod_object_set_importance(slod_context* ctx, slod_object h, float importance) {
  if (!ctx) return SLOD_ERROR_INVALID_ARGUMENT;
  return guarded(ctx, [&] {
    uint32_t dense;
    if (!resolve(ctx, h, dense)) return fail(ctx, SLOD_ERROR_NOT_FOUND, "slod_object_set_importance: stale or unknown object handle");
    if (!(importance >= 0.0f) || !std::isfinite(importance))
      return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_object_set_importance: importance must be finite and >= 0");
    if (ctx->recording) return fail(ctx, SLOD_ERROR_UNSUPPORTED, "slod_object_set_importance: replays cannot record importance changes");
    ctx->objects.importance[dense] = importance;
    return ok(ctx);
  });
}

uint32_t slod_object_count(const slod_context* ctx) { return ctx ? static_cast<uint32_t>(ctx->objects.objectCount()) : 0; }

void slod_camera_init(slod_camera* c) {
  if (!c) return;
  *c = slod_camera{};
  c->eye[2] = 5.0f;
  c->up[1] = 1.0f;
  c->fov_y_deg = 60.0f;
  c->viewport_width = 1280;
  c->viewport_height = 720;
}

void slod_frame_params_init(slod_frame_params* p) {
  if (!p) return;
  *p = slod_frame_params{};
  p->budget_ms = 16.7f;
  p->pixels_per_cell = 1.0f;
}

slod_status slod_select(slod_context* ctx, const slod_camera* camera, const slod_frame_params* params, slod_selection* out,
                        size_t capacity, slod_frame_result* result) {
  if (!ctx) return SLOD_ERROR_INVALID_ARGUMENT;
  return guarded(ctx, [&] {
    if (!camera || !params) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_select: null camera or params");
    const size_t n = ctx->objects.objectCount();
    if (n > 0 && !out) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_select: out is null");
    if (capacity < n)
      return fail(ctx, SLOD_ERROR_CAPACITY, "slod_select: out holds " + std::to_string(capacity) + " entries for " +
                                                std::to_string(n) + " objects");
    if (!finite(camera->eye, 3) || !finite(camera->target, 3) || !finite(camera->up, 3) || !(camera->fov_y_deg > 0.0f) ||
        !(camera->fov_y_deg < 180.0f) || camera->viewport_width == 0 || camera->viewport_height == 0)
      return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_select: camera has a non-finite value, a field of view outside "
                                                    "(0, 180) degrees or an empty viewport");
    if (!(params->pixels_per_cell > 0.0f) || !std::isfinite(params->budget_ms))
      return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_select: pixels_per_cell must be > 0 and budget_ms finite");
    if (Error e = ensureSelector(ctx)) return fail(ctx, e);
    if (ctx->spheres_dirty) updateSpheres(ctx);
    const selection::Camera cam = toCamera(*camera);
    selection::SelectionJob job;
    job.camera = &cam;
    job.params.pixels_per_cell = params->pixels_per_cell;
    const bool budget = params->budget_ms > 0.0f;
    job.params.mode = budget ? selection::SelectionMode::kBudget : selection::SelectionMode::kDistance;
    job.params.budget_ms = budget ? params->budget_ms : 1.0f;
    job.levels = ctx->objects.table.view();
    job.centers = Span<const glm::vec3>(ctx->centers.data(), n);
    job.radii = Span<const float>(ctx->radii.data(), n);
    job.max_scales = Span<const float>(ctx->scales.data(), n);
    job.chains = Span<const uint32_t>(ctx->objects.object_chain.data(), n);
    job.importance = Span<const float>(ctx->objects.importance.data(), n);
    job.must_draw = Span<const uint8_t>(ctx->objects.must_draw.data(), n);
    job.levels_out = Span<int8_t>(ctx->levels.data(), n);
    selection::SelectionStats st;
    job.stats = &st;
    job.context = ctx->selector;
    if (!job.run()) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_select: the selector refused the frame (degenerate camera?)");
    for (size_t i = 0; i < n; ++i) {
      const uint32_t slot = ctx->dense_slot[i];
      out[i].object = makeHandle(slot, ctx->slot_generation[slot]);
      out[i].user_data = ctx->user_data[i];
      out[i].level = ctx->levels[i];
    }
    if (result) {
      *result = slod_frame_result{};
      result->frame = st.frame;
      result->predicted_ms = static_cast<float>(st.predicted_ms);
      result->drawn_count = st.drawn_count;
      result->culled_count = st.culled_count;
      result->dropped_count = st.dropped_count;
      result->switch_count = st.switch_count;
      result->over_budget = (st.flags & selection::kFlagOverBudget) ? 1 : 0;
    }
    if (ctx->recording) {
      selection::ReplayFrame f;
      if (ctx->replay.frames.empty()) ctx->record_base = st.frame;
      f.frame = ctx->replay.frames.size();
      f.time_s = static_cast<double>(f.frame) / 60.0;
      f.eye = cam.eye;
      f.target = cam.target;
      f.up = cam.up;
      f.moves.swap(ctx->pending_moves);
      ctx->replay.frames.push_back(std::move(f));
      ctx->replay.header.has_budget = budget;
      ctx->replay.header.budget_ms = budget ? params->budget_ms : 0.0;
      ctx->replay.header.pixels_per_cell = params->pixels_per_cell;
      ctx->replay.header.viewport_width_px = camera->viewport_width;
      ctx->replay.header.viewport_height_px = camera->viewport_height;
      ctx->replay.header.fov_y_deg = camera->fov_y_deg;
    }
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

slod_status slod_pick(slod_context* ctx, const slod_camera* camera, float x, float y, slod_pick_result* out) {
  if (!ctx) return SLOD_ERROR_INVALID_ARGUMENT;
  return guarded(ctx, [&] {
    if (!camera || !out) return fail(ctx, SLOD_ERROR_INVALID_ARGUMENT, "slod_pick: null argument");
    *out = slod_pick_result{};
    out->level = -1;
    const size_t n = ctx->objects.objectCount();
    if (ctx->rays_chains_dirty || !ctx->rays) {
      if (ctx->chains.empty()) return ok(ctx);
      ctx->rays = std::make_unique<selection::RayScene>();
      std::vector<const LodChain*> ptrs;
      for (const LodChain& c : ctx->chains) ptrs.push_back(&c);
      if (Error e = ctx->rays->init(Span<const LodChain* const>(ptrs.data(), ptrs.size()))) return fail(ctx, e);
      ctx->rays_chains_dirty = false;
    }
    std::vector<int32_t> drawn(ctx->levels.begin(), ctx->levels.end());
    if (Error e = ctx->rays->setObjects(Span<const glm::mat4>(ctx->objects.node_local.data(), n),
                                        Span<const uint32_t>(ctx->objects.object_chain.data(), n),
                                        Span<const int32_t>(drawn.data(), n)))
      return fail(ctx, e);
    ctx->rays->commit();
    const selection::PickHit hit = ctx->rays->pick(toCamera(*camera), glm::vec2(x, y));
    if (hit.object >= 0 && static_cast<size_t>(hit.object) < n) {
      const uint32_t slot = ctx->dense_slot[static_cast<size_t>(hit.object)];
      out->object = makeHandle(slot, ctx->slot_generation[slot]);
      out->level = hit.level;
      out->point[0] = hit.point.x;
      out->point[1] = hit.point.y;
      out->point[2] = hit.point.z;
      out->distance = hit.distance;
    }
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
    if (Error e = scene::writePack(pack_path, data, ctx->chains, s.chain_bounds, opts)) return fail(ctx, e);
    // a replay starts cold: forget last frame's levels and restart the cost model from its prior
    if (Error e = ensureSelector(ctx)) return fail(ctx, e);
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
    if (Error e = selection::writeReplay(ctx->replay_path, ctx->replay)) return fail(ctx, e);
    return ok(ctx);
  });
}

}  // extern "C"
