// Amortised occlusion estimate feeding the benefit of Funkhouser & Séquin 1993 (an object nobody can
// see gains nothing from detail). Samples follow a golden-angle (Vogel) disc, a stratified pattern of
// equal-area rings, facing the camera over the object's bounding-sphere footprint.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>
#if defined(__SSE2__)
#include <emmintrin.h>
#include <xmmintrin.h>
#endif

#include "ray_scene_impl.h"

namespace scenelod::selection {
namespace {

constexpr float kGoldenAngle = 2.39996323f;  // pi * (3 - sqrt(5))
constexpr uint32_t kNever = 0;  // generations of live objects start at 1
// radix selection of the highest priorities: buckets over the top bits of the (positive) float
constexpr int kBucketShift = 18;

// Number of set bits (SWAR: no library call on targets without a popcount instruction).
inline uint32_t bitCount(uint32_t v) {
  v = v - ((v >> 1) & 0x55555555u);
  v = (v & 0x33333333u) + ((v >> 2) & 0x33333333u);
  return (((v + (v >> 4)) & 0x0F0F0F0Fu) * 0x01010101u) >> 24;
}
constexpr size_t kBuckets = size_t(1) << (32 - kBucketShift);

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

// Projected radius in pixels of sphere i when it is live, (partly) in the view volume and fully
// beyond the eye's own position; -1 otherwise; +inf when the eye is inside the sphere.
inline float projectRadius(const View& v, const glm::vec4& s, bool live) {
  const glm::vec3 d = glm::vec3(s) - v.eye;
  const float r = s.w;
  const float depth = glm::dot(d, v.forward);
  bool in = live && depth + r > v.near_plane;
  if (v.ortho) {
    in = in && std::fabs(glm::dot(d, v.right)) <= v.half_w + r && std::fabs(glm::dot(d, v.up)) <= v.half_h + r;
    return in ? r * v.px_per_unit_at_1 : -1.0f;
  }
  for (const glm::vec3& n : v.side) in = in && glm::dot(d, n) >= -r;
  if (!in) return -1.0f;
  const float dist2 = glm::dot(d, d);
  if (dist2 <= r * r) return std::numeric_limits<float>::infinity();
  return r * v.px_per_unit_at_1 / std::sqrt(dist2);
}

// Columns the priority pass reads and writes (object side and estimator side).
struct PriorityColumns {
  const glm::vec4* spheres;
  const uint8_t* live;
  const uint32_t* generation;
  uint32_t* seen_generation;
  uint32_t* age_origin;
  float* priority;
  // eye inside the sphere: the object reads as tested now and visible
  float* visible;
  uint64_t* tested_frame;
  uint32_t* tested_generation;
};

// The per-object rule of the priority pass, given its projected radius (see projectRadius):
// returns its priority, or -1 when it is not a candidate.
inline float prioritize(const PriorityColumns& c, size_t id, float r_px, uint64_t frame, uint32_t untested_origin) {
  if (!(r_px >= 0.0f)) return -1.0f;
  const uint32_t gen = c.generation[id];
  const uint32_t frame32 = static_cast<uint32_t>(frame);
  if (std::isinf(r_px)) {
    c.visible[id] = 1.0f;
    c.tested_frame[id] = frame;
    c.tested_generation[id] = gen;
    c.age_origin[id] = frame32;
    c.seen_generation[id] = gen;
    return -1.0f;
  }
  if (c.seen_generation[id] != gen) {
    // first frame this object (generation) is a candidate: it counts as tested untested_age_frames
    // ago; a test sets the origin to the test's frame
    c.seen_generation[id] = gen;
    c.age_origin[id] = untested_origin;
  }
  const float age = static_cast<float>(static_cast<int32_t>(frame32 - c.age_origin[id]));
  return (1.0f + std::min(r_px, OcclusionEstimator::kMaxPriorityRadiusPx)) * age;
}

// Writes every id's priority (-1 when not a candidate) and returns the number of candidates. With
// SSE2 (perspective cameras), four objects at a time without branches except for the rare objects
// whose eye-inside or first-seen state must be written, which take the scalar rule; the results
// are the scalar rule's, bit for bit.
size_t priorityPass(const View& v, const PriorityColumns& c, size_t count, uint64_t frame, uint32_t untested_age) {
  const uint32_t untested_origin = static_cast<uint32_t>(frame) - untested_age;  // wraps: ages are differences
  size_t i = 0, candidates = 0;
#if defined(__SSE2__)
  if (!v.ortho) {
    const __m128 ex = _mm_set1_ps(v.eye.x), ey = _mm_set1_ps(v.eye.y), ez = _mm_set1_ps(v.eye.z);
    const __m128 fx = _mm_set1_ps(v.forward.x), fy = _mm_set1_ps(v.forward.y), fz = _mm_set1_ps(v.forward.z);
    const __m128 near_plane = _mm_set1_ps(v.near_plane), ppu = _mm_set1_ps(v.px_per_unit_at_1);
    const __m128 minus_one = _mm_set1_ps(-1.0f), one = _mm_set1_ps(1.0f);
    const __m128 max_r_px = _mm_set1_ps(OcclusionEstimator::kMaxPriorityRadiusPx);
    const __m128i frame32 = _mm_set1_epi32(static_cast<int>(static_cast<uint32_t>(frame)));
    const __m128 zero = _mm_setzero_ps();
    __m128 nx[4], ny[4], nz[4];
    for (int k = 0; k < 4; ++k) {
      nx[k] = _mm_set1_ps(v.side[k].x);
      ny[k] = _mm_set1_ps(v.side[k].y);
      nz[k] = _mm_set1_ps(v.side[k].z);
    }
    for (; i + 4 <= count; i += 4) {
      __m128 x = _mm_loadu_ps(&c.spheres[i].x), y = _mm_loadu_ps(&c.spheres[i + 1].x);
      __m128 z = _mm_loadu_ps(&c.spheres[i + 2].x), r = _mm_loadu_ps(&c.spheres[i + 3].x);
      _MM_TRANSPOSE4_PS(x, y, z, r);
      const __m128 dx = _mm_sub_ps(x, ex), dy = _mm_sub_ps(y, ey), dz = _mm_sub_ps(z, ez);
      const __m128 depth = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, fx), _mm_mul_ps(dy, fy)), _mm_mul_ps(dz, fz));
      uint32_t live4;
      std::memcpy(&live4, c.live + i, 4);
      const __m128i live_bytes = _mm_cvtsi32_si128(static_cast<int>(live4));
      const __m128i live_words = _mm_unpacklo_epi16(_mm_unpacklo_epi8(live_bytes, _mm_setzero_si128()), _mm_setzero_si128());
      __m128 in = _mm_castsi128_ps(_mm_cmpgt_epi32(live_words, _mm_setzero_si128()));
      in = _mm_and_ps(in, _mm_cmpgt_ps(_mm_add_ps(depth, r), near_plane));
      const __m128 minus_r = _mm_sub_ps(zero, r);
      for (int k = 0; k < 4; ++k) {
        const __m128 dn = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, nx[k]), _mm_mul_ps(dy, ny[k])), _mm_mul_ps(dz, nz[k]));
        in = _mm_and_ps(in, _mm_cmpge_ps(dn, minus_r));
      }
      const int in_mask = _mm_movemask_ps(in);
      if (in_mask == 0) {
        _mm_storeu_ps(c.priority + i, minus_one);
        continue;
      }
      const __m128 dist2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
      const __m128 inside = _mm_cmple_ps(dist2, _mm_mul_ps(r, r));
      const __m128 px = _mm_div_ps(_mm_mul_ps(r, ppu), _mm_sqrt_ps(dist2));
      const __m128i same_gen = _mm_cmpeq_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(c.generation + i)),
                                               _mm_loadu_si128(reinterpret_cast<const __m128i*>(c.seen_generation + i)));
      const int special = in_mask & (_mm_movemask_ps(inside) | (~_mm_movemask_ps(_mm_castsi128_ps(same_gen)) & 15));
      if (special != 0) {
        // eye inside a sphere or a first sighting: the scalar rule writes that object's state
        float px_lanes[4], prio[4];
        _mm_storeu_ps(px_lanes, px);
        const int inside_mask = _mm_movemask_ps(inside);
        for (int k = 0; k < 4; ++k) {
          const float r_px = (in_mask >> k & 1) ? ((inside_mask >> k & 1) ? std::numeric_limits<float>::infinity() : px_lanes[k]) : -1.0f;
          prio[k] = prioritize(c, i + static_cast<size_t>(k), r_px, frame, untested_origin);
          candidates += prio[k] >= 0.0f ? 1 : 0;
        }
        _mm_storeu_ps(c.priority + i, _mm_loadu_ps(prio));
        continue;
      }
      const __m128i origin = _mm_loadu_si128(reinterpret_cast<const __m128i*>(c.age_origin + i));
      const __m128 age = _mm_cvtepi32_ps(_mm_sub_epi32(frame32, origin));
      const __m128 prio = _mm_mul_ps(_mm_add_ps(one, _mm_min_ps(px, max_r_px)), age);
      _mm_storeu_ps(c.priority + i, _mm_or_ps(_mm_and_ps(in, prio), _mm_andnot_ps(in, minus_one)));
      candidates += bitCount(static_cast<uint32_t>(in_mask));
    }
  }
