// Uniform-subdivision clustering (Rossignac & Borrel 1993): the bounding box is cut into cubes of
// the cell width, starting at its minimum corner, and the vertices in one cube form a cluster. The
// baseline Low & Tan 1997 §3.2 compares floating cells with.
#include <algorithm>
#include <cmath>

#include "cluster_internal.h"

namespace scenelod::detail {

void assignUniform(const PreparedMesh& p, float cell_width, Assignment& out) {
  out.reset(p.mesh->vertexCount(), cell_width, true, CellShape::kCube);
  out.grid_origin = p.bounds.min;
  const float inv = 1.0f / cell_width;
  const double patches = 2.0 * p.surface_area / (double(cell_width) * double(cell_width));
  GridHash grid(static_cast<size_t>(std::min(double(p.order.size()), patches)) + 16);
  // visiting vertices heaviest first makes each cluster's id order and its first vertex the heaviest
  const PositionsByWeight sorted(p);
  for (size_t i = 0; i < p.order.size(); ++i) {
    const uint32_t v = p.order[i];
    const glm::vec3 q = (sorted[i] - out.grid_origin) * inv;
    const GridKey key{floorToInt(q.x), floorToInt(q.y),
                      floorToInt(q.z)};
    uint32_t& c = grid.at(key);
    if (c == kNone) {
      c = out.cluster_count++;
      out.heaviest.push_back(v);
    }
    out.cluster_of[v] = c;
  }
}

}  // namespace scenelod::detail
