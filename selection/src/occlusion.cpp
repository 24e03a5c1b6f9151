// Amortised occlusion estimate feeding the benefit of Funkhouser & Séquin 1993 (an object nobody can
// see gains nothing from detail). Samples follow a golden-angle (Vogel) disc, a stratified pattern of
// equal-area rings, facing the camera over the object's bounding-sphere footprint.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>

#include "ray_scene_impl.h"

namespace scenelod::selection {
namespace {

constexpr float kGoldenAngle = 2.39996323f;  // pi * (3 - sqrt(5))
constexpr uint32_t kNever = 0;               // generations of live objects start at 1

// The Embree context handed to the filter: RTCIntersectContext must stay the first member.
struct OcclusionContext {
  RTCIntersectContext base;
  uint32_t self = RTC_INVALID_GEOMETRY_ID;
  const float* occluder_error_world = nullptr;
  float error_limit_const = 0.0f;   // accepted world error at t: const + per_t * t
  float error_limit_per_t = 0.0f;
};

// Rejects hits on the tested object itself, and hits on occluders whose level's error projects to
// more than occluder_error_px pixels at the hit distance (Embree passes that distance in tfar).
void occluderFilter(const RTCFilterFunctionNArguments* args) {
  const auto* c = reinterpret_cast<const OcclusionContext*>(args->context);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    const unsigned inst = RTCHitN_instID(args->hit, args->N, i, 0);
    if (inst == c->self) {
      args->valid[i] = 0;
      continue;
    }
    const float t = RTCRayN_tfar(args->ray, args->N, i);
    if (c->occluder_error_world[inst] > c->error_limit_const + c->error_limit_per_t * t) args->valid[i] = 0;
  }
}

void fillRay(RTCRay& r, const glm::vec3& o, const glm::vec3& d, float t_near, float t_far) {
  r.org_x = o.x;
  r.org_y = o.y;
  r.org_z = o.z;
  r.dir_x = d.x;
  r.dir_y = d.y;
  r.dir_z = d.z;
  r.tnear = t_near;
  r.tfar = t_far;
  r.time = 0.0f;
  r.mask = 0xFFFFFFFFu;
  r.id = 0;
  r.flags = 0;
}

struct View {
  glm::vec3 eye, forward, right, up;
  bool ortho = false;
  float near_plane = 0.0f;
  float tan_half_y = 0.0f, tan_half_x = 0.0f;
  float half_h = 0.0f, half_w = 0.0f;     // orthographic
  float px_per_unit_at_1 = 0.0f;          // perspective: H / (2 tan(fov/2)); ortho: H / ortho_height
  // inward normals of the four side planes (perspective, through the eye)
  glm::vec3 side[4];
};

View makeView(const Camera& c) {
  View v;
  v.eye = c.eye;
  v.forward = glm::normalize(c.target - c.eye);
  v.right = glm::normalize(glm::cross(v.forward, c.up));
  v.up = glm::cross(v.right, v.forward);
  v.ortho = c.projection == Projection::kOrthographic;
  v.near_plane = v.ortho ? 0.0f : c.near_plane;
  const float w = static_cast<float>(std::max<uint32_t>(c.viewport_width_px, 1));
  const float h = static_cast<float>(std::max<uint32_t>(c.viewport_height_px, 1));
  v.tan_half_y = std::tan(0.5f * c.fov_y_rad);
  v.tan_half_x = v.tan_half_y * w / h;
  v.half_h = 0.5f * c.ortho_height;
  v.half_w = v.half_h * w / h;
  v.px_per_unit_at_1 = v.ortho ? h / c.ortho_height : h / (2.0f * v.tan_half_y);
  v.side[0] = glm::normalize(v.forward * v.tan_half_x + v.right);   // left plane
  v.side[1] = glm::normalize(v.forward * v.tan_half_x - v.right);   // right plane
  v.side[2] = glm::normalize(v.forward * v.tan_half_y + v.up);      // bottom plane
  v.side[3] = glm::normalize(v.forward * v.tan_half_y - v.up);      // top plane
  return v;
}

// Projected radius in pixels when the sphere is (partly) in the view volume and fully beyond the
// eye's own position; -1 when outside; +inf when the eye is inside the sphere.
float projectedRadiusPx(const View& v, const glm::vec4& s) {
  const glm::vec3 d = glm::vec3(s) - v.eye;
  const float r = s.w;
  const float depth = glm::dot(d, v.forward);
  if (depth + r <= v.near_plane) return -1.0f;
  if (v.ortho) {
    if (std::fabs(glm::dot(d, v.right)) > v.half_w + r || std::fabs(glm::dot(d, v.up)) > v.half_h + r) return -1.0f;
    return r * v.px_per_unit_at_1;
  }
  for (const glm::vec3& n : v.side)
    if (glm::dot(d, n) < -r) return -1.0f;
  const float dist2 = glm::dot(d, d);
  if (dist2 <= r * r) return std::numeric_limits<float>::infinity();
  return r * v.px_per_unit_at_1 / std::sqrt(dist2);
}

}  // namespace