#endif
  for (; i < count; ++i) {
    c.priority[i] = prioritize(c, i, projectRadius(v, c.spheres[i], c.live[i] != 0), frame, untested_origin);
    candidates += c.priority[i] >= 0.0f ? 1 : 0;
  }
  return candidates;
}

uint32_t floatBits(float f) {
  uint32_t b;
  std::memcpy(&b, &f, sizeof b);
  return b;
}

// Writes to keys[0, k) the k candidates of highest priority (ties: lower id first) as
// (priority bits << 32 | ~id), in no particular order; 0 < k <= candidate count. A histogram over
// the top bits of the priorities finds the bucket holding the k-th largest key, the buckets above
// are taken whole, and only that bucket's keys are ordered. Keys are distinct (the low half is the
// id), so the chosen set is the one a full sort would give. O(count); `histogram` holds kBuckets.
void chooseLargest(const float* priority, size_t count, size_t k, size_t candidates, uint32_t* histogram,
                   uint64_t* keys) {
  // keys with bits >= take_bits go first; keys with bits in [order_bits, take_bits) are ordered
  uint32_t take_bits = 0, order_bits = 0;
  size_t above = 0;
  if (k < candidates) {
    std::fill(histogram, histogram + kBuckets, 0u);
    for (size_t i = 0; i < count; ++i)
      if (priority[i] >= 0.0f) ++histogram[floatBits(priority[i]) >> kBucketShift];
    size_t bucket = kBuckets;
    while (bucket-- > 0) {
      if (above + histogram[bucket] >= k) break;
      above += histogram[bucket];
    }
    order_bits = static_cast<uint32_t>(bucket) << kBucketShift;
    take_bits = bucket + 1 < kBuckets ? static_cast<uint32_t>(bucket + 1) << kBucketShift : 0xFFFFFFFFu;
  }
  // priorities are >= 0 for candidates, so their bits order like the values; -1 fails both tests
  const float order_from = [&] {
    float f;
    std::memcpy(&f, &order_bits, sizeof f);
    return f;
  }();
  size_t front = 0, back = above;
  auto place = [&](size_t i) {
    const uint32_t bits = floatBits(priority[i]);
    const uint64_t key = (uint64_t(bits) << 32) | ~static_cast<uint32_t>(i);
    if (bits >= take_bits) {
      keys[front++] = key;
    } else {
      keys[back++] = key;
    }
  };
  size_t i = 0;
#if defined(__SSE2__)
  const __m128 from = _mm_set1_ps(order_from);
  for (; i + 4 <= count; i += 4) {
    const int mask = _mm_movemask_ps(_mm_cmpge_ps(_mm_loadu_ps(priority + i), from));
    for (int m = mask; m != 0; m &= m - 1) place(i + static_cast<size_t>(__builtin_ctz(static_cast<unsigned>(m))));
  }
#endif
  for (; i < count; ++i)
    if (priority[i] >= order_from) place(i);
  if (k < candidates) std::nth_element(keys + above, keys + (k - 1), keys + back, std::greater<uint64_t>());
}

