#pragma once
// Small meshes with known geometry for the evaluation tests, made in code.
#include <cmath>
#include <map>
#include <utility>

#include <glm/geometric.hpp>

#include "scenelod/lodcore/mesh.h"

namespace scenelod::test {

// axis-aligned box [lo, hi], 12 outward-facing triangles
inline Mesh makeBox(glm::vec3 lo, glm::vec3 hi) {
  Mesh m;
  for (int i = 0; i < 8; ++i) m.positions.push_back({(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z});
  const uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) m.triangles.insert(m.triangles.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
  return m;
}

// icosahedron subdivided `levels` times, every vertex on the sphere of radius r about c
inline Mesh makeIcosphere(int levels, float r, glm::vec3 c = glm::vec3(0.0f)) {
  const float t = (1.0f + std::sqrt(5.0f)) * 0.5f;
  std::vector<glm::vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                              {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) p = glm::normalize(p);
  std::vector<uint32_t> f = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6,
                             7, 1, 8, 3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7,
                             9, 8, 1};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto middle = [&](uint32_t a, uint32_t b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(glm::normalize(v[a] + v[b]));
      return mid[key] = static_cast<uint32_t>(v.size() - 1);
    };
    std::vector<uint32_t> g;
    for (size_t i = 0; i < f.size(); i += 3) {
      const uint32_t a = f[i], b = f[i + 1], cc = f[i + 2];
      const uint32_t ab = middle(a, b), bc = middle(b, cc), ca = middle(cc, a);
      g.insert(g.end(), {a, ab, ca, b, bc, ab, cc, ca, bc, ab, bc, ca});
    }
    f.swap(g);
  }
  Mesh m;
  for (auto& p : v) m.positions.push_back(c + r * p);
  m.triangles = f;
  return m;
}

// the mesh scaled by s about point c
inline Mesh scaled(Mesh m, float s, glm::vec3 c) {
  for (auto& p : m.positions) p = c + s * (p - c);
  return m;
}

inline Mesh translated(Mesh m, glm::vec3 d) {
  for (auto& p : m.positions) p += d;
  return m;
}

}  // namespace scenelod::test
