// Adjustment of normals (Low & Tan 1997 §2 step 6): face normals of the simplified triangles, and
// vertex normals that average only faces within a crease angle of each other, splitting a cluster's
// vertex into one copy per distinct normal. Vertices only used by edges and points take the
// cluster's area-weighted normal of the original faces (edges are shaded with dynamic normals).
#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/vec4.hpp>

#include "cluster_internal.h"

namespace scenelod::detail {

void buildOutputMesh(Eliminated& e, const Representatives& r, float crease_angle_deg, Mesh& out) {
  out = Mesh();
  const size_t nc = r.positions.size();
  const size_t tn = e.triangles.size() / 3;
  const bool colors = !r.colors.empty();
  const float cos_crease = std::cos(std::clamp(crease_angle_deg, 0.0f, 180.0f) * 3.14159265358979f / 180.0f);

  std::vector<glm::vec4> face(tn);  // xyz: unit face normal (0 when degenerate), w: twice the area
  for (size_t t = 0; t < tn; ++t) {
    const glm::vec3& a = r.positions[e.triangles[3 * t]];
    const glm::vec3 n = glm::cross(r.positions[e.triangles[3 * t + 1]] - a, r.positions[e.triangles[3 * t + 2]] - a);
    const float l = glm::length(n);
    face[t] = l > 0.0f ? glm::vec4(n / l, l) : glm::vec4(0.0f);
  }
  // cluster -> incident triangle corners
  std::vector<uint32_t> offsets(nc + 1, 0);
  for (uint32_t c : e.triangles) ++offsets[c + 1];
  for (size_t c = 0; c < nc; ++c) offsets[c + 1] += offsets[c];
  std::vector<uint32_t> corners(e.triangles.size());
  {
    std::vector<uint32_t> fill(offsets.begin(), offsets.end() - 1);
    for (size_t i = 0; i < e.triangles.size(); ++i) corners[fill[e.triangles[i]]++] = static_cast<uint32_t>(i);
  }
  std::vector<uint8_t> needs_vertex(nc, 0);
  for (uint32_t c : e.edges) needs_vertex[c] = 1;
  for (uint32_t c : e.points) needs_vertex[c] = 1;

  std::vector<uint32_t> base_vertex(nc, kNone);
  // one vertex per used cluster, plus its copies split at creases (a few per cent on scanned meshes):
  // reserving that, not the cluster count, keeps the arrays from doubling on the first split
  size_t used_count = 0;
  for (size_t c = 0; c < nc; ++c) used_count += offsets[c + 1] != offsets[c] || needs_vertex[c];
  const size_t expected_vertices = used_count + used_count / 16 + 16;
  out.positions.reserve(expected_vertices);
  out.normals.reserve(expected_vertices);
  if (colors) out.colors.reserve(expected_vertices);
  auto addVertex = [&](uint32_t c, const glm::vec3& n) {
    out.positions.push_back(r.positions[c]);
    out.normals.push_back(n);
    if (colors) out.colors.push_back(r.colors[c]);
    return static_cast<uint32_t>(out.positions.size() - 1);
  };
  for (uint32_t c = 0; c < nc; ++c) {
    const uint32_t b = offsets[c], en = offsets[c + 1];
    const uint32_t first_vertex = static_cast<uint32_t>(out.positions.size());
    for (uint32_t i = b; i < en; ++i) {
      const uint32_t t = corners[i] / 3;
      const glm::vec3 ut(face[t]);
      glm::vec3 n(0.0f);
      for (uint32_t j = b; j < en; ++j) {
        const uint32_t u = corners[j] / 3;
        const glm::vec3 uu(face[u]);
        if (u == t || glm::dot(ut, uu) >= cos_crease) n += uu * face[u].w;
      }
      const float l = glm::length(n);
      n = l > 0.0f ? n / l : r.normals[c];
      uint32_t v = kNone;
      for (uint32_t k = first_vertex; k < out.positions.size(); ++k)
        if (out.normals[k] == n) {
          v = k;
          break;
        }
      if (v == kNone) v = addVertex(c, n);
      // each corner's cluster id is no longer read once the corner lists exist: the output
      // vertex takes its place, so the output triangles need no second array
      e.triangles[corners[i]] = v;
    }
    if (b != en) base_vertex[c] = first_vertex;
    else if (needs_vertex[c]) base_vertex[c] = addVertex(c, r.normals[c]);
  }
  std::vector<glm::vec4>().swap(face);
  // split vertices may have grown the arrays past the reserve: the chain keeps every level, so
  // give back the slack
  out.positions.shrink_to_fit();
  out.normals.shrink_to_fit();
  out.colors.shrink_to_fit();
  out.triangles = std::move(e.triangles);
  out.triangles.shrink_to_fit();  // elimination reserved for about 2 triangles per cluster
  out.edges.resize(e.edges.size());
  for (size_t i = 0; i < e.edges.size(); ++i) out.edges[i] = base_vertex[e.edges[i]];
  out.edge_thickness = std::move(e.edge_thickness);
  if (out.edge_thickness.size() != out.edges.size() / 2) out.edge_thickness.assign(out.edges.size() / 2, 0.0f);
  out.points.resize(e.points.size());
  for (size_t i = 0; i < e.points.size(); ++i) out.points[i] = base_vertex[e.points[i]];
}

}  // namespace scenelod::detail
