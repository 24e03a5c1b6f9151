// The ray scene behind picking and occlusion (Funkhouser & Séquin 1993 use visibility to cut benefit):
// one Embree scene per (mesh, level), objects as instances of them with flattened world transforms.
// The instance level is our own BVH over object boxes (top_bvh.h), refitted when objects move:
// committing 10 000 moved Embree 3 instances rebuilt Embree's top level at 35-90 ms on the project
// machine (docs/VISIBILITY.md), a refit costs well under a millisecond.
#include <algorithm>
#include <cmath>
#include <string>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include "ray_scene_impl.h"
#include "scenelod/scene/scene.h"

namespace scenelod::selection {
namespace {

bool finiteMatrix(const glm::mat4& m) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(m[c][r])) return false;
  return true;
}

// The largest factor by which the linear part of m stretches a length (its largest singular value:
// the square root of the largest eigenvalue of M^T M, closed form for symmetric 3 x 3 matrices),
// never below the longest column. Object-space radii and errors times this bound world ones, also
// for sheared matrices (a parent's non-uniform scale above a rotated child), where the longest
// column alone falls short.
float largestScale(const glm::mat4& m) {
  const glm::vec3 c0(m[0]), c1(m[1]), c2(m[2]);
  const float column = std::max(glm::length(c0), std::max(glm::length(c1), glm::length(c2)));
  const double a01 = glm::dot(c0, c1), a02 = glm::dot(c0, c2), a12 = glm::dot(c1, c2);
  const double off = a01 * a01 + a02 * a02 + a12 * a12;
  if (!(off > 0.0)) return column;  // orthogonal columns (rotation and scale): the longest column
  const double a00 = glm::dot(c0, c0), a11 = glm::dot(c1, c1), a22 = glm::dot(c2, c2);
  const double q = (a00 + a11 + a22) / 3.0;
  const double b00 = a00 - q, b11 = a11 - q, b22 = a22 - q;
  const double p = std::sqrt((b00 * b00 + b11 * b11 + b22 * b22 + 2.0 * off) / 6.0);
  const double det = b00 * (b11 * b22 - a12 * a12) - a01 * (a01 * b22 - a12 * a02) + a02 * (a01 * a12 - b11 * a02);
  const double r = std::min(1.0, std::max(-1.0, det / (2.0 * p * p * p)));
  return std::max(column, static_cast<float>(std::sqrt(q + 2.0 * p * std::cos(std::acos(r) / 3.0)) * (1.0 + 1e-6)));
}

std::string deviceErrorText(RTCDevice device) {
  const RTCError e = rtcGetDeviceError(device);
  switch (e) {
    case RTC_ERROR_NONE: return "";
    case RTC_ERROR_OUT_OF_MEMORY: return "Embree ran out of memory";
    case RTC_ERROR_INVALID_ARGUMENT: return "Embree reported an invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "Embree reported an invalid operation";
    case RTC_ERROR_UNSUPPORTED_CPU: return "Embree does not support this CPU";
    case RTC_ERROR_CANCELLED: return "Embree build cancelled";
    default: return "Embree reported an unknown error";
  }
}

RTCScene buildPrototype(RTCDevice device, const Mesh& mesh) {
  const size_t tri_count = mesh.triangleCount();
  if (tri_count == 0) return nullptr;
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                        3 * sizeof(float), mesh.vertexCount()));
  auto* t = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                           3 * sizeof(uint32_t), tri_count));
  if (!v || !t) {
    rtcReleaseGeometry(geom);
    return nullptr;
  }
  for (size_t i = 0; i < mesh.vertexCount(); ++i) {
    v[3 * i + 0] = mesh.positions[i].x;
    v[3 * i + 1] = mesh.positions[i].y;
    v[3 * i + 2] = mesh.positions[i].z;
  }
  std::copy(mesh.triangles.begin(), mesh.triangles.end(), t);
  rtcCommitGeometry(geom);
  RTCScene scene = rtcNewScene(device);
  rtcAttachGeometry(scene, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(scene);
  return scene;
}

}  // namespace

void RayScene::Impl::release() {
  bvh = TopBvh();
  built = moved = false;
  dead_in_bvh = 0;
  for (ChainPrototypes& c : chains)
    for (RTCScene s : c.levels)
      if (s) rtcReleaseScene(s);
  chains.clear();
  if (device) rtcReleaseDevice(device);
  device = nullptr;
  box_lo.clear();
  box_hi.clear();
  world_sphere.clear();
  largest_scale.clear();
  inverse_world.clear();
  world.clear();
  chain.clear();
  drawn_level.clear();
  generation.clear();
  live.clear();
  free_ids.clear();
  scene_handle.clear();
}

RayScene::RayScene() : impl_(new Impl) {}

RayScene::~RayScene() {
  impl_->release();
  delete impl_;
}

