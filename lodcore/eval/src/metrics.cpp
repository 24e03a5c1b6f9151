// Surface distance between an original and a simplified mesh by sampling, after Metro (Cignoni,
// Rocchini & Scopigno 1998), with closest points from Embree point queries. Thick edges are
// capsules and points spheres (Low & Tan 1997 §3.3), see metrics.h.
#include "scenelod/eval/metrics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include "embree_scene.h"

namespace scenelod::eval {

namespace {

constexpr double kPi = 3.14159265358979323846;

// splitmix64: a small fixed generator, the same on every platform and standard library
struct Rng {
  uint64_t state;
  uint64_t next() {
    uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }
};

double triangleArea(const Mesh& m, size_t t) {
  const glm::dvec3 a(m.positions[m.triangles[3 * t]]), b(m.positions[m.triangles[3 * t + 1]]),
      c(m.positions[m.triangles[3 * t + 2]]);
  return 0.5 * glm::length(glm::cross(b - a, c - a));
}

glm::vec3 anyPerpendicular(const glm::vec3& u) {
  const glm::vec3 other = std::fabs(u.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
  return glm::normalize(glm::cross(u, other));
}

glm::vec3 randomUnit(Rng& rng) {
  const double z = 2.0 * rng.uniform() - 1.0, phi = 2.0 * kPi * rng.uniform();
  const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
  return glm::vec3(static_cast<float>(s * std::cos(phi)), static_cast<float>(s * std::sin(phi)), static_cast<float>(z));
}

// one point on the surface of the capsule (a, b, r); on the segment when r = 0
glm::vec3 sampleCapsule(const glm::vec3& a, const glm::vec3& b, float r, Rng& rng) {
  const glm::vec3 ab = b - a;
  const float len = glm::length(ab);
  if (r <= 0.0f) return a + static_cast<float>(rng.uniform()) * ab;
  const double lateral = 2.0 * kPi * r * len, caps = 4.0 * kPi * r * r;
  if (len > 0.0f && rng.uniform() * (lateral + caps) < lateral) {
    const glm::vec3 u = ab / len, p = anyPerpendicular(u), q = glm::cross(u, p);
    const double phi = 2.0 * kPi * rng.uniform();
    const glm::vec3 axis = a + static_cast<float>(rng.uniform()) * ab;
    return axis + r * (static_cast<float>(std::cos(phi)) * p + static_cast<float>(std::sin(phi)) * q);
  }
  // a hemisphere at either end, facing away from the segment (the whole sphere when len = 0)
  glm::vec3 dir = randomUnit(rng);
  const bool at_b = rng.uniform() < 0.5;
  if (len > 0.0f) {
    const float along = glm::dot(dir, ab);
    if ((at_b && along < 0.0f) || (!at_b && along > 0.0f)) dir -= 2.0f * along / (len * len) * ab;
  }
  return (at_b ? b : a) + r * dir;
}

std::vector<glm::vec3> samplePoints(const Mesh& m, const DistanceParams& params) {
  std::vector<glm::vec3> out;
  Rng rng{params.seed * 0x2545F4914F6CDD1Dull + 17};
  const size_t tris = m.triangleCount();
  std::vector<double> cdf(tris);
  double total_area = 0.0;
  for (size_t t = 0; t < tris; ++t) cdf[t] = (total_area += triangleArea(m, t));
  double total_length = 0.0;
  for (size_t e = 0; e < m.edgeCount(); ++e)
    total_length += glm::length(m.positions[m.edges[2 * e + 1]] - m.positions[m.edges[2 * e]]);

  const size_t n = params.area_sample_count;
  out.reserve(n + m.vertexCount() + m.pointCount() + m.edgeCount());
  if (total_area > 0.0) {
    for (size_t i = 0; i < n; ++i) {
      const double u = rng.uniform() * total_area;
      size_t t = static_cast<size_t>(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin());
      t = std::min(t, tris - 1);
      double s = std::sqrt(rng.uniform()), r = rng.uniform();
      const glm::vec3 a = m.positions[m.triangles[3 * t]], b = m.positions[m.triangles[3 * t + 1]],
                      c = m.positions[m.triangles[3 * t + 2]];
      out.push_back(static_cast<float>(1.0 - s) * a + static_cast<float>(s * (1.0 - r)) * b +
                    static_cast<float>(s * r) * c);
    }
  }
  // edges: the spacing of the area samples carried over to their length, or all n samples by
  // length when there are no triangles
  const double spacing = total_area > 0.0 ? std::sqrt(total_area / std::max<size_t>(n, 1))
                                          : (total_length > 0.0 ? total_length / std::max<size_t>(n, 1) : 0.0);
  for (size_t e = 0; e < m.edgeCount(); ++e) {
    const glm::vec3 a = m.positions[m.edges[2 * e]], b = m.positions[m.edges[2 * e + 1]];
    const double len = glm::length(b - a);
    const size_t k = spacing > 0.0 ? std::max<size_t>(1, static_cast<size_t>(std::ceil(len / spacing))) : 1;
    for (size_t i = 0; i < k; ++i) out.push_back(sampleCapsule(a, b, 0.5f * m.edgeThickness(e), rng));
  }
  if (params.include_vertices) {
    std::vector<uint8_t> used(m.vertexCount(), 0);
    for (uint32_t i : m.triangles) used[i] = 1;
    for (uint32_t i : m.edges) used[i] = 1;
    for (uint32_t i : m.points) used[i] = 1;
    for (size_t i = 0; i < used.size(); ++i)
      if (used[i]) out.push_back(m.positions[i]);
  } else {
    for (uint32_t i : m.points) out.push_back(m.positions[i]);  // a sphere of radius 0 is its centre
  }
  return out;
}

// spreads the low 21 bits of v to every third bit (for a 63-bit Morton code)
uint64_t spreadBits(uint64_t v) {
  v &= 0x1FFFFF;
  v = (v | v << 32) & 0x1F00000000FFFFull;
  v = (v | v << 16) & 0x1F0000FF0000FFull;
  v = (v | v << 8) & 0x100F00F00F00F00Full;
  v = (v | v << 4) & 0x10C30C30C30C30C3ull;
  v = (v | v << 2) & 0x1249249249249249ull;
  return v;
}

// samples in Morton order, so consecutive samples are neighbours in space
std::vector<glm::vec3> mortonOrder(std::vector<glm::vec3> pts) {
  if (pts.size() < 2) return pts;
  glm::vec3 lo = pts[0], hi = pts[0];
  for (const auto& p : pts) lo = glm::min(lo, p), hi = glm::max(hi, p);
  const glm::vec3 ext = glm::max(hi - lo, glm::vec3(1e-30f));
  std::vector<std::pair<uint64_t, uint32_t>> keys(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    const glm::vec3 u = (pts[i] - lo) / ext * 2097151.0f;
    keys[i] = {spreadBits(static_cast<uint64_t>(u.x)) | spreadBits(static_cast<uint64_t>(u.y)) << 1 |
                   spreadBits(static_cast<uint64_t>(u.z)) << 2,
               static_cast<uint32_t>(i)};
  }
  std::sort(keys.begin(), keys.end());  // (code, index): a total order, so deterministic
  std::vector<glm::vec3> out(pts.size());
  for (size_t i = 0; i < keys.size(); ++i) out[i] = pts[keys[i].second];
  return out;
}

OneSidedDistance measureOneSided(const std::vector<glm::vec3>& unordered, const detail::EmbreeScene& target,
                                 float scale) {
  const std::vector<glm::vec3> samples = mortonOrder(unordered);
  std::vector<float> d(samples.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, samples.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
    // the previous sample's distance plus the step to this sample bounds this sample's distance
    // (triangle inequality): a tight search radius. Answers are exact whatever the hint.
    float hint = 0.01f * scale;
    for (size_t i = r.begin(); i < r.end(); ++i) {
      if (i > r.begin())
        hint = (d[i - 1] + glm::length(samples[i] - samples[i - 1])) * 1.001f + 1e-6f * scale;
      d[i] = target.closestDistance(samples[i], hint);
    }
  });
  OneSidedDistance out;
  out.sample_count = d.size();
  if (d.empty()) return out;
  double sum = 0.0, sum2 = 0.0, mx = 0.0;
  for (float x : d) {  // serial, fixed order: the same sums whatever the thread count
    sum += x;
    sum2 += static_cast<double>(x) * x;
    mx = std::max(mx, static_cast<double>(x));
  }
  out.max = mx;
  out.mean = sum / static_cast<double>(d.size());
  out.rms = std::sqrt(sum2 / static_cast<double>(d.size()));
  return out;
}

}  // namespace

Error measureSurfaceDistance(const Mesh& original, const Mesh& simplified, const DistanceParams& params,
                             DistanceResult& out) {
  out = DistanceResult{};
  if (Error e = validateMesh(original, "original mesh"); !e.ok()) return e;
  if (Error e = validateMesh(simplified, "simplified mesh"); !e.ok()) return e;
  if (original.triangleCount() == 0)
    return {Status::kInvalidMesh, "original mesh has no triangles: the error is measured against its surface"};
  double area = 0.0;
  for (size_t t = 0; t < original.triangleCount(); ++t) area += triangleArea(original, t);
  if (!(area > 0.0)) return {Status::kInvalidMesh, "original mesh has only zero-area triangles: no surface to measure"};
  if (simplified.empty())
    return {Status::kInvalidMesh, "simplified mesh has no triangles, edges or points: nothing to measure"};

  out.diagonal = computeBounds(original).diagonal();
  detail::EmbreeScene original_scene, simplified_scene;
  if (Error e = original_scene.build(original); !e.ok()) return e;
  if (Error e = simplified_scene.build(simplified); !e.ok()) return e;

  const float scale = static_cast<float>(out.diagonal > 0.0 ? out.diagonal : 1.0);
  out.forward = measureOneSided(samplePoints(original, params), simplified_scene, scale);
  out.backward = measureOneSided(samplePoints(simplified, params), original_scene, scale);
  const double diag = out.diagonal > 0.0 ? out.diagonal : 1.0;
  out.hausdorff = std::max(out.forward.max, out.backward.max) / diag;
  out.rms = std::max(out.forward.rms, out.backward.rms) / diag;
  out.mean = std::max(out.forward.mean, out.backward.mean) / diag;
  return {};
}

Error checkComparableScales(const Mesh& a, const std::string& what_a, const Mesh& b, const std::string& what_b,
                            double max_ratio) {
  const double da = computeBounds(a).diagonal(), db = computeBounds(b).diagonal();
  if (!(da > 0.0) || !(db > 0.0))
    return {Status::kInvalidMesh, (da > 0.0 ? what_b : what_a) + ": bounding box has zero size"};
  const double ratio = std::max(da, db) / std::min(da, db);
  if (ratio > max_ratio) {
    char buf[256];
    std::snprintf(buf, sizeof buf, "bounding-box diagonals differ by %.1fx (%g vs %g): ", ratio, da, db);
    return {Status::kInvalidArgument, std::string(buf) + what_a + " and " + what_b +
                                          " are not at the same scale (different units or a different model?)"};
  }
  return {};
}

}  // namespace scenelod::eval