// Interleaves the low 16 bits of x and y (Morton order).
uint32_t interleave(uint32_t x, uint32_t y) {
  auto spread = [](uint32_t v) {
    v &= 0xFFFFu;
    v = (v | (v << 8)) & 0x00FF00FFu;
    v = (v | (v << 4)) & 0x0F0F0F0Fu;
    v = (v | (v << 2)) & 0x33333333u;
    v = (v | (v << 1)) & 0x55555555u;
    return v;
  };
  return spread(x) | (spread(y) << 1);
}

// Morton code of where a point lies on the screen (clamped to it; points behind the eye go to an
// edge): nearby codes mean nearby view directions.
uint32_t screenCode(const View& v, const glm::vec3& p) {
  const glm::vec3 d = p - v.eye;
  float x, y;
  if (v.ortho) {
    x = glm::dot(d, v.right) / std::max(v.half_w, 1e-30f);
    y = glm::dot(d, v.up) / std::max(v.half_h, 1e-30f);
  } else {
    const float depth = std::max(glm::dot(d, v.forward), 1e-30f);
    x = glm::dot(d, v.right) / (depth * v.tan_half_x);
    y = glm::dot(d, v.up) / (depth * v.tan_half_y);
  }
  auto cell = [](float t) {
    const float c = (std::min(std::max(t, -1.0f), 1.0f) + 1.0f) * 511.5f;  // NaN-free: clamped first
    return static_cast<uint32_t>(c);
  };
  return interleave(cell(x), cell(y));
}

