// Mesh validation, bounds, polygon triangulation (fan for convex faces, ear clipping otherwise) and
// area-weighted vertex normals.
#include "scenelod/lodcore/mesh.h"

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <vector>

#include <glm/geometric.hpp>

namespace scenelod {

float Aabb::diagonal() const { return glm::length(max - min); }

namespace {

bool finite3(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

namespace detail {

// every index below vertex_count, by comparisons the compiler vectorises (no early exit; a running
// unsigned maximum costs twice as many SSE2 operations)
bool indicesBelow(const uint32_t* idx, size_t count, size_t vertex_count) {
  if (vertex_count > UINT32_MAX) return true;
  const uint32_t limit = static_cast<uint32_t>(vertex_count);
  uint32_t bad = 0;
  for (size_t k = 0; k < count; ++k) bad |= idx[k] >= limit;
  return !bad;
}

}  // namespace detail

namespace {

// `known_in_range`: the caller has already found every index below the vertex count
Error checkIndices(const std::vector<uint32_t>& idx, size_t per, size_t vertex_count, const char* kind,
                   const std::string& what, bool known_in_range = false) {
  if (idx.size() % per != 0)
    return {Status::kInvalidMesh, what + ": " + kind + " index count " + std::to_string(idx.size()) +
                                      " is not a multiple of " + std::to_string(per)};
  // the first bad index is looked for only when there is one
  if (known_in_range || detail::indicesBelow(idx.data(), idx.size(), vertex_count)) return {};
  for (size_t i = 0; i < idx.size(); ++i)
    if (idx[i] >= vertex_count)
      return {Status::kInvalidMesh, what + ": " + kind + " " +
                                        std::to_string(i / per) + " uses vertex index " + std::to_string(idx[i]) +
                                        " but the mesh has " + std::to_string(vertex_count) + " vertices"};
  return {};
}

template <class Vec>
Error checkStream(const std::vector<Vec>& v, size_t n, const std::string& name, const std::string& what) {
  if (v.empty()) return {};
  if (v.size() != n)
    return {Status::kInvalidMesh, what + ": " + std::to_string(v.size()) + " " + name + " for " + std::to_string(n) +
                                      " vertices"};
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < Vec::length(); ++c)
      if (!std::isfinite(v[i][c]))
        return {Status::kInvalidMesh, what + ": vertex " + std::to_string(i) + " has a NaN or infinite value in its " + name};
  return {};
}

// the skeleton: parents in range and no cycle
Error checkSkeleton(const std::vector<int32_t>& parents, const std::string& what) {
  const size_t j = parents.size();
  for (size_t i = 0; i < j; ++i)
    if (parents[i] < -1 || parents[i] >= static_cast<int64_t>(j))
      return {Status::kInvalidMesh, what + ": joint " + std::to_string(i) + " has parent " + std::to_string(parents[i]) +
                                        " but the skeleton has " + std::to_string(j) + " joints"};
  const size_t cycle = firstParentCycle(Span<const int32_t>(parents.data(), j));
  if (cycle < j)
    return {Status::kInvalidMesh, what + ": the skeleton's joint parents form a cycle through joint " + std::to_string(cycle)};
  return {};
}

// texture coordinates, tangents and skin: sizes, finite values, tangent signs, weights, joints
Error checkAttributes(const Mesh& m, const std::string& what) {
  const size_t n = m.positions.size();
  if (Error e = checkStream(m.uvs, n, "texture coordinates", what); !e.ok()) return e;
  for (size_t s = 0; s < m.extra_uvs.size(); ++s)
    if (Error e = checkStream(m.extra_uvs[s], n, "texture coordinates (set " + std::to_string(s + 1) + ")", what); !e.ok())
      return e;
  if (Error e = checkStream(m.tangents, n, "tangents", what); !e.ok()) return e;
  for (size_t i = 0; i < m.tangents.size(); ++i)
    if (std::fabs(m.tangents[i].w) != 1.0f)
      return {Status::kInvalidMesh, what + ": vertex " + std::to_string(i) + " has tangent sign w = " +
                                        std::to_string(m.tangents[i].w) + " (must be +1 or -1)"};
  if (m.joints.empty() != m.weights.empty())
    return {Status::kInvalidMesh, what + (m.joints.empty() ? ": skin weights without joints" : ": skin joints without weights")};
  if (!m.joints.empty() && m.joints.size() != n)
    return {Status::kInvalidMesh, what + ": " + std::to_string(m.joints.size()) + " skin joints for " + std::to_string(n) +
                                      " vertices"};
  if (Error e = checkStream(m.weights, n, "skin weights", what); !e.ok()) return e;
  for (size_t i = 0; i < m.weights.size(); ++i) {
    const glm::vec4& w = m.weights[i];
    if (w.x < 0.0f || w.y < 0.0f || w.z < 0.0f || w.w < 0.0f || !(w.x + w.y + w.z + w.w > 0.0f))
      return {Status::kInvalidMesh, what + ": vertex " + std::to_string(i) +
                                        " has a negative skin weight or weights summing to 0"};
  }
  if (Error e = checkSkeleton(m.joint_parents, what); !e.ok()) return e;
  if (!m.joint_parents.empty())
    for (size_t i = 0; i < m.joints.size(); ++i)
      for (int c = 0; c < 4; ++c)
        if (m.joints[i][c] >= m.joint_parents.size())
          return {Status::kInvalidMesh, what + ": vertex " + std::to_string(i) + " uses joint " +
                                            std::to_string(m.joints[i][c]) + " but the skeleton has " +
                                            std::to_string(m.joint_parents.size()) + " joints"};
  return {};
}

glm::vec3 newellNormal(const Mesh& m, size_t begin, size_t end) {
  glm::vec3 n(0.0f);
  for (size_t i = begin; i < end; ++i) {
    const glm::vec3& a = m.positions[m.face_corners[i]];
    const glm::vec3& b = m.positions[m.face_corners[i + 1 < end ? i + 1 : begin]];
    n.x += (a.y - b.y) * (a.z + b.z);
    n.y += (a.z - b.z) * (a.x + b.x);
    n.z += (a.x - b.x) * (a.y + b.y);
  }
  return n;
}

}  // namespace

namespace detail {

// every coordinate finite, checked without an early exit (vectorised)
bool coordinatesFinite(const Mesh& m) {
  // a vec3 is three packed floats: the coordinates are read as one array
  static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "packed vec3");
  const size_t n = m.positions.size();
  const float* coord = n ? &m.positions[0].x : nullptr;
  int bad = 0;
  for (size_t k = 0; k < 3 * n; ++k) bad |= !(std::fabs(coord[k]) <= FLT_MAX);
  return !bad;
}

// validateMesh with the answers of its two largest scans given: whether every coordinate is finite
// and whether every triangle and edge index is below the vertex count. prepareMesh makes those
// scans in its own first passes, which read the coordinates and indices anyway; given false, the
// first bad element is looked for here, so the error is validateMesh's.
Error validateMeshScanned(const Mesh& m, const std::string& what, bool coordinates_finite,
                          bool indices_in_range) {
  const size_t n = m.positions.size();
  // the first bad vertex only on failure
  for (size_t i = 0; !coordinates_finite && i < n; ++i)
    if (!finite3(m.positions[i]))
      return {Status::kInvalidMesh, what + ": vertex " + std::to_string(i) + " has a NaN or infinite coordinate"};
  if (!m.normals.empty() && m.normals.size() != n)
    return {Status::kInvalidMesh, what + ": " + std::to_string(m.normals.size()) + " normals for " +
                                      std::to_string(n) + " vertices"};
  if (!m.colors.empty() && m.colors.size() != n)
    return {Status::kInvalidMesh, what + ": " + std::to_string(m.colors.size()) + " colours for " +
                                      std::to_string(n) + " vertices"};
  if (Error e = checkAttributes(m, what); !e.ok()) return e;
  if (Error e = checkIndices(m.triangles, 3, n, "triangle", what, indices_in_range); !e.ok()) return e;
  if (Error e = checkIndices(m.edges, 2, n, "edge", what, indices_in_range); !e.ok()) return e;
  if (!m.triangle_groups.empty() && m.triangle_groups.size() != m.triangleCount())
    return {Status::kInvalidMesh, what + ": " + std::to_string(m.triangle_groups.size()) + " triangle groups for " +
                                      std::to_string(m.triangleCount()) + " triangles"};
  if (Error e = checkIndices(m.points, 1, n, "point", what); !e.ok()) return e;
  if (!m.edge_groups.empty() && m.edge_groups.size() != m.edgeCount())
    return {Status::kInvalidMesh, what + ": " + std::to_string(m.edge_groups.size()) + " edge groups for " +
                                      std::to_string(m.edgeCount()) + " edges"};
  if (!m.point_groups.empty() && m.point_groups.size() != m.pointCount())
    return {Status::kInvalidMesh, what + ": " + std::to_string(m.point_groups.size()) + " point groups for " +
                                      std::to_string(m.pointCount()) + " points"};
  if (!m.edge_thickness.empty()) {
    if (m.edge_thickness.size() != m.edgeCount())
      return {Status::kInvalidMesh, what + ": " + std::to_string(m.edge_thickness.size()) +
                                        " edge thicknesses for " + std::to_string(m.edgeCount()) + " edges"};
    for (size_t e = 0; e < m.edge_thickness.size(); ++e)
      if (!std::isfinite(m.edge_thickness[e]) || m.edge_thickness[e] < 0.0f)
        return {Status::kInvalidMesh, what + ": edge " + std::to_string(e) + " has a negative or non-finite thickness"};
  }
  if (!m.face_offsets.empty()) {
    if (m.face_offsets.front() != 0 || m.face_offsets.back() != m.face_corners.size())
      return {Status::kInvalidMesh, what + ": face offsets do not span the corner list"};
    for (size_t f = 0; f + 1 < m.face_offsets.size(); ++f)
      if (m.face_offsets[f] > m.face_offsets[f + 1])
        return {Status::kInvalidMesh, what + ": face offsets decrease at face " + std::to_string(f)};
    if (Error e = checkIndices(m.face_corners, 1, n, "face corner", what); !e.ok()) return e;
  } else if (!m.face_corners.empty()) {
    return {Status::kInvalidMesh, what + ": face corners without face offsets"};
  }
  return {};
}

}  // namespace detail

size_t firstParentCycle(Span<const int32_t> parent) {
  const size_t n = parent.size();
  std::vector<uint8_t> state(n, 0);  // 0 unvisited, 1 on the current walk, 2 reaches a root
  std::vector<size_t> walk;
  for (size_t i = 0; i < n; ++i) {
    walk.clear();
    size_t k = i;
    while (state[k] == 0) {
      state[k] = 1;
      walk.push_back(k);
      if (parent[k] < 0) break;
      k = static_cast<size_t>(parent[k]);
    }
    if (state[k] == 1 && parent[k] >= 0) return k;
    for (size_t w : walk) state[w] = 2;
  }
  return n;
}

Error validateMesh(const Mesh& m, const std::string& what) {
  return detail::validateMeshScanned(m, what, detail::coordinatesFinite(m), false);
}

Error meshFromView(const MeshView& v, Mesh& out, const std::string& what) {
  out = Mesh{};
  if (v.positions.count > 0 && v.positions.data == nullptr)
    return {Status::kInvalidArgument, what + ": positions pointer is null"};
  if (v.triangles.count > 0 && v.triangles.data == nullptr)
    return {Status::kInvalidArgument, what + ": index pointer is null"};
  if (v.positions.stride < sizeof(glm::vec3) && v.positions.count > 1)
    return {Status::kInvalidArgument, what + ": position stride " + std::to_string(v.positions.stride) +
                                          " is smaller than 12 bytes"};
  out.positions.resize(v.positions.count);
  for (size_t i = 0; i < v.positions.count; ++i) out.positions[i] = v.positions[i];
  if (!v.normals.empty()) {
    out.normals.resize(v.normals.count);
    for (size_t i = 0; i < v.normals.count; ++i) out.normals[i] = v.normals[i];
  }
  if (!v.colors.empty()) {
    out.colors.resize(v.colors.count);
    for (size_t i = 0; i < v.colors.count; ++i) out.colors[i] = v.colors[i];
  }
  out.triangles.assign(v.triangles.begin(), v.triangles.end());
  return validateMesh(out, what);
}

Aabb computeBounds(Span<const glm::vec3> p) {
  Aabb b;
  if (p.empty()) return b;
  b.min = b.max = p[0];
  for (const glm::vec3& v : p) {
    b.min = glm::min(b.min, v);
    b.max = glm::max(b.max, v);
  }
  return b;
}

Aabb computeBounds(const Mesh& mesh) {
  return computeBounds(Span<const glm::vec3>(mesh.positions.data(), mesh.positions.size()));
}

size_t triangulateFaces(Mesh& m) {
  m.triangles.clear();
  std::vector<uint32_t> ring;
  std::vector<glm::vec2> flat;
  for (size_t f = 0; f + 1 < m.face_offsets.size(); ++f) {
    const size_t begin = m.face_offsets[f], end = m.face_offsets[f + 1], k = end - begin;
    if (k < 3) continue;
    if (k == 3) {
      m.triangles.insert(m.triangles.end(), m.face_corners.begin() + begin, m.face_corners.begin() + end);
      continue;
    }
    // project onto the plane of the Newell normal and ear-clip; convex faces come out as fans
    glm::vec3 n = newellNormal(m, begin, end);
    const float len = glm::length(n);
    if (!(len > 0.0f)) {  // degenerate face: a fan keeps its connectivity
      for (size_t i = 1; i + 1 < k; ++i)
        m.triangles.insert(m.triangles.end(), {m.face_corners[begin], m.face_corners[begin + i], m.face_corners[begin + i + 1]});
      continue;
    }
    n /= len;
    const glm::vec3 t = glm::normalize(std::fabs(n.x) > 0.9f ? glm::cross(n, glm::vec3(0, 1, 0)) : glm::cross(n, glm::vec3(1, 0, 0)));
    const glm::vec3 s = glm::cross(n, t);
    ring.assign(m.face_corners.begin() + begin, m.face_corners.begin() + end);
    flat.resize(k);
    for (size_t i = 0; i < k; ++i) {
      const glm::vec3& p = m.positions[ring[i]];
      flat[i] = glm::vec2(glm::dot(p, t), glm::dot(p, s));
    }
    std::vector<size_t> live(k);
    for (size_t i = 0; i < k; ++i) live[i] = i;
    auto cross2 = [](glm::vec2 a, glm::vec2 b, glm::vec2 c) { return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x); };
    size_t guard = 0;
    while (live.size() > 3 && guard < k * k) {
      ++guard;
      bool clipped = false;
      for (size_t i = 0; i < live.size(); ++i) {
        const size_t ia = live[(i + live.size() - 1) % live.size()], ib = live[i], ic = live[(i + 1) % live.size()];
        const glm::vec2 a = flat[ia], b = flat[ib], c = flat[ic];
        if (cross2(a, b, c) <= 0.0f) continue;  // reflex or flat corner
        bool inside = false;
        for (size_t j : live) {
          if (j == ia || j == ib || j == ic) continue;
          const glm::vec2 p = flat[j];
          if (cross2(a, b, p) >= 0.0f && cross2(b, c, p) >= 0.0f && cross2(c, a, p) >= 0.0f) { inside = true; break; }
        }
        if (inside) continue;
        m.triangles.insert(m.triangles.end(), {ring[ia], ring[ib], ring[ic]});
        live.erase(live.begin() + static_cast<std::ptrdiff_t>(i));
        clipped = true;
        break;
      }
      if (!clipped) break;  // self-intersecting polygon: finish with a fan below
    }
    for (size_t i = 1; i + 1 < live.size(); ++i)
      m.triangles.insert(m.triangles.end(), {ring[live[0]], ring[live[i]], ring[live[i + 1]]});
  }
  return m.triangleCount();
}

void computeVertexNormals(Mesh& m) {
  m.normals.assign(m.positions.size(), glm::vec3(0.0f));
  for (size_t t = 0; t + 2 < m.triangles.size(); t += 3) {
    const uint32_t a = m.triangles[t], b = m.triangles[t + 1], c = m.triangles[t + 2];
    // the unnormalised cross product weights each face by twice its area
    const glm::vec3 n = glm::cross(m.positions[b] - m.positions[a], m.positions[c] - m.positions[a]);
    m.normals[a] += n;
    m.normals[b] += n;
    m.normals[c] += n;
  }
  for (glm::vec3& n : m.normals) {
    const float len = glm::length(n);
    n = len > 0.0f ? n / len : glm::vec3(0.0f, 0.0f, 1.0f);
  }
}

}  // namespace scenelod