Error RayScene::init(Span<const LodChain* const> chains, const RaySceneParams& params) {
  Impl& m = *impl_;
  m.release();
  m.params = params;
  if (!(params.occluder_relative_error >= 0.0f) || !(params.occluder_error_px >= 0.0f))
    return Error(Status::kInvalidArgument, "ray scene: occluder_relative_error and occluder_error_px must be >= 0");
  m.device = rtcNewDevice(params.device_config);
  if (!m.device) return Error(Status::kUnsupported, "ray scene: could not create the Embree device");
  m.chains.resize(chains.count);
  for (size_t c = 0; c < chains.count; ++c) {
    const LodChain* chain = chains[c];
    const std::string what = "ray scene: chain " + std::to_string(c);
    if (!chain) return Error(Status::kInvalidArgument, what + " is null");
    if (chain->empty()) return Error(Status::kInvalidArgument, what + " has no levels");
    ChainPrototypes& p = m.chains[c];
    p.levels.assign(chain->levelCount(), nullptr);
    p.max_error.assign(chain->levelCount(), 0.0f);
    glm::vec3 lo(3.0e38f), hi(-3.0e38f);
    for (size_t l = 0; l < chain->levelCount(); ++l) {
      const Mesh& mesh = chain->levels[l].mesh;
      Error e = validateMesh(mesh, what + " level " + std::to_string(l));
      if (!e.ok()) return e;
      for (const glm::vec3& q : mesh.positions) {
        lo = glm::min(lo, q);
        hi = glm::max(hi, q);
      }
    }
    if (lo.x > hi.x) return Error(Status::kInvalidMesh, what + " has no vertices");
    p.box_lo = lo;
    p.box_hi = hi;
    p.center = 0.5f * (lo + hi);
    float r2 = 0.0f;
    for (size_t l = 0; l < chain->levelCount(); ++l)
      for (const glm::vec3& q : chain->levels[l].mesh.positions) {
        const glm::vec3 d = q - p.center;
        r2 = std::max(r2, glm::dot(d, d));
      }
    p.radius = std::sqrt(r2);
    if (chain->levels[0].mesh.triangleCount() == 0)
      return Error(Status::kInvalidMesh, what + " level 0 has no triangles to ray-trace");
    p.occluder_level = 0;
    for (size_t l = 0; l < chain->levelCount(); ++l) {
      p.max_error[l] = std::max(0.0f, chain->levels[l].max_error);
      p.levels[l] = buildPrototype(m.device, chain->levels[l].mesh);
      const std::string err = deviceErrorText(m.device);
      if (!err.empty()) return Error(Status::kOutOfMemory, what + " level " + std::to_string(l) + ": " + err);
      // levels get coarser with l: the last one within the error allowance wins
      if (p.levels[l] && p.max_error[l] <= params.occluder_relative_error * p.radius)
        p.occluder_level = static_cast<int32_t>(l);
    }
  }
  const std::string err = deviceErrorText(m.device);
  if (!err.empty()) return Error(Status::kOutOfMemory, "ray scene: " + err);
  return {};
}

namespace {

Error checkObject(const RayScene::Impl& m, const glm::mat4& world, uint32_t chain, int32_t level,
                  const std::string& what) {
  if (chain >= m.chains.size())
    return Error(Status::kInvalidArgument, what + ": chain id " + std::to_string(chain) + " out of range (" +
                                               std::to_string(m.chains.size()) + " chains)");
  const int32_t count = static_cast<int32_t>(m.chains[chain].levels.size());
  if (level < -1 || level >= count)
    return Error(Status::kInvalidArgument, what + ": drawn level " + std::to_string(level) +
                                               " outside [-1, " + std::to_string(count) + ")");
  if (!finiteMatrix(world)) return Error(Status::kInvalidArgument, what + ": world transform is not finite");
  const float det = glm::determinant(glm::mat3(world));
  if (!(std::fabs(det) > 1e-30f)) return Error(Status::kInvalidArgument, what + ": world transform is singular");
  return {};
}

constexpr float kEmpty = 3.0e38f;

void growTo(RayScene::Impl& m, size_t n) {
  if (m.live.size() >= n) return;
  m.box_lo.resize(n, glm::vec3(kEmpty));
  m.box_hi.resize(n, glm::vec3(-kEmpty));
  m.world_sphere.resize(n, glm::vec4(0.0f));
  m.largest_scale.resize(n, 0.0f);
  m.inverse_world.resize(n, glm::mat4(1.0f));
  m.world.resize(n, glm::mat4(1.0f));
  m.chain.resize(n, 0);
  m.drawn_level.resize(n, -1);
  m.generation.resize(n, 0);
  m.live.resize(n, 0);
}

void clearObject(RayScene::Impl& m, size_t id) {
  m.live[id] = 0;
  m.world_sphere[id] = glm::vec4(0.0f);
  m.box_lo[id] = glm::vec3(kEmpty);
  m.box_hi[id] = glm::vec3(-kEmpty);
}

void updateDerived(RayScene::Impl& m, uint32_t id) {
  const ChainPrototypes& p = m.chains[m.chain[id]];
  const glm::mat4& w = m.world[id];
  const float scale = largestScale(w);
  m.world_sphere[id] = glm::vec4(glm::vec3(w * glm::vec4(p.center, 1.0f)), p.radius * scale);
  // world box of the object-space box: centre mapped, half extent through |M|
  const glm::vec3 c(w * glm::vec4(0.5f * (p.box_lo + p.box_hi), 1.0f));
  const glm::vec3 h = 0.5f * (p.box_hi - p.box_lo);
  const glm::vec3 e = glm::abs(glm::vec3(w[0])) * h.x + glm::abs(glm::vec3(w[1])) * h.y + glm::abs(glm::vec3(w[2])) * h.z;
  m.box_lo[id] = c - e;
  m.box_hi[id] = c + e;
  m.largest_scale[id] = scale;
  m.inverse_world[id] = glm::inverse(w);
}

// Places object `id` (storage already grown); the tree learns of it at commit().
void placeObject(RayScene::Impl& m, uint32_t id, const glm::mat4& world, uint32_t chain, int32_t level) {
  m.world[id] = world;
  m.chain[id] = chain;
  m.drawn_level[id] = level;
  m.live[id] = 1;
  ++m.generation[id];
  updateDerived(m, id);
}

}  // namespace