// The rays of one test (perspective: a cone from the eye around the axis to the object's centre,
// half-angle asin(r / D); orthographic: a cylinder of radius r along the view direction through the
// object's centre, from the eye's plane), as far as t_end (the far side of the object's bounding
// sphere, beyond which nothing can hide it).
struct Beam {
  glm::vec3 apex{0.0f}, axis{0.0f};
  bool ortho = false;
  float sin_a = 0.0f, cos_a = 1.0f;  // perspective
  float radius = 0.0f;               // orthographic
  float t_near = 0.0f, t_end = 0.0f;
  // for tree nodes: every beam point lies within `reach` (the beam's radius at t_end) of the axis
  // segment from the apex to depth t_end, so a node box is met only if the segment crosses the box
  // grown by `reach`
  float reach = 0.0f;
  glm::vec3 inv_axis{0.0f};

  void finish() {
    reach = ortho ? radius : t_end * sin_a / std::max(cos_a, 1e-6f);
    inv_axis = glm::vec3(1.0f / axis.x, 1.0f / axis.y, 1.0f / axis.z);
  }
  // Conservative: false only when no ray of the beam reaches the box; writes the axis depth where
  // the segment enters the grown box (for near-first ordering).
  bool meetsBox(const glm::vec3& lo, const glm::vec3& hi, float& depth) const {
    float exit;
    return rayBox(apex, inv_axis, lo - glm::vec3(reach), hi + glm::vec3(reach), 0.0f, t_end, depth, exit);
  }

  // Conservative: false only when no ray of the beam meets the sphere (p, rho) within
  // [t_near, t_end]. Perspective: perp * cos(a) - along * sin(a) is at most the distance from p to
  // the cone (exact where the nearest cone point is on its side, smaller elsewhere).
  bool meets(const glm::vec3& p, float rho) const {
    const glm::vec3 q = p - apex;
    const float along = glm::dot(q, axis);
    const float q2 = glm::dot(q, q);
    const float perp = std::sqrt(std::max(q2 - along * along, 0.0f));
    if (ortho) return along + rho >= t_near && along - rho <= t_end && perp <= radius + rho;
    const float dist = std::sqrt(q2);
    return dist + rho >= t_near && dist - rho <= t_end && perp * cos_a - along * sin_a <= rho;
  }
};

// Calls visit(id) for the live objects other than `self` whose bounding spheres the beam meets,
// nearer along the axis roughly first (the tree is walked nearer child first), until visit returns
// true. Tree nodes are tested as boxes against the beam's axis segment (Beam::meetsBox). No
// allocation.
template <class Visit>
void forEachCandidate(const RayScene::Impl& m, const Beam& beam, uint32_t self, Visit&& visit) {
  auto take = [&](uint32_t id) {
    const glm::vec4 sp = m.world_sphere[id];
    return id != self && m.live[id] && beam.meets(glm::vec3(sp), sp.w) && visit(id);
  };
  const TopBvh& bvh = m.bvh;
  if (!bvh.nodes.empty()) {
    uint32_t stack[TopBvh::kStackSize];
    int top = 0;
    float depth_l, depth_r;
    // an emptied tree (all objects removed) has an inverted box, which the slab test rejects
    if (beam.meetsBox(bvh.nodes[0].lo, bvh.nodes[0].hi, depth_l)) stack[top++] = 0;
    while (top > 0) {
      const TopBvh::Node& n = bvh.nodes[stack[--top]];
      if (n.count > 0) {
        for (uint32_t k = n.first; k < n.first + n.count; ++k)
          if (take(bvh.items[k])) return;
        continue;
      }
      const TopBvh::Node& l = bvh.nodes[n.first];
      const TopBvh::Node& r = bvh.nodes[n.first + 1];
      const bool hit_l = beam.meetsBox(l.lo, l.hi, depth_l);
      const bool hit_r = beam.meetsBox(r.lo, r.hi, depth_r);
      if (top + 2 > TopBvh::kStackSize) continue;  // cannot happen: the median split keeps depth ~log2(n)
      // push the farther child first so the nearer one is popped next
      if (depth_l <= depth_r) {
        if (hit_r) stack[top++] = n.first + 1;
        if (hit_l) stack[top++] = n.first;
      } else {
        if (hit_l) stack[top++] = n.first;
        if (hit_r) stack[top++] = n.first + 1;
      }
    }
  }
  for (uint32_t id : bvh.pending)
    if (take(id)) return;
}

constexpr uint32_t kChunk = 16;  // rays handled together (bit masks of 16)
constexpr uint32_t kMaxChunks = 256 / kChunk;  // rays_per_test <= 256

