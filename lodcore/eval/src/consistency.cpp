// Low & Tan 1997 §3.2.2: counting the triangles that change between two simplifications.
#include "scenelod/eval/consistency.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vector_relational.hpp>

namespace scenelod::eval {

namespace {

struct Tri {
  glm::vec3 c[3];
  glm::vec3 centroid() const { return (c[0] + c[1] + c[2]) / 3.0f; }
};

bool lessVec(const glm::vec3& a, const glm::vec3& b) {
  return a.x != b.x ? a.x < b.x : a.y != b.y ? a.y < b.y : a.z < b.z;
}

// triangles with every corner in the region, rotated to start at the lexicographically smallest
// corner so that equal triangles compare corner by corner whatever their first index was
std::vector<Tri> trianglesInside(const Mesh& m, const Aabb& region) {
  std::vector<Tri> out;
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    Tri tr;
    bool in = true;
    for (int k = 0; k < 3; ++k) {
      tr.c[k] = m.positions[m.triangles[3 * t + k]];
      in = in && glm::all(glm::greaterThanEqual(tr.c[k], region.min)) &&
           glm::all(glm::lessThanEqual(tr.c[k], region.max));
    }
    if (!in) continue;
    int first = 0;
    for (int k = 1; k < 3; ++k)
      if (lessVec(tr.c[k], tr.c[first])) first = k;
    std::rotate(tr.c, tr.c + first, tr.c + 3);
    out.push_back(tr);
  }
  return out;
}

bool sameCorners(const Tri& x, const Tri& y, float eps) {
  return glm::distance(x.c[0], y.c[0]) <= eps && glm::distance(x.c[1], y.c[1]) <= eps &&
         glm::distance(x.c[2], y.c[2]) <= eps;
}

}  // namespace

TriangleChangeCount countChangedTriangles(const Mesh& before, const Mesh& after, const Aabb& region, float eps) {
  const std::vector<Tri> a = trianglesInside(before, region), b = trianglesInside(after, region);
  TriangleChangeCount result;
  result.compared = a.size();
  if (a.empty()) return result;
  // grid of centroids of `after`: the cube side is the mean triangle extent plus eps, so a match
  // (centroids within eps) lies in the cube of the query centroid or one of its 26 neighbours
  double extent_sum = 0.0;
  for (const Tri& t : b) {
    const glm::vec3 size = glm::max(t.c[0], glm::max(t.c[1], t.c[2])) - glm::min(t.c[0], glm::min(t.c[1], t.c[2]));
    extent_sum += double(std::max(size.x, std::max(size.y, size.z)));
  }
  const float region_diag = glm::length(region.max - region.min);
  float cell = b.empty() ? 1.0f : float(extent_sum / double(b.size())) + eps;
  if (!(cell > 0.0f) || !std::isfinite(cell)) cell = std::max(region_diag, 1e-30f);
  cell = std::max(cell, region_diag * 1e-6f);  // keeps the 21-bit cube keys from wrapping
  auto key = [&](const glm::vec3& p) {
    const glm::ivec3 q = glm::ivec3(glm::floor((p - region.min) / cell));
    return (uint64_t(uint32_t(q.x) & 0x1fffffu) << 42) | (uint64_t(uint32_t(q.y) & 0x1fffffu) << 21) |
           uint64_t(uint32_t(q.z) & 0x1fffffu);
  };
  std::unordered_map<uint64_t, std::vector<uint32_t>> grid;
  grid.reserve(b.size());
  for (size_t i = 0; i < b.size(); ++i) grid[key(b[i].centroid())].push_back(uint32_t(i));
  for (const Tri& x : a) {
    const glm::vec3 centroid = x.centroid();
    bool found = false;
    for (int dx = -1; dx <= 1 && !found; ++dx)
      for (int dy = -1; dy <= 1 && !found; ++dy)
        for (int dz = -1; dz <= 1 && !found; ++dz) {
          const auto it = grid.find(key(centroid + glm::vec3(float(dx), float(dy), float(dz)) * cell));
          if (it == grid.end()) continue;
          for (uint32_t j : it->second)
            if (sameCorners(x, b[j], eps)) {
              found = true;
              break;
            }
        }
    if (!found) ++result.changed;
  }
  return result;
}

}  // namespace scenelod::eval