Error RayScene::setObjects(Span<const glm::mat4> world, Span<const uint32_t> chain_ids,
                           Span<const int32_t> drawn_levels) {
  Impl& m = *impl_;
  if (!m.device) return Error(Status::kInvalidArgument, "ray scene: setObjects before init");
  if (world.count != chain_ids.count || world.count != drawn_levels.count)
    return Error(Status::kInvalidArgument, "ray scene: setObjects got " + std::to_string(world.count) +
                                               " transforms, " + std::to_string(chain_ids.count) + " chain ids and " +
                                               std::to_string(drawn_levels.count) + " drawn levels");
  for (size_t i = 0; i < world.count; ++i) {
    Error e = checkObject(m, world[i], chain_ids[i], drawn_levels[i], "ray scene: object " + std::to_string(i));
    if (!e.ok()) return e;
  }
  for (size_t i = 0; i < m.live.size(); ++i) clearObject(m, i);
  growTo(m, world.count);
  m.free_ids.clear();
  for (size_t i = world.count; i < m.live.size(); ++i) m.free_ids.push_back(static_cast<uint32_t>(i));
  for (size_t i = 0; i < world.count; ++i)
    placeObject(m, static_cast<uint32_t>(i), world[i], chain_ids[i], drawn_levels[i]);
  m.built = false;
  return {};
}

Error RayScene::addObject(const glm::mat4& world, uint32_t chain_id, int32_t drawn_level, uint32_t& id) {
  Impl& m = *impl_;
  if (!m.device) return Error(Status::kInvalidArgument, "ray scene: addObject before init");
  Error e = checkObject(m, world, chain_id, drawn_level, "ray scene: new object");
  if (!e.ok()) return e;
  if (!m.free_ids.empty()) {
    auto it = std::min_element(m.free_ids.begin(), m.free_ids.end());
    id = *it;
    *it = m.free_ids.back();
    m.free_ids.pop_back();
  } else {
    id = static_cast<uint32_t>(m.live.size());
    growTo(m, m.live.size() + 1);
  }
  placeObject(m, id, world, chain_id, drawn_level);
  // found by the linear pass over pending objects until the next rebuild
  if (m.built) m.bvh.pending.push_back(id);
  return {};
}

Error RayScene::removeObject(uint32_t id) {
  Impl& m = *impl_;
  if (id >= m.live.size() || !m.live[id])
    return Error(Status::kNotFound, "ray scene: removeObject: no live object with id " + std::to_string(id));
  clearObject(m, id);
  m.free_ids.push_back(id);
  auto& pending = m.bvh.pending;
  auto it = std::find(pending.begin(), pending.end(), id);
  if (it != pending.end()) {
    pending.erase(it);
  } else {
    ++m.dead_in_bvh;  // its empty box leaves the tree at the next refit
    m.moved = true;
  }
  return {};
}