struct RaysSoA {
  float ox[kChunk], oy[kChunk], oz[kChunk], dx[kChunk], dy[kChunk], dz[kChunk];
  void set(uint32_t k, const glm::vec3& o, const glm::vec3& d) {
    ox[k] = o.x;
    oy[k] = o.y;
    oz[k] = o.z;
    dx[k] = d.x;
    dy[k] = d.y;
    dz[k] = d.z;
  }
  glm::vec3 origin(uint32_t k) const { return {ox[k], oy[k], oz[k]}; }
  glm::vec3 direction(uint32_t k) const { return {dx[k], dy[k], dz[k]}; }
};

// The level of object `other` to test a ray against when its hits may lie no nearer than where the
// ray enters the object's box, where `allowed` world units of error project to occluder_error_px
// pixels: the coarsest level from the occluder level down whose world error is within `allowed`,
// level 0 (the mesh itself, exact) when none is. Levels without triangles are skipped.
inline RTCScene traceLevel(const ChainPrototypes& p, float scale, float allowed) {
  int32_t l = p.occluder_level;
  while (l > 0 && (p.levels[static_cast<size_t>(l)] == nullptr || p.max_error[static_cast<size_t>(l)] * scale > allowed)) --l;
  return p.levels[static_cast<size_t>(l)];
}

// Tests the rays in `active` (bit k = ray k) against object `other`, each within [t_start[k], t_end[k]]:
// first against its bounding sphere (world space), then, in object space, against its chain's box,
// whose entry distance t_box is a lower bound of any hit's distance; the ray is then traced at the
// coarsest level whose world error projects to at most occluder_error_px pixels at t_box (level 0
// when no coarser one is trusted there), so every hit that blocks is trusted at its own distance.
// Returns `active` without the rays it blocks; counts its Embree queries in `embree_rays`.
template <class Limit>
uint32_t blockRays(const RayScene::Impl& m, uint32_t other, const RaysSoA& rays, uint32_t active,
                   const float* t_start, const float* t_end, const Limit& limit, uint32_t& embree_rays) {
  const glm::vec4 sp = m.world_sphere[other];
  const float r2 = sp.w * sp.w;
  const ChainPrototypes& op = m.chains[m.chain[other]];
  const float scale = m.largest_scale[other];
  const glm::mat4& inv = m.inverse_world[other];
  // the rays that reach the object's box, with the level each is traced at
  RTCScene pend_level[kChunk];
  uint32_t pend_lane[kChunk];
  glm::vec3 pend_o[kChunk], pend_d[kChunk];
  uint32_t pending = 0;
  for (uint32_t left = active; left != 0; left &= left - 1) {
    const uint32_t k = static_cast<uint32_t>(__builtin_ctz(left));
    const float ocx = sp.x - rays.ox[k], ocy = sp.y - rays.oy[k], ocz = sp.z - rays.oz[k];
    const float along = ocx * rays.dx[k] + ocy * rays.dy[k] + ocz * rays.dz[k];
    const float miss2 = ocx * ocx + ocy * ocy + ocz * ocz - along * along;
    if (miss2 > r2) continue;
    const float half = std::sqrt(r2 - miss2);
    if (std::max(along - half, t_start[k]) > std::min(along + half, t_end[k])) continue;
    // object space keeps the ray parameter t
    const glm::vec3 o(inv * glm::vec4(rays.origin(k), 1.0f));
    const glm::vec3 d(inv * glm::vec4(rays.direction(k), 0.0f));
    float t_box, t_box_exit;
    if (!rayBox(o, glm::vec3(1.0f / d.x, 1.0f / d.y, 1.0f / d.z), op.box_lo, op.box_hi, t_start[k], t_end[k], t_box,
                t_box_exit))
      continue;
    const RTCScene level = traceLevel(op, scale, limit(t_box));
    pend_level[pending] = level;
    pend_lane[pending] = k;
    pend_o[pending] = o;
    pend_d[pending] = d;
    ++pending;
  }
  // 8-ray packets (rtcOccluded8, native on AVX2; 16 is emulated there), one level at a time; a
  // lone ray goes alone. 1.3x faster than one rtcOccluded1 per ray at 100,000 objects
  // (docs/bench/visibility.md)
  uint32_t done = 0;
  while (done != (1u << pending) - 1u) {
    const uint32_t first = static_cast<uint32_t>(__builtin_ctz(~done));
    const RTCScene level = pend_level[first];
    alignas(32) RTCRay8 r8;
    alignas(32) int valid[8];
    uint32_t lane_of[8];
    uint32_t count = 0;
    for (uint32_t i = first; i < pending && count < 8; ++i) {
      if ((done >> i & 1u) || pend_level[i] != level) continue;
      done |= 1u << i;
      const uint32_t k = pend_lane[i];
      r8.org_x[count] = pend_o[i].x;
      r8.org_y[count] = pend_o[i].y;
      r8.org_z[count] = pend_o[i].z;
      r8.dir_x[count] = pend_d[i].x;
      r8.dir_y[count] = pend_d[i].y;
      r8.dir_z[count] = pend_d[i].z;
      r8.tnear[count] = t_start[k];
      r8.tfar[count] = t_end[k];
      r8.time[count] = 0.0f;
      r8.mask[count] = 0xFFFFFFFFu;
      r8.id[count] = 0;
      r8.flags[count] = 0;
      valid[count] = -1;
      lane_of[count] = k;
      ++count;
    }
    for (uint32_t j = count; j < 8; ++j) valid[j] = 0;
    if (count == 1) {
      ++embree_rays;
      if (occludedInObjectSpace(level, pend_o[first], pend_d[first], t_start[lane_of[0]], t_end[lane_of[0]]))
        active &= ~(1u << lane_of[0]);
      continue;
    }
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    rtcOccluded8(valid, level, &ctx, &r8);
    embree_rays += count;
    for (uint32_t j = 0; j < count; ++j)
      if (r8.tfar[j] < 0.0f) active &= ~(1u << lane_of[j]);
  }
  return active;
}

