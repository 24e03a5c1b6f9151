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
constexpr uint32_t kNever = 0;  // generations of live objects start at 1

// Accepted world-space error of an occluder hit at ray parameter t: const + per_t * t, i.e.
// occluder_error_px pixels at distance t.
struct ErrorLimit {
  float at_zero = 0.0f;
  float per_t = 0.0f;
  float operator()(float t) const { return at_zero + per_t * t; }
};

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
  return scene.impl_ != nullptr && scene.impl_->device != nullptr;
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

  ErrorLimit limit;
  const float err_px = m.params.occluder_error_px;
  if (view.ortho) {
    limit.at_zero = err_px / view.px_per_unit_at_1;
  } else {
    limit.per_t = err_px / view.px_per_unit_at_1;
  }
  const float t_near = view.near_plane;

  const float rotation = std::fmod(static_cast<float>(s.frame % 100003u) * kGoldenAngle, 6.2831853f);
  for (size_t c = 0; c < test_count; ++c) {
    const uint32_t id = s.candidates[c];
    const glm::vec4 sph = m.world_sphere[id];
    const glm::vec3 center(sph);
    const float r = sph.w;
    const ChainPrototypes& proto = m.chains[m.chain[id]];
    RTCScene self_scene = proto.levels[static_cast<size_t>(proto.occluder_level)];

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
      // where the ray meets the object itself, at its occluder level
      float t_self = std::numeric_limits<float>::infinity();
      if (!intersectObject(m, id, self_scene, o, dir, t_near, t_self)) continue;
      ++counted;
      t_self *= 1.0f - 1e-4f;
      if (t_self <= t_near) continue;
      ++s.stats.occlusion_rays;
      bool blocked = false;
      traverse(m.bvh, m.box_lo, m.box_hi, o, dir, t_near, t_self,
               [&](uint32_t other, float t_enter, float t_exit, float& t_max) {
                 if (other == id || !m.live[other]) return false;  // never its own occluder
                 // cheap reject: the ray (unit direction) passes outside the bounding sphere
                 const glm::vec4 sp = m.world_sphere[other];
                 const glm::vec3 oc = glm::vec3(sp) - o;
                 const float along = glm::dot(oc, dir);
                 if (glm::dot(oc, oc) - along * along > sp.w * sp.w) return false;
                 const ChainPrototypes& op = m.chains[m.chain[other]];
                 RTCScene occluder = op.levels[static_cast<size_t>(op.occluder_level)];
                 const float e = m.occluder_error_world[other];
                 if (e <= limit(t_enter)) {
                   // every hit in the box is trusted
                   blocked = occludedByObject(m, other, occluder, o, dir, t_near, t_max);
                 } else if (e <= limit(std::min(t_exit, t_max))) {
                   // trusted only beyond some distance: find the hit and check it
                   float t_hit = t_max;
                   blocked = intersectObject(m, other, occluder, o, dir, t_near, t_hit) && e <= limit(t_hit);
                 }
                 return blocked;
               });
      if (blocked) ++hidden;
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