struct OcclusionEstimator::State {
  OcclusionParams params;
  size_t max_objects = 0;
  uint64_t frame = 0;
  OcclusionStats stats;
  // per id
  std::vector<float> visible;                 // latest estimate
  std::vector<uint64_t> tested_frame;         // frame of that estimate
  std::vector<uint32_t> tested_generation;    // object generation it belongs to (kNever = none)
  std::vector<uint64_t> first_seen_frame;     // first frame this generation was a candidate
  std::vector<uint32_t> seen_generation;
  std::vector<float> priority;
  // scratch
  std::vector<uint32_t> candidates;
};

OcclusionEstimator::OcclusionEstimator() : state_(new State) {}
OcclusionEstimator::~OcclusionEstimator() { delete state_; }

Error OcclusionEstimator::init(size_t max_objects, const OcclusionParams& params) {
  if (max_objects == 0) return Error(Status::kInvalidArgument, "occlusion estimator: max_objects must be > 0");
  if (params.rays_per_test < 1 || params.rays_per_test > 256)
    return Error(Status::kInvalidArgument, "occlusion estimator: rays_per_test " +
                                               std::to_string(params.rays_per_test) + " outside [1, 256]");
  State& s = *state_;
  s = State();
  s.params = params;
  s.max_objects = max_objects;
  s.visible.assign(max_objects, 1.0f);
  s.tested_frame.assign(max_objects, 0);
  s.tested_generation.assign(max_objects, kNever);
  s.first_seen_frame.assign(max_objects, 0);
  s.seen_generation.assign(max_objects, kNever);
  s.priority.assign(max_objects, 0.0f);
  s.candidates.assign(max_objects, 0);
  return {};
}

bool OcclusionEstimator::validate(const RayScene& scene, Span<float> visible_fraction) const {
  const size_t cap = scene.objectCapacity();
  if (state_->max_objects == 0 || cap > state_->max_objects) return false;
  if (visible_fraction.count != 0 && (visible_fraction.data == nullptr || visible_fraction.count < cap)) return false;
  return scene.impl_ != nullptr && scene.impl_->occluder_scene != nullptr;
}

