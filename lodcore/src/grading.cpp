// Grading of vertices by visual importance, and the once-per-mesh sort by weight.
// Low & Tan 1997 §3.1: weight = cos(theta/2) x longest incident edge, theta the largest angle
// between two incident edges (cos(theta/2) is the probability that the vertex lies on the silhouette
// from a random view direction). Rossignac & Borrel 1993: 1/theta in place of cos(theta/2).
// §4: the sort by weight happens once per mesh for all levels.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "cluster_internal.h"

namespace scenelod {

const char* gradingName(Grading g) {
  switch (g) {
    case Grading::kLowTan: return "lowtan";
    case Grading::kRossignac: return "rossignac";
  }
  return "unknown";
}

namespace {

constexpr float kPi = 3.14159265358979f;
constexpr float kMinTheta = 1e-3f;        // rossignac: 1/theta is capped at 1/kMinTheta
constexpr float kBoundaryFactor = 0.5f;   // boost: a boundary vertex is on the silhouette at least half the time
constexpr size_t kExactPairLimit = 64;    // above this degree, the widest pair is found by two sweeps

// smallest dot product over pairs of unit vectors (cos of the largest angle between them)
float minPairDot(const glm::vec3* d, size_t n) {
  if (n < 2) return 1.0f;
  float best = 1.0f;
  if (n <= kExactPairLimit) {
    for (size_t i = 0; i < n; ++i)
      for (size_t j = i + 1; j < n; ++j) best = std::min(best, glm::dot(d[i], d[j]));
    return best;
  }
  // two farthest-point sweeps: exact for the typical fan, within a factor 2 of the angle otherwise
  size_t a = 0;
  for (int sweep = 0; sweep < 2; ++sweep) {
    size_t far = a;
    float far_dot = 2.0f;
    for (size_t i = 0; i < n; ++i) {
      const float dd = glm::dot(d[a], d[i]);
      if (dd < far_dot) far_dot = dd, far = i;
    }
    best = std::min(best, far_dot);
    a = far;
  }
  return best;
}

}  // namespace

void gradeVertices(const Mesh& mesh, Grading grading, bool boost_features, std::vector<float>& weights,
                   std::vector<float>* angular_out, float* longest_edge_out, std::vector<float>* raw_out) {
  const size_t vn = mesh.vertexCount(), tn = mesh.triangleCount(), en = mesh.edgeCount();
  weights.assign(vn, 0.0f);
  if (angular_out) angular_out->assign(vn, 0.0f);
  if (vn == 0) {
    if (longest_edge_out) *longest_edge_out = 0.0f;
    return;
  }
  // vertex -> incidences (triangle corners 3t+k, then edge ends 3T+2e+k), compressed rows
  std::vector<uint32_t> offsets(vn + 1, 0);
  for (uint32_t v : mesh.triangles) ++offsets[v + 1];
  for (uint32_t v : mesh.edges) ++offsets[v + 1];
  for (size_t v = 0; v < vn; ++v) offsets[v + 1] += offsets[v];
  std::vector<uint32_t> incidence(offsets[vn]);
  {
    std::vector<uint32_t> fill(offsets.begin(), offsets.end() - 1);
    for (size_t i = 0; i < mesh.triangles.size(); ++i) incidence[fill[mesh.triangles[i]]++] = static_cast<uint32_t>(i);
    const uint32_t base = static_cast<uint32_t>(3 * tn);
    for (size_t i = 0; i < mesh.edges.size(); ++i) incidence[fill[mesh.edges[i]]++] = base + static_cast<uint32_t>(i);
  }
  (void)en;
  const glm::vec3* pos = mesh.positions.data();
  const uint32_t* tri = mesh.triangles.data();
  const uint32_t tri_corners = static_cast<uint32_t>(3 * tn);
  std::vector<float> longest(vn, 0.0f);
  std::vector<float> angular(vn, 0.0f);

  tbb::parallel_for(tbb::blocked_range<size_t>(0, vn, 1024), [&](const tbb::blocked_range<size_t>& range) {
    std::vector<glm::vec3> dirs, normals;
    std::vector<uint32_t> neighbours;
    for (size_t v = range.begin(); v != range.end(); ++v) {
      const uint32_t b = offsets[v], e = offsets[v + 1];
      if (b == e) continue;
      dirs.clear();
      normals.clear();
      neighbours.clear();
      float longest_v = 0.0f;
      auto addNeighbour = [&](uint32_t u) {
        const glm::vec3 d = pos[u] - pos[v];
        const float len = glm::length(d);
        if (len > 0.0f) {
          dirs.push_back(d / len);
          longest_v = std::max(longest_v, len);
        }
      };
      for (uint32_t i = b; i < e; ++i) {
        const uint32_t inc = incidence[i];
        if (inc < tri_corners) {
          const uint32_t t = inc / 3, k = inc % 3;
          const uint32_t u1 = tri[3 * t + (k + 1) % 3], u2 = tri[3 * t + (k + 2) % 3];
          addNeighbour(u1);
          addNeighbour(u2);
          if (boost_features) {
            neighbours.push_back(u1);
            neighbours.push_back(u2);
            const glm::vec3 n = glm::cross(pos[tri[3 * t + 1]] - pos[tri[3 * t]], pos[tri[3 * t + 2]] - pos[tri[3 * t]]);
            const float nl = glm::length(n);
            if (nl > 0.0f) normals.push_back(n / nl);
          }
        } else {
          const uint32_t c = inc - tri_corners;
          addNeighbour(mesh.edges[c ^ 1u]);
        }
      }
      longest[v] = longest_v;
      if (dirs.empty()) continue;  // only zero-length edges: no direction, weight 0
      const float cos_theta = std::clamp(minPairDot(dirs.data(), dirs.size()), -1.0f, 1.0f);
      float a;
      if (grading == Grading::kLowTan) {
        a = std::sqrt(std::max(0.0f, (1.0f + cos_theta) * 0.5f));  // cos(theta/2)
        if (boost_features) {
          // boundary: some neighbour is shared by only one incident triangle
          std::sort(neighbours.begin(), neighbours.end());
          bool boundary = false;
          for (size_t i = 0; i < neighbours.size() && !boundary;) {
            size_t j = i;
            while (j < neighbours.size() && neighbours[j] == neighbours[i]) ++j;
            if (j - i == 1) boundary = true;
            i = j;
          }
          if (boundary) a = std::max(a, kBoundaryFactor);
          const float crease = (1.0f - std::clamp(minPairDot(normals.data(), normals.size()), -1.0f, 1.0f)) * 0.5f;
          a = std::max(a, crease);
        }
      } else {
        a = kPi / std::max(std::acos(cos_theta), kMinTheta);
      }
      angular[v] = a;
    }
  });

  float longest_edge = 0.0f;
  for (float l : longest) longest_edge = std::max(longest_edge, l);
  const float inv = longest_edge > 0.0f ? 1.0f / longest_edge : 0.0f;
  // weights = raw * inv: rounding is monotone, so the normalised weights keep the raw order
  for (size_t v = 0; v < vn; ++v) longest[v] *= angular[v];
  for (size_t v = 0; v < vn; ++v) weights[v] = longest[v] * inv;
  if (raw_out) raw_out->swap(longest);
  if (angular_out) angular_out->swap(angular);
  if (longest_edge_out) *longest_edge_out = longest_edge;
}

Error prepareMesh(const Mesh& in, const ClusterParams& params, PreparedMesh& out, const std::string& what) {
  if (Error e = validateMesh(in, what)) return e;
  out = PreparedMesh();
  out.mesh = &in;
  out.grading = params.grading;
  out.boost_features = params.boost_features;
  // the sort uses the unnormalised product: normalising a factor by a constant cannot change the
  // order, and this way the order does not depend on other parts of the mesh (whose longest edge
  // would be the normaliser) even by rounding
  std::vector<float> raw;
  gradeVertices(in, params.grading, params.boost_features, out.weights, nullptr, &out.longest_edge, &raw);

  const size_t vn = in.vertexCount();
  std::vector<uint8_t> referenced(vn, 0);
  for (uint32_t v : in.triangles) referenced[v] = 1;
  for (uint32_t v : in.edges) referenced[v] = 1;
  for (uint32_t v : in.points) referenced[v] = 1;

  // weights are >= 0 floats, whose bit patterns sort like the values: heaviest first, then by index
  std::vector<uint64_t> keys;
  keys.reserve(vn);
  bool first = true;
  for (size_t v = 0; v < vn; ++v) {
    if (!referenced[v]) continue;
    uint32_t bits;
    std::memcpy(&bits, &raw[v], sizeof bits);
    keys.push_back((uint64_t(~bits) << 32) | uint64_t(v));
    const glm::vec3& p = in.positions[v];
    if (first) out.bounds.min = out.bounds.max = p, first = false;
    out.bounds.min = glm::min(out.bounds.min, p);
    out.bounds.max = glm::max(out.bounds.max, p);
  }
  std::sort(keys.begin(), keys.end());
  out.order.resize(keys.size());
  out.sorted_positions.resize(keys.size());
  for (size_t i = 0; i < keys.size(); ++i) {
    out.order[i] = static_cast<uint32_t>(keys[i] & 0xffffffffu);
    out.sorted_positions[i] = in.positions[out.order[i]];
  }

  double sum = 0.0, area = 0.0;
  const size_t tn = in.triangleCount();
  for (size_t t = 0; t < tn; ++t) {
    const glm::vec3 a = in.positions[in.triangles[3 * t]], b = in.positions[in.triangles[3 * t + 1]],
                    c = in.positions[in.triangles[3 * t + 2]];
    sum += double(glm::length(b - a)) + double(glm::length(c - b)) + double(glm::length(a - c));
    area += 0.5 * double(glm::length(glm::cross(b - a, c - a)));
  }
  out.surface_area = area;
  for (size_t e = 0; e < in.edgeCount(); ++e)
    sum += glm::length(in.positions[in.edges[2 * e]] - in.positions[in.edges[2 * e + 1]]);
  const size_t count = 3 * tn + in.edgeCount();
  out.mean_edge_length = count ? static_cast<float>(sum / double(count)) : 0.0f;
  return {};
}

}  // namespace scenelod
