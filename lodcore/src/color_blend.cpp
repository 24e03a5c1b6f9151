// Area-weighted colour blending, Reddy 1996 (SCROOGE §7.3).
#include "scenelod/lodcore/color_blend.h"

#include <vector>

#include <glm/geometric.hpp>

namespace scenelod {

void areaWeightedColors(const Mesh& mesh, Span<const uint32_t> vertex_group, Span<glm::vec3> group_colors) {
  const size_t n = mesh.vertexCount();
  const bool has_colors = mesh.colors.size() == n;
  // barycentric area of every vertex: a third of each incident triangle's area
  std::vector<double> vertex_area(n, 0.0);
  for (size_t t = 0; t + 2 < mesh.triangles.size(); t += 3) {
    const uint32_t a = mesh.triangles[t], b = mesh.triangles[t + 1], c = mesh.triangles[t + 2];
    const double area =
        0.5 * glm::length(glm::cross(mesh.positions[b] - mesh.positions[a], mesh.positions[c] - mesh.positions[a]));
    vertex_area[a] += area / 3.0;
    vertex_area[b] += area / 3.0;
    vertex_area[c] += area / 3.0;
  }
  struct Acc {
    glm::dvec3 weighted{0.0};
    double area = 0.0;
    glm::dvec3 plain{0.0};
    size_t count = 0;
  };
  std::vector<Acc> acc(group_colors.size());
  for (size_t v = 0; v < n && v < vertex_group.size(); ++v) {
    const uint32_t g = vertex_group[v];
    if (g == kNoGroup || g >= acc.size()) continue;
    const glm::dvec3 c = has_colors ? glm::dvec3(mesh.colors[v]) : glm::dvec3(1.0);
    acc[g].weighted += vertex_area[v] * c;
    acc[g].area += vertex_area[v];
    acc[g].plain += c;
    ++acc[g].count;
  }
  for (size_t g = 0; g < acc.size(); ++g) {
    if (acc[g].area > 0.0)
      group_colors[g] = glm::vec3(acc[g].weighted / acc[g].area);
    else if (acc[g].count > 0)
      group_colors[g] = glm::vec3(acc[g].plain / double(acc[g].count));
    else
      group_colors[g] = glm::vec3(0.0f);
  }
}

glm::vec3 polygonMeanColor(const glm::vec3* p, const glm::vec3* c, size_t count) {
  if (count == 0) return glm::vec3(0.0f);
  glm::dvec3 weighted(0.0), plain(0.0);
  double area = 0.0;
  for (size_t i = 0; i < count; ++i) plain += glm::dvec3(c[i]);
  for (size_t i = 1; i + 1 < count; ++i) {
    const double a = 0.5 * glm::length(glm::cross(glm::dvec3(p[i] - p[0]), glm::dvec3(p[i + 1] - p[0])));
    weighted += a * (glm::dvec3(c[0]) + glm::dvec3(c[i]) + glm::dvec3(c[i + 1])) / 3.0;
    area += a;
  }
  if (area > 0.0) return glm::vec3(weighted / area);
  return glm::vec3(plain / double(count));
}

}  // namespace scenelod
