// Thick edges (Low & Tan 1997 §3.3.1): for the set T of triangles collapsed onto the edge between
// clusters A and B, V_A are T's vertices in A (each counted once), P_A their mean, likewise V_B and
// P_B; L is the line through P_A and P_B, D_A the mean distance of V_A to L, D_B likewise, and the
// edge's thickness is (2 D_A + 2 D_B) / 2 = D_A + D_B. Instead of the paper's per-cluster search
// trees we sort (edge, side, vertex) keys once, which gives the same sets in O(n log n) over the
// collapsed triangles only. The dynamic normal of §3.3.2 is in thick_edge.h.
#include <algorithm>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <glm/ext/vector_double3.hpp>

#include "cluster_internal.h"

namespace scenelod::detail {

void computeThickness(const PreparedMesh& p, const Assignment& a, const std::vector<CollapsedTriangle>& collapsed,
                      Eliminated& e) {
  if (collapsed.empty()) return;
  const Mesh& m = *p.mesh;
  // key: edge (31 bits) | side (1 bit) << 32 | vertex
  std::vector<uint64_t> keys;
  keys.reserve(collapsed.size() * 3);
  for (const CollapsedTriangle& ct : collapsed) {
    const uint32_t ca = e.edges[2 * ct.edge];
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = m.triangles[3 * ct.triangle + k];
      const uint64_t side = a.cluster_of[v] == ca ? 0 : 1;
      keys.push_back((((uint64_t(ct.edge) << 1) | side) << 32) | v);
    }
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());

  // group by edge: [begin, end) ranges of keys, side 0 first
  size_t i = 0;
  while (i < keys.size()) {
    const uint32_t edge = static_cast<uint32_t>(keys[i] >> 33);
    size_t j = i;
    glm::dvec3 sum[2] = {glm::dvec3(0.0), glm::dvec3(0.0)};
    size_t count[2] = {0, 0};
    while (j < keys.size() && (keys[j] >> 33) == edge) {
      const int side = static_cast<int>((keys[j] >> 32) & 1u);
      sum[side] += glm::dvec3(m.positions[keys[j] & 0xffffffffu]);
      ++count[side];
      ++j;
    }
    if (count[0] && count[1]) {
      const glm::dvec3 pa = sum[0] / double(count[0]), pb = sum[1] / double(count[1]);
      const glm::dvec3 axis = pb - pa;
      const double len = glm::length(axis);
      double dist[2] = {0.0, 0.0};
      for (size_t k = i; k < j; ++k) {
        const int side = static_cast<int>((keys[k] >> 32) & 1u);
        const glm::dvec3 d = glm::dvec3(m.positions[keys[k] & 0xffffffffu]) - pa;
        // distance to the line through pa and pb (to pa itself when they coincide)
        dist[side] += len > 0.0 ? glm::length(glm::cross(d, axis)) / len : glm::length(d);
      }
      e.edge_thickness[edge] = static_cast<float>(dist[0] / double(count[0]) + dist[1] / double(count[1]));
    }
    i = j;
  }
}

}  // namespace scenelod::detail