// The beam from the eye around an object's bounding sphere (centre, radius r): a cone (perspective)
// or the object's own line of sight (orthographic); `disc_r` gets the radius of the disc through the
// centre, across the axis, that fills the sphere's outline.
Beam objectBeam(const View& view, const glm::vec3& center, float r, float& disc_r) {
  Beam beam;
  beam.apex = view.eye;
  beam.ortho = view.ortho;
  beam.t_near = view.near_plane;
  disc_r = r;
  if (view.ortho) {
    // parallel rays from the eye's plane: the beam's axis is the object's own line of sight
    beam.axis = view.forward;
    beam.apex = center - beam.axis * glm::dot(center - view.eye, beam.axis);
    beam.radius = r;
    beam.t_end = glm::dot(center - beam.apex, beam.axis) + r;
  } else {
    const glm::vec3 d = center - view.eye;
    const float dist = glm::length(d);
    beam.axis = d / dist;
    // the disc through the centre that fills the sphere's tangent cone
    disc_r = r * dist / std::sqrt(std::max(dist * dist - r * r, 1e-12f));
    beam.sin_a = std::min(r / dist, 1.0f);
    beam.cos_a = std::sqrt(std::max(1.0f - beam.sin_a * beam.sin_a, 0.0f));
    beam.t_end = dist + r;
  }
  beam.finish();
  return beam;
}

// Visible fractions out, per id: the latest estimate while the id is live and its object is the one
// tested, 1 otherwise.
void writeVisibleFractions(const uint8_t* live, const uint32_t* gen, const uint32_t* tested_gen, const float* vis,
                           size_t cap, float* out) {
  size_t id = 0;
#if defined(__SSE2__)
  const __m128 one = _mm_set1_ps(1.0f);
  for (; id + 4 <= cap; id += 4) {
    uint32_t live4;
    std::memcpy(&live4, live + id, 4);
    const __m128i lb = _mm_cvtsi32_si128(static_cast<int>(live4));
    const __m128i lw = _mm_unpacklo_epi16(_mm_unpacklo_epi8(lb, _mm_setzero_si128()), _mm_setzero_si128());
    const __m128i same = _mm_cmpeq_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(tested_gen + id)),
                                         _mm_loadu_si128(reinterpret_cast<const __m128i*>(gen + id)));
    const __m128 keep = _mm_castsi128_ps(_mm_and_si128(same, _mm_cmpgt_epi32(lw, _mm_setzero_si128())));
    _mm_storeu_ps(out + id, _mm_or_ps(_mm_and_ps(keep, _mm_loadu_ps(vis + id)), _mm_andnot_ps(keep, one)));
  }
#endif
  for (; id < cap; ++id) out[id] = (live[id] != 0) & (tested_gen[id] == gen[id]) ? vis[id] : 1.0f;
}

}  // namespace