bool OcclusionEstimator::update(const RayScene& scene, const Camera& camera, Span<float> visible_fraction) {
  if (!validate(scene, visible_fraction)) return false;
  State& s = *state_;
  const RayScene::Impl& m = *scene.impl_;
  const size_t cap = scene.objectCapacity();
  ++s.frame;
  s.stats = OcclusionStats();
  const View view = makeView(camera);

  // priority pass over every live object
  size_t cand_count = 0;
  for (size_t id = 0; id < cap; ++id) {
    if (!m.live[id]) continue;
    const uint32_t gen = m.generation[id];
    const float r_px = projectedRadiusPx(view, m.world_sphere[id]);
    if (r_px < 0.0f) continue;
    if (std::isinf(r_px)) {
      // the eye is inside the bounding sphere: count the object as visible, as measured now
      s.visible[id] = 1.0f;
      s.tested_frame[id] = s.frame;
      s.tested_generation[id] = gen;
      continue;
    }
    if (s.seen_generation[id] != gen) {
      s.seen_generation[id] = gen;
      s.first_seen_frame[id] = s.frame;
    }
    const uint64_t age = s.tested_generation[id] == gen
                             ? s.frame - s.tested_frame[id]
                             : s.frame - s.first_seen_frame[id] + s.params.untested_age_frames;
    s.priority[id] = (1.0f + std::min(r_px, kMaxPriorityRadiusPx)) * static_cast<float>(age);
    s.candidates[cand_count++] = static_cast<uint32_t>(id);
  }
  s.stats.candidates = static_cast<uint32_t>(cand_count);

  const uint32_t n = s.params.rays_per_test;
  const size_t test_count = std::min<size_t>(cand_count, s.params.ray_budget / n);
  if (test_count < cand_count) {
    // highest priority first, ties by id: a strict order, so the chosen set is deterministic
    const float* prio = s.priority.data();
    std::nth_element(s.candidates.begin(), s.candidates.begin() + static_cast<std::ptrdiff_t>(test_count),
                     s.candidates.begin() + static_cast<std::ptrdiff_t>(cand_count),
                     [prio](uint32_t a, uint32_t b) { return prio[a] > prio[b] || (prio[a] == prio[b] && a < b); });
  }

  OcclusionContext ctx;
  rtcInitIntersectContext(&ctx.base);
  ctx.base.filter = occluderFilter;
  ctx.occluder_error_world = m.occluder_error_world.data();
  const float err_px = m.params.occluder_error_px;
  if (view.ortho) {
    ctx.error_limit_const = err_px / view.px_per_unit_at_1;
  } else {
    ctx.error_limit_per_t = err_px / view.px_per_unit_at_1;
  }
  RTCIntersectContext plain;
  rtcInitIntersectContext(&plain);

  const float rotation = std::fmod(static_cast<float>(s.frame % 100003u) * kGoldenAngle, 6.2831853f);
  for (size_t c = 0; c < test_count; ++c) {
    const uint32_t id = s.candidates[c];
    const glm::vec4 sph = m.world_sphere[id];
    const glm::vec3 center(sph);
    const float r = sph.w;
    const ChainPrototypes& proto = m.chains[m.chain[id]];
    RTCScene self_scene = proto.levels[static_cast<size_t>(proto.occluder_level)];
    const glm::mat4& inv = m.inverse_world[id];

    glm::vec3 w;
    float disc_r = r;
    if (view.ortho) {
      w = view.forward;
    } else {
      const glm::vec3 d = center - view.eye;
      const float dist = glm::length(d);
      w = d / dist;
      // the disc through the centre that fills the sphere's tangent cone
      disc_r = r * dist / std::sqrt(std::max(dist * dist - r * r, 1e-12f));
    }
    const glm::vec3 ref = std::fabs(glm::dot(w, view.up)) < 0.9f ? view.up : view.right;
    const glm::vec3 u = glm::normalize(glm::cross(w, ref));
    const glm::vec3 v = glm::cross(u, w);

    ctx.self = id;
    uint32_t counted = 0, hidden = 0;
    for (uint32_t k = 0; k < n; ++k) {
      const float rho = disc_r * std::sqrt((static_cast<float>(k) + 0.5f) / static_cast<float>(n));
      const float th = static_cast<float>(k) * kGoldenAngle + rotation;
      const glm::vec3 p = center + rho * (std::cos(th) * u + std::sin(th) * v);
      glm::vec3 o, dir;
      if (view.ortho) {
        dir = w;
        o = p - w * glm::dot(p - view.eye, w);
      } else {
        o = view.eye;
        dir = glm::normalize(p - view.eye);
      }
      // where the ray meets the object itself (its occluder level, in object space; an affine map
      // keeps the ray parameter t)
      RTCRayHit self;
      const glm::vec3 lo(inv * glm::vec4(o, 1.0f));
      const glm::vec3 ld(inv * glm::vec4(dir, 0.0f));
      fillRay(self.ray, lo, ld, view.near_plane, std::numeric_limits<float>::infinity());
      self.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      self.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(self_scene, &plain, &self);
      if (self.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
      ++counted;
      const float t_self = self.ray.tfar * (1.0f - 1e-4f);
      if (t_self <= view.near_plane) continue;
      RTCRay occ;
      fillRay(occ, o, dir, view.near_plane, t_self);
      rtcOccluded1(m.occluder_scene, &ctx.base, &occ);
      ++s.stats.occlusion_rays;
      if (occ.tfar == -std::numeric_limits<float>::infinity()) ++hidden;
    }
    s.stats.samples += n;
    s.stats.self_hits += counted;
    ++s.stats.objects_tested;
    s.visible[id] = counted ? static_cast<float>(counted - hidden) / static_cast<float>(counted) : 1.0f;
    s.tested_frame[id] = s.frame;
    s.tested_generation[id] = m.generation[id];
  }

  if (visible_fraction.count) {
    for (size_t id = 0; id < cap; ++id)
      visible_fraction[id] = (m.live[id] && s.tested_generation[id] == m.generation[id]) ? s.visible[id] : 1.0f;
  }
  return true;
}

float OcclusionEstimator::visibleFraction(const RayScene& scene, uint32_t id) const {
  const State& s = *state_;
  if (!scene.isLive(id) || id >= s.max_objects || s.tested_generation[id] != scene.objectGeneration(id)) return 1.0f;
  return s.visible[id];
}

uint32_t OcclusionEstimator::ageFrames(const RayScene& scene, uint32_t id) const {
  const State& s = *state_;
  if (!scene.isLive(id) || id >= s.max_objects || s.tested_generation[id] != scene.objectGeneration(id))
    return std::numeric_limits<uint32_t>::max();
  return static_cast<uint32_t>(std::min<uint64_t>(s.frame - s.tested_frame[id], 0xFFFFFFFEu));
}

const OcclusionStats& OcclusionEstimator::lastStats() const { return state_->stats; }
uint64_t OcclusionEstimator::frameCount() const { return state_->frame; }

}  // namespace scenelod::selection
