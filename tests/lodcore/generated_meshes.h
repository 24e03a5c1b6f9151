#pragma once
// Small meshes made in code for the clustering tests: UV spheres, subdivided boxes, grids,
// cylinders, and unions of them (CAD-like multi-part meshes).
#include <cmath>
#include <cstdint>

#include <glm/vec3.hpp>

#include "scenelod/lodcore/mesh.h"

namespace scenelod::test {

// UV sphere with bumps (the benchmarks' large generated mesh): rings x segments quads, about
// 2 x rings x segments triangles; 720 x 720 gives 1,035,360
inline Mesh makeBumpySphere(int rings, int segments) {
  Mesh m;
  const float pi = 3.14159265358979f;
  for (int r = 0; r <= rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const float th = pi * float(r) / float(rings), ph = 2.0f * pi * float(s) / float(segments);
      const float rad = 1.0f + 0.05f * std::sin(9.0f * th) * std::cos(7.0f * ph);
      m.positions.push_back(rad * glm::vec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)));
    }
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const uint32_t a = uint32_t(r * segments + s), b = uint32_t(r * segments + (s + 1) % segments);
      const uint32_t c = b + uint32_t(segments), d = a + uint32_t(segments);
      if (r > 0) m.triangles.insert(m.triangles.end(), {a, d, b});
      if (r + 1 < rings) m.triangles.insert(m.triangles.end(), {b, d, c});
    }
  return m;
}

// UV sphere with `rings` latitude bands and `segments` longitudes, counter-clockwise outward.
inline Mesh makeSphere(glm::vec3 centre, float radius, int rings, int segments) {
  Mesh m;
  const float pi = 3.14159265358979f;
  m.positions.push_back(centre + glm::vec3(0, 0, radius));
  for (int r = 1; r < rings; ++r) {
    const float th = pi * float(r) / float(rings);
    for (int s = 0; s < segments; ++s) {
      const float ph = 2.0f * pi * float(s) / float(segments);
      m.positions.push_back(centre + radius * glm::vec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)));
    }
  }
  m.positions.push_back(centre + glm::vec3(0, 0, -radius));
  const uint32_t south = static_cast<uint32_t>(m.positions.size() - 1);
  auto ring = [&](int r, int s) { return uint32_t(1 + (r - 1) * segments + (s % segments)); };
  for (int s = 0; s < segments; ++s) m.triangles.insert(m.triangles.end(), {0u, ring(1, s), ring(1, s + 1)});
  for (int r = 1; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const uint32_t a = ring(r, s), b = ring(r + 1, s), c = ring(r + 1, s + 1), d = ring(r, s + 1);
      m.triangles.insert(m.triangles.end(), {a, b, c, a, c, d});
    }
  for (int s = 0; s < segments; ++s) m.triangles.insert(m.triangles.end(), {ring(rings - 1, s), south, ring(rings - 1, s + 1)});
  return m;
}

// Grid of n x n quads in the z = 0 plane over [0, size]^2, normals +z.
inline Mesh makeGrid(int n, float size, glm::vec3 origin = glm::vec3(0.0f)) {
  Mesh m;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) m.positions.push_back(origin + glm::vec3(size * x / n, size * y / n, 0.0f));
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const uint32_t a = uint32_t(y * (n + 1) + x), b = a + 1, c = a + uint32_t(n + 1) + 1, d = a + uint32_t(n + 1);
      m.triangles.insert(m.triangles.end(), {a, b, c, a, c, d});
    }
  return m;
}

// Axis-aligned box from lo to hi, each face an n x n grid, outward counter-clockwise.
inline Mesh makeBox(glm::vec3 lo, glm::vec3 hi, int n) {
  Mesh m;
  auto face = [&](glm::vec3 o, glm::vec3 u, glm::vec3 v) {
    const uint32_t base = static_cast<uint32_t>(m.positions.size());
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) m.positions.push_back(o + u * (float(i) / n) + v * (float(j) / n));
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const uint32_t a = base + uint32_t(j * (n + 1) + i), b = a + 1, c = a + uint32_t(n + 1) + 1, d = a + uint32_t(n + 1);
        m.triangles.insert(m.triangles.end(), {a, b, c, a, c, d});
      }
  };
  const glm::vec3 e = hi - lo;
  face(lo, {0, e.y, 0}, {e.x, 0, 0});                      // z = lo (normal -z)
  face({lo.x, lo.y, hi.z}, {e.x, 0, 0}, {0, e.y, 0});      // z = hi
  face(lo, {e.x, 0, 0}, {0, 0, e.z});                      // y = lo
  face({lo.x, hi.y, lo.z}, {0, 0, e.z}, {e.x, 0, 0});      // y = hi
  face(lo, {0, 0, e.z}, {0, e.y, 0});                      // x = lo
  face({hi.x, lo.y, lo.z}, {0, e.y, 0}, {0, 0, e.z});      // x = hi
  return m;
}

// Open cylinder along x from x0 to x1 with `radius`, `rings` x `segments` quads.
inline Mesh makeCylinder(float x0, float x1, float radius, int rings, int segments, glm::vec3 offset = glm::vec3(0.0f)) {
  Mesh m;
  const float pi = 3.14159265358979f;
  for (int r = 0; r <= rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const float ph = 2.0f * pi * float(s) / float(segments);
      m.positions.push_back(offset + glm::vec3(x0 + (x1 - x0) * float(r) / float(rings), radius * std::cos(ph), radius * std::sin(ph)));
    }
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const uint32_t a = uint32_t(r * segments + s), b = uint32_t(r * segments + (s + 1) % segments);
      const uint32_t c = b + uint32_t(segments), d = a + uint32_t(segments);
      m.triangles.insert(m.triangles.end(), {a, b, c, a, c, d});
    }
  return m;
}

// Appends `b` to `a` (vertex attributes that both lack stay empty).
inline void appendMesh(Mesh& a, const Mesh& b) {
  const uint32_t base = static_cast<uint32_t>(a.positions.size());
  a.positions.insert(a.positions.end(), b.positions.begin(), b.positions.end());
  for (uint32_t i : b.triangles) a.triangles.push_back(base + i);
  for (uint32_t i : b.edges) a.edges.push_back(base + i);
  for (uint32_t i : b.points) a.points.push_back(base + i);
}

// A CAD-like part: a box plate with a sphere and a thin rod on it.
inline Mesh makeCadPart() {
  Mesh m = makeBox({0, 0, 0}, {4, 3, 0.5f}, 8);
  appendMesh(m, makeSphere({2, 1.5f, 1.2f}, 0.7f, 16, 24));
  appendMesh(m, makeCylinder(-1.0f, 5.0f, 0.05f, 24, 8, {0, 1.5f, 2.2f}));
  return m;
}

}  // namespace scenelod::test