struct OcclusionEstimator::State {
  OcclusionParams params;
  size_t max_objects = 0;
  uint64_t frame = 0;
  // the disc pattern, rays_per_test entries: sqrt((k + 0.5) / n), cos and sin of k * golden angle
  std::vector<glm::vec3> pattern;
  OcclusionStats stats;
  // per id, read by the priority pass every frame
  std::vector<float> priority;                // 4 B: this frame's priority, -1 when not a candidate
  std::vector<uint32_t> age_origin;           // 4 B: age = frame - age_origin (low 32 bits of the frame
                                              //      of the test, or of first seen minus untested_age_frames)
  std::vector<uint32_t> seen_generation;      // 4 B: object generation age_origin belongs to (kNever = none)
  // per id, read by the output pass and the queries
  std::vector<float> visible;                 // 4 B: latest estimate
  std::vector<uint64_t> tested_frame;         // 8 B: frame of that estimate
  std::vector<uint32_t> tested_generation;    // 4 B: object generation it belongs to (kNever = none)
  // scratch: candidates as (priority bits << 32 | ~id), so one integer order is "priority down, id up"
  std::vector<uint64_t> keys;                 // the chosen objects, then (screen code << 32 | id)
  std::vector<uint32_t> histogram;            // kBuckets counters over the top bits of the priority

  // One object's test: rays_per_test samples over the disc that fills its outline (the pattern turned
  // by the frame's rotation), each counted when it meets the object at its occluder level and hidden
  // when another object blocks it first; updates the object's estimate and the statistics.
  void testObject(const RayScene::Impl& m, const View& view, const ErrorLimit& limit, float cos_rot, float sin_rot,
                  uint32_t id);
};

