#pragma once
// Thick edges for renderers (Low & Tan 1997 §3.3): an edge left by collapsing an elongated part
// carries a thickness (Mesh::edge_thickness, object space); a renderer draws it as a line of
// thickness / R pixels (R the object-space size of one pixel) and shades it with a dynamic normal.
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace scenelod {

// The dynamic normal of edge v1-v2 seen from `camera` (§3.3.2): ((V1-C) x (V2-C)) x (V2-V1),
// normalised. It is perpendicular to the edge, lies in the plane of the edge and the camera, and
// makes an acute angle with the direction from the edge to the camera. Returns (0,0,0) when the
// camera is on the edge's line or the edge has zero length. Per-frame safe: no allocation.
inline glm::vec3 dynamicNormal(const glm::vec3& v1, const glm::vec3& v2, const glm::vec3& camera) {
  const glm::vec3 n = glm::cross(glm::cross(v1 - camera, v2 - camera), v2 - v1);
  const float len2 = glm::dot(n, n);
  if (!(len2 > 0.0f)) return glm::vec3(0.0f);
  return n / glm::sqrt(len2);
}

// Pixel width of a thick edge of object-space `thickness` when one pixel covers `pixel_size` object
// units (R of §4). Returns at least 1 (a hairline). Per-frame safe.
inline float thickEdgePixelWidth(float thickness, float pixel_size) {
  const float w = pixel_size > 0.0f ? thickness / pixel_size : 1.0f;
  return w > 1.0f ? w : 1.0f;
}

}  // namespace scenelod
