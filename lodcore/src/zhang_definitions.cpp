// Definitions 1-9 and the vertex classification of §2 of Zhang, Shu & Luo 2003, "Mesh
// Simplification Based on Shading Characteristic" (WSCG 2003 short papers). The super plane of
// definition 6 is the triangulated hole left by deleting the vertex (Fig. 4b); the paper does not say
// how to triangulate it, we take the fan from the ring vertex that gives the smallest |SV|, so that a
// vertex on a straight crease gets SH = 0 and a corner does not (docs/ZHANG.md).
#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "scenelod/lodcore/zhang.h"
#include "zhang_internal.h"

namespace scenelod {

const char* zhangVertexClassName(ZhangVertexClass c) {
  switch (c) {
    case ZhangVertexClass::kSimple: return "simple";
    case ZhangVertexClass::kComplex: return "complex";
    case ZhangVertexClass::kEdge: return "edge";
    case ZhangVertexClass::kInnerEdge: return "inner-edge";
    case ZhangVertexClass::kAngle: return "angle";
    case ZhangVertexClass::kIsolated: return "isolated";
  }
  return "unknown";
}

const char* zhangInfluenceName(ZhangInfluence i) {
  return i == ZhangInfluence::kVisionCharacteristic ? "ca" : "sh";
}

const char* zhangPlacementName(ZhangPlacement p) {
  return p == ZhangPlacement::kInterpolated ? "interpolated" : "neighbour";
}

const char* zhangModeName(ZhangMode m) { return m == ZhangMode::kEdgeCollapse ? "edge-collapse" : "triangle"; }

const char* zhangStopReasonName(ZhangStopReason r) {
  return r == ZhangStopReason::kTargetReached ? "target-reached" : "no-valid-collapse";
}

float zhangEquivalentCellWidth(float max_displacement) { return 2.0f * max_displacement / std::sqrt(3.0f); }

namespace zhang_detail {

float angleBetweenUnit(const glm::vec3& a, const glm::vec3& b) {
  if (glm::dot(a, a) == 0.0f || glm::dot(b, b) == 0.0f) return 0.0f;
  return std::acos(std::clamp(glm::dot(a, b), -1.0f, 1.0f));
}

namespace {

constexpr uint32_t kFirst = 1u, kSecond = 1u << 16;

uint32_t firstCount(uint32_t c) { return c & 0xffffu; }
uint32_t secondCount(uint32_t c) { return c >> 16; }

// counts appearances and successors; returns false when a ring vertex starts two pairs
void tallyStar(const StarPair* pairs, size_t n, StarScratch& s) {
  s.reset();
  for (size_t i = 0; i < n; ++i) {
    const uint32_t u = pairs[i].u, w = pairs[i].w;
    if (s.count[u] == 0) s.touched.push_back(u);
    if (s.count[w] == 0) s.touched.push_back(w);
    s.count[u] += kFirst;
    s.count[w] += kSecond;
    s.next[u] = w;
  }
}

// after tallyStar: orders the ring into s.ring when it is one cycle through every neighbour
bool orderDiskRing(const StarPair* pairs, size_t n, StarScratch& s) {
  s.ring.clear();
  if (n < 3 || s.touched.size() != n) return false;
  for (uint32_t v : s.touched)
    if (s.count[v] != (kFirst | kSecond)) return false;
  uint32_t v = pairs[0].u;
  for (size_t i = 0; i < n; ++i) {
    s.ring.push_back(v);
    v = s.next[v];
    if (v == kNone) return false;
  }
  return v == pairs[0].u;
}

// fan triangulations of the ordered ring, from up to 32 start vertices; the one with least |SV|
void fanHeight(const glm::vec3& pv, const glm::vec3* positions, const std::vector<uint32_t>& ring, float& sa,
               float& sv) {
  const size_t d = ring.size();
  const size_t starts = std::min<size_t>(d, 32);
  float best_v = INFINITY, best_a = 0.0f;
  for (size_t k = 0; k < starts; ++k) {
    const size_t s = k * d / starts;
    const glm::vec3 a = positions[ring[s]] - pv;
    double vol = 0.0, area = 0.0;
    for (size_t m = 1; m + 1 < d; ++m) {
      const glm::vec3 b = positions[ring[(s + m) % d]] - pv, c = positions[ring[(s + m + 1) % d]] - pv;
      vol += glm::dot(a, glm::cross(b, c)) / 6.0;
      area += 0.5 * glm::length(glm::cross(b - a, c - a));
    }
    if (std::fabs(vol) < best_v) {
      best_v = static_cast<float>(std::fabs(vol));
      best_a = static_cast<float>(area);
    }
  }
  sa = best_a;
  sv = best_v;
}

}  // namespace

float superHeightOfStar(const glm::vec3& pv, const StarPair* pairs, size_t n, const glm::vec3* positions,
                        StarScratch& s) {
  tallyStar(pairs, n, s);
  if (!orderDiskRing(pairs, n, s)) return 0.0f;
  float sa = 0.0f, sv = 0.0f;
  fanHeight(pv, positions, s.ring, sa, sv);
  return sa > 0.0f ? 3.0f * sv / sa : 0.0f;
}

void measureStar(const glm::vec3& pv, const StarPair* pairs, size_t n, const glm::vec3* positions,
                 float max_angle_rad, const ZhangParams& params, StarScratch& s, StarMeasure& out,
                 bool always_height) {
  out = StarMeasure{};
  if (n == 0) {
    out.vertex_class = ZhangVertexClass::kIsolated;
    return;
  }
  tallyStar(pairs, n, s);
  out.neighbour_count = static_cast<uint32_t>(s.touched.size());
  bool consistent = true;  // every ring vertex starts and ends at most one pair
  double dist = 0.0;
  for (uint32_t v : s.touched) {
    const uint32_t c = s.count[v];
    if (firstCount(c) + secondCount(c) != 2) ++out.characteristic;
    if (firstCount(c) > 1 || secondCount(c) > 1) consistent = false;
    dist += glm::length(positions[v] - pv);
  }
  out.mean_neighbour_distance = static_cast<float>(dist / static_cast<double>(s.touched.size()));

  if (out.characteristic == 0) {
    out.disk = consistent && orderDiskRing(pairs, n, s);
    if (!out.disk) {
      out.vertex_class = ZhangVertexClass::kComplex;  // pinched: two or more fans share the vertex
      return;
    }
    const float feature = params.feature_angle_deg * 3.14159265f / 180.0f;
    if (always_height || max_angle_rad > feature) {
      fanHeight(pv, positions, s.ring, out.super_area, out.super_volume);
      out.super_height = out.super_area > 0.0f ? 3.0f * out.super_volume / out.super_area : 0.0f;
    }
    if (max_angle_rad <= feature) {
      out.vertex_class = ZhangVertexClass::kSimple;
    } else {
      const float ratio = out.mean_neighbour_distance > 0.0f ? out.super_height / out.mean_neighbour_distance : 0.0f;
      out.vertex_class = ratio > params.angle_height_ratio ? ZhangVertexClass::kAngle : ZhangVertexClass::kInnerEdge;
    }
    return;
  }
  if (out.characteristic == 2 && consistent && s.touched.size() == n + 1) {
    // one open fan: walk from the ring vertex that starts a pair but ends none
    uint32_t start = kNone;
    for (uint32_t v : s.touched)
      if (secondCount(s.count[v]) == 0) start = v;
    size_t steps = 0;
    for (uint32_t v = start; v != kNone && firstCount(s.count[v]) == 1 && steps <= n; v = s.next[v]) ++steps;
    if (steps == n) {
      out.vertex_class = ZhangVertexClass::kEdge;
      return;
    }
  }
  out.vertex_class = ZhangVertexClass::kComplex;
}

}  // namespace zhang_detail

Error computeZhangMeasures(const Mesh& mesh, const ZhangParams& params, std::vector<ZhangVertexMeasures>& out) {
  using namespace zhang_detail;
  out.clear();
  if (Error e = validateMesh(mesh, "zhang measures"); !e.ok()) return e;
  const size_t vn = mesh.vertexCount(), tn = mesh.triangleCount();
  out.assign(vn, ZhangVertexMeasures{});
  // vertex -> triangle adjacency (definition 3), skipping triangles with a repeated index
  std::vector<uint32_t> offsets(vn + 1, 0), incident;
  std::vector<glm::vec3> face_n(tn), vertex_n(vn, glm::vec3(0.0f));
  std::vector<float> face_a(tn);
  auto degenerate = [&](size_t t) {
    const uint32_t* f = &mesh.triangles[3 * t];
    return f[0] == f[1] || f[1] == f[2] || f[0] == f[2];
  };
  for (size_t t = 0; t < tn; ++t) {
    const uint32_t* f = &mesh.triangles[3 * t];
    const glm::vec3 c = glm::cross(mesh.positions[f[1]] - mesh.positions[f[0]], mesh.positions[f[2]] - mesh.positions[f[0]]);
    const float len = glm::length(c);
    face_n[t] = len > 0.0f ? c / len : glm::vec3(0.0f);
    face_a[t] = 0.5f * len;
    if (degenerate(t)) continue;
    for (int k = 0; k < 3; ++k) {
      ++offsets[f[k] + 1];
      vertex_n[f[k]] += c;  // area weighted
    }
  }
  for (size_t v = 0; v < vn; ++v) offsets[v + 1] += offsets[v];
  incident.resize(offsets[vn]);
  std::vector<uint32_t> fill(offsets.begin(), offsets.end() - 1);
  for (size_t t = 0; t < tn; ++t) {
    if (degenerate(t)) continue;
    for (int k = 0; k < 3; ++k) incident[fill[mesh.triangles[3 * t + k]]++] = static_cast<uint32_t>(3 * t + k);
  }
  StarScratch scratch;
  scratch.resize(vn);
  std::vector<StarPair> pairs;
  for (size_t v = 0; v < vn; ++v) {
    pairs.clear();
    const float len = glm::length(vertex_n[v]);
    const glm::vec3 nv = len > 0.0f ? vertex_n[v] / len : glm::vec3(0.0f);
    float ca = 0.0f, max_angle = 0.0f;
    for (uint32_t i = offsets[v]; i < offsets[v + 1]; ++i) {
      const uint32_t corner = incident[i], t = corner / 3, k = corner % 3;
      pairs.push_back({mesh.triangles[3 * t + (k + 1) % 3], mesh.triangles[3 * t + (k + 2) % 3]});
      const float angle = angleBetweenUnit(nv, face_n[t]);
      max_angle = std::max(max_angle, angle);
      ca = std::max(ca, angle * face_a[t]);
    }
    StarMeasure m;
    measureStar(mesh.positions[v], pairs.data(), pairs.size(), mesh.positions.data(), max_angle, params, scratch, m);
    ZhangVertexMeasures& o = out[v];
    o.characteristic = m.characteristic;
    o.super_area = m.super_area;
    o.super_volume = m.super_volume;
    o.super_height = m.super_height;
    o.vision = ca;
    o.max_angle_rad = max_angle;
    o.vertex_class = m.vertex_class;
  }
  return {};
}

}  // namespace scenelod