Error RayScene::syncFromScene(const scene::Scene& sc, Span<const int32_t> drawn_levels) {
  Impl& m = *impl_;
  if (!m.device) return Error(Status::kInvalidArgument, "ray scene: syncFromScene before init");
  const size_t n = sc.objectCount();
  if (!drawn_levels.empty() && drawn_levels.count != n)
    return Error(Status::kInvalidArgument, "ray scene: syncFromScene got " + std::to_string(drawn_levels.count) +
                                               " drawn levels for " + std::to_string(n) + " scene objects");
  auto fetch = [&](size_t i, scene::ObjectDesc& desc, glm::mat4& world) -> Error {
    const scene::ObjectHandle h = sc.objectAt(i);
    Error e = sc.getObject(h, desc);
    if (e.ok()) e = sc.getWorld(desc.node, world);
    if (!e.ok()) return Error(e.status, "ray scene: scene object " + std::to_string(i) + ": " + e.message);
    return {};
  };
  // check everything first, so a refused sync leaves the ray scene as it was
  for (size_t i = 0; i < n; ++i) {
    scene::ObjectDesc desc;
    glm::mat4 world;
    Error e = fetch(i, desc, world);
    if (e.ok()) e = checkObject(m, world, desc.chain, drawn_levels.empty() ? 0 : drawn_levels[i],
                            "ray scene: scene object " + std::to_string(i));
    if (!e.ok()) return e;
  }
  for (size_t id = n; id < m.live.size(); ++id)
    if (m.live[id]) removeObject(static_cast<uint32_t>(id));
  growTo(m, n);
  m.scene_handle.resize(m.live.size(), ~uint64_t(0));
  for (size_t i = 0; i < n; ++i) {
    scene::ObjectDesc desc;
    glm::mat4 world;
    fetch(i, desc, world);
    const int32_t level = drawn_levels.empty() ? 0 : drawn_levels[i];
    const scene::ObjectHandle h = sc.objectAt(i);
    const uint64_t key = (uint64_t(h.slot) << 32) | h.generation;
    const uint32_t id = static_cast<uint32_t>(i);
    if (m.live[i] && m.scene_handle[i] == key && m.chain[i] == desc.chain) {
      if (m.world[i] != world) setTransform(id, world);
      m.drawn_level[i] = level;
      continue;
    }
    // a different object now sits at this index: replace it under a new generation
    if (m.live[i]) removeObject(id);
    auto it = std::find(m.free_ids.rbegin(), m.free_ids.rend(), id);
    if (it != m.free_ids.rend()) m.free_ids.erase(std::next(it).base());
    placeObject(m, id, world, desc.chain, level);
    if (m.built) m.bvh.pending.push_back(id);
    m.scene_handle[i] = key;
  }
  return {};
}

void RayScene::setTransform(uint32_t id, const glm::mat4& world) {
  Impl& m = *impl_;
  m.world[id] = world;
  updateDerived(m, id);
  m.moved = true;
}

void RayScene::setDrawnLevel(uint32_t id, int32_t level) {
  Impl& m = *impl_;
  m.drawn_level[id] = level;
}

void RayScene::commit() {
  Impl& m = *impl_;
  if (!m.device) return;
  const size_t live_count = m.live.size() - m.free_ids.size();
  // rebuild when the tree is missing, when many objects wait outside it or sit dead in it, or when
  // refits loosened it (summed inner-node area doubled)
  const size_t slack = std::max<size_t>(64, live_count / 8);
  bool rebuild = !m.built || m.bvh.pending.size() > slack || m.dead_in_bvh > slack;
  if (!rebuild && m.moved) {
    m.bvh.refit(m.box_lo, m.box_hi);
    rebuild = m.bvh.area > 2.0f * m.bvh.built_area;
  }
  if (rebuild) {
    std::vector<uint32_t> ids;
    ids.reserve(live_count);
    for (size_t i = 0; i < m.live.size(); ++i)
      if (m.live[i]) ids.push_back(static_cast<uint32_t>(i));
    m.bvh.build(ids, m.box_lo, m.box_hi);
    m.built = true;
    m.dead_in_bvh = 0;
  }
  m.moved = false;
}

size_t RayScene::chainCount() const { return impl_->chains.size(); }
size_t RayScene::objectCapacity() const { return impl_->live.size(); }
bool RayScene::isLive(uint32_t id) const { return id < impl_->live.size() && impl_->live[id]; }
uint32_t RayScene::objectGeneration(uint32_t id) const { return impl_->generation[id]; }
uint32_t RayScene::chainOf(uint32_t id) const { return impl_->chain[id]; }
int32_t RayScene::drawnLevel(uint32_t id) const { return impl_->drawn_level[id]; }
int32_t RayScene::occluderLevel(uint32_t chain_id) const { return impl_->chains[chain_id].occluder_level; }
Span<const glm::vec4> RayScene::worldSpheres() const {
  return Span<const glm::vec4>(impl_->world_sphere.data(), impl_->world_sphere.size());
}
const glm::mat4& RayScene::worldTransform(uint32_t id) const { return impl_->world[id]; }
const RaySceneParams& RayScene::params() const { return impl_->params; }

}  // namespace scenelod::selection