void OcclusionEstimator::State::testObject(const RayScene::Impl& m, const View& view, const ErrorLimit& limit,
                                           float cos_rot, float sin_rot, uint32_t id) {
  const glm::vec4 sph = m.world_sphere[id];
  const glm::vec3 center(sph);
  const ChainPrototypes& proto = m.chains[m.chain[id]];
  RTCScene self_scene = proto.levels[static_cast<size_t>(proto.occluder_level)];
  const float t_near = view.near_plane;
  float disc_r = sph.w;
  const Beam beam = objectBeam(view, center, sph.w, disc_r);
  const glm::vec3 w = beam.axis;
  const glm::vec3 ref = std::fabs(glm::dot(w, view.up)) < 0.9f ? view.up : view.right;
  const glm::vec3 u0 = glm::normalize(glm::cross(w, ref));
  const glm::vec3 v0 = glm::cross(u0, w);
  // the frame's rotation of the pattern, applied to the disc's axes
  const glm::vec3 u = cos_rot * u0 + sin_rot * v0;
  const glm::vec3 v = cos_rot * v0 - sin_rot * u0;

  const uint32_t n = params.rays_per_test;
  const uint32_t chunks = (n + kChunk - 1) / kChunk;
  RaysSoA rays[kMaxChunks];
  float t_sphere[kMaxChunks][kChunk];  // where each ray enters the object's bounding sphere
  uint32_t open[kMaxChunks];           // rays not blocked before the bounding sphere
  const float r2 = sph.w * sph.w;
  bool any_open = false;
  // 1. occluders in front of the object's bounding sphere, for every ray: when they block all of
  //    them the object is hidden whichever rays meet it, and it needs no ray against itself
  for (uint32_t c = 0; c < chunks; ++c) {
    const uint32_t k0 = c * kChunk, lanes = std::min(kChunk, n - k0);
    float t_start[kChunk];
    for (uint32_t k = 0; k < lanes; ++k) {
      const glm::vec3 pat = pattern[k0 + k];
      const glm::vec3 p = center + (disc_r * pat.x) * (pat.y * u + pat.z * v);
      glm::vec3 o, dir;
      if (view.ortho) {
        dir = w;
        o = p - w * glm::dot(p - view.eye, w);
      } else {
        o = view.eye;
        dir = glm::normalize(p - view.eye);
      }
      rays[c].set(k, o, dir);
      // the squared miss distance from a cross product: |oc|^2 - along^2 cancels far from the eye
      const glm::vec3 oc = center - o;
      const float along = glm::dot(oc, dir);
      const glm::vec3 across = glm::cross(oc, dir);
      const float miss2 = glm::dot(across, across);
      t_sphere[c][k] = std::max(miss2 < r2 ? along - std::sqrt(r2 - miss2) : along, t_near);
      t_start[k] = t_near;
    }
    uint32_t active = lanes == 32 ? ~0u : (1u << lanes) - 1u;
    stats.occlusion_rays += lanes;
    forEachCandidate(m, beam, id, [&](uint32_t other) {
      ++stats.occluder_candidates;
      active = blockRays(m, other, rays[c], active, t_start, t_sphere[c], limit, stats.embree_rays);
      return active == 0;
    });
    open[c] = active;
    any_open = any_open || active != 0;
  }
  uint32_t counted = 0, hidden = 0;
  if (!any_open) {
    counted = hidden = n;
  } else {
    // 2. where each ray meets the object itself, at its occluder level (one rtcIntersect1 per
    //    ray): rays outside its silhouette are not counted; the others are hidden when blocked
    //    before the sphere, or between the sphere and the object
    for (uint32_t c = 0; c < chunks; ++c) {
      const uint32_t k0 = c * kChunk, lanes = std::min(kChunk, n - k0);
      float t_self[kChunk], t_end[kChunk];
      uint32_t self_hits = 0, active = 0;
      for (uint32_t k = 0; k < lanes; ++k) {
        t_self[k] = std::numeric_limits<float>::infinity();
        ++stats.embree_rays;
        if (!intersectObject(m, id, self_scene, rays[c].origin(k), rays[c].direction(k), t_near, t_self[k])) continue;
        self_hits |= 1u << k;
        t_end[k] = t_self[k] * (1.0f - 1e-4f);
        if ((open[c] >> k & 1u) && t_end[k] > t_sphere[c][k]) active |= 1u << k;
      }
      counted += bitCount(self_hits);
      const uint32_t inside = active;
      if (active != 0)
        forEachCandidate(m, beam, id, [&](uint32_t other) {
          ++stats.occluder_candidates;
          active = blockRays(m, other, rays[c], active, t_sphere[c], t_end, limit, stats.embree_rays);
          return active == 0;
        });
      hidden += bitCount(self_hits & ~(open[c] & ~(inside & ~active)));
    }
  }
  stats.samples += n;
  stats.self_hits += counted;
  stats.hidden_samples += hidden;
  ++stats.objects_tested;
  visible[id] = counted ? static_cast<float>(counted - hidden) / static_cast<float>(counted) : 1.0f;
  tested_frame[id] = frame;
  tested_generation[id] = m.generation[id];
  age_origin[id] = static_cast<uint32_t>(frame);
}

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
  s.pattern.resize(params.rays_per_test);
  for (uint32_t k = 0; k < params.rays_per_test; ++k) {
    const float th = static_cast<float>(k) * kGoldenAngle;
    s.pattern[k] = glm::vec3(std::sqrt((static_cast<float>(k) + 0.5f) / static_cast<float>(params.rays_per_test)),
                             std::cos(th), std::sin(th));
  }
  s.priority.assign(max_objects, -1.0f);
  s.age_origin.assign(max_objects, 0);
  s.seen_generation.assign(max_objects, kNever);
  s.visible.assign(max_objects, 1.0f);
  s.tested_frame.assign(max_objects, 0);
  s.tested_generation.assign(max_objects, kNever);
  s.keys.assign(max_objects, 0);
  s.histogram.assign(kBuckets, 0);
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

  // priority pass: every id's priority, then the budget's worth of the highest
  PriorityColumns cols;
  cols.spheres = m.world_sphere.data();
  cols.live = m.live.data();
  cols.generation = m.generation.data();
  cols.seen_generation = s.seen_generation.data();
  cols.age_origin = s.age_origin.data();
  cols.priority = s.priority.data();
  cols.visible = s.visible.data();
  cols.tested_frame = s.tested_frame.data();
  cols.tested_generation = s.tested_generation.data();
  const size_t cand_count = priorityPass(view, cols, cap, s.frame, s.params.untested_age_frames);
  s.stats.candidates = static_cast<uint32_t>(cand_count);

  const size_t test_count = std::min<size_t>(cand_count, s.params.ray_budget / s.params.rays_per_test);
  if (test_count > 0) chooseLargest(s.priority.data(), cap, test_count, cand_count, s.histogram.data(), s.keys.data());

  ErrorLimit limit;
  const float err_px = m.params.occluder_error_px;
  if (view.ortho) {
    limit.at_zero = err_px / view.px_per_unit_at_1;
  } else {
    limit.per_t = err_px / view.px_per_unit_at_1;
  }
  const float rotation = std::fmod(static_cast<float>(s.frame % 100003u) * kGoldenAngle, 6.2831853f);
  const float cos_rot = std::cos(rotation), sin_rot = std::sin(rotation);
  // test in screen order (a Morton code of the centre's view direction), so consecutive beams cross
  // the same tree nodes and those stay in cache
  for (size_t c = 0; c < test_count; ++c) {
    const uint32_t id = ~static_cast<uint32_t>(s.keys[c]);
    s.keys[c] = (uint64_t(screenCode(view, glm::vec3(m.world_sphere[id]))) << 32) | id;
  }
  std::sort(s.keys.begin(), s.keys.begin() + static_cast<std::ptrdiff_t>(test_count));
  for (size_t c = 0; c < test_count; ++c)
    s.testObject(m, view, limit, cos_rot, sin_rot, static_cast<uint32_t>(s.keys[c]));

  if (visible_fraction.count)
    writeVisibleFractions(m.live.data(), m.generation.data(), s.tested_generation.data(), s.visible.data(), cap,
                          visible_fraction.data);
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
