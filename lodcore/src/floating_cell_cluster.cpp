// Floating-cell clustering (Low & Tan 1997 §3.2 and §4). Vertices are visited heaviest first (the
// sort is done once per mesh, PreparedMesh); a vertex inside no existing cell becomes the centre of
// a new cell of width w (a cube of side w or a sphere of diameter w). A vertex inside several cells
// joins the one with the heaviest centre (§3.2) or, in the variant of §3.2.3, the nearest centre.
//
// §4's grid: space is cut into cubes of side w (from the origin, so the grid, like the cells, does not
// depend on the bounding box) and each cell is listed in the cube holding its centre. A cell's centre
// is never inside another cell, so two centres are more than w/2 apart along some axis (cube cells)
// or in distance (sphere cells): a grid cube lists at most 8 cube cells (one per w/2 octant) and at
// most 64 sphere cells (one per w/4 sub-cube, whose diagonal is below w/2). The lists are linked
// through a flat array, so their length needs no fixed bound. A cell containing a vertex at q (grid
// units) has its centre within 1/2 of q along each axis: only the 2 x 2 x 2 cubes covering
// [q - 1/2, q + 1/2] are searched.
#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "cluster_internal.h"

namespace scenelod::detail {

namespace {
// slack on the searched range so that a centre exactly on a cell's face is never missed by rounding
constexpr float kSearchSlack = 1e-4f;
}  // namespace

void assignFloating(const PreparedMesh& p, float cell_width, CellShape shape, bool nearest, Assignment& out) {
  const Mesh& m = *p.mesh;
  out.cluster_of.assign(m.vertexCount(), kNone);
  out.heaviest.clear();
  out.cluster_count = 0;
  out.cell_width = cell_width;
  out.uniform = false;
  out.shape = shape;
  const float inv = 1.0f / cell_width;
  const float half = 0.5f * cell_width;
  const float half2 = half * half;
  const bool cube = shape == CellShape::kCube;

  std::vector<glm::vec3> centre;  // per cell: its centre position (12 bytes, the hot data of the search)
  std::vector<uint32_t> next;     // per cell: next cell listed in the same grid cube
  // cells: about one per w x w patch of surface, never more than the vertices
  const double patches = 2.0 * p.surface_area / (double(cell_width) * double(cell_width));
  const size_t expected = static_cast<size_t>(std::min(double(p.order.size()), patches)) + 16;
  centre.reserve(expected);
  next.reserve(expected);
  out.heaviest.reserve(expected);
  GridHash grid(expected);

  const size_t n = p.order.size();
  for (size_t i = 0; i < n; ++i) {
    const uint32_t v = p.order[i];
    const glm::vec3 pv = p.sorted_positions[i];
    const glm::vec3 q = pv * inv;
    int32_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = floorToInt(q[a] - 0.5f - kSearchSlack);
      hi[a] = floorToInt(q[a] + 0.5f + kSearchSlack);
    }
    uint32_t best = kNone;
    float best_d2 = std::numeric_limits<float>::infinity();
    for (int32_t x = lo[0]; x <= hi[0]; ++x)
      for (int32_t y = lo[1]; y <= hi[1]; ++y)
        for (int32_t z = lo[2]; z <= hi[2]; ++z)
          for (uint32_t c = grid.find({x, y, z}); c != kNone; c = next[c]) {
            const glm::vec3 d = pv - centre[c];
            const float d2 = glm::dot(d, d);
            const bool inside = cube ? (std::fabs(d.x) <= half && std::fabs(d.y) <= half && std::fabs(d.z) <= half)
                                     : d2 <= half2;
            if (!inside) continue;
            // cells are numbered in creation order, which is the order of their centres' weights
            if (nearest ? (d2 < best_d2 || (d2 == best_d2 && c < best)) : c < best) {
              best = c;
              best_d2 = d2;
            }
          }
    if (best == kNone) {
      best = out.cluster_count++;
      centre.push_back(pv);
      out.heaviest.push_back(v);
      uint32_t& head = grid.at({floorToInt(q.x), floorToInt(q.y),
                                floorToInt(q.z)});
      next.push_back(head);
      head = best;
    }
    out.cluster_of[v] = best;
  }
}

void Assignment::cellBox(const Mesh& m, uint32_t c, glm::vec3& lo, glm::vec3& hi) const {
  const glm::vec3 p = m.positions[heaviest[c]];
  if (uniform) {
    const glm::vec3 q = (p - grid_origin) * (1.0f / cell_width);
    lo = grid_origin + glm::floor(q) * cell_width;
    hi = lo + glm::vec3(cell_width);
  } else {
    lo = p - glm::vec3(0.5f * cell_width);
    hi = p + glm::vec3(0.5f * cell_width);
  }
}

Error checkCellWidth(const PreparedMesh& p, float cell_width) {
  if (!std::isfinite(cell_width) || !(cell_width > 0.0f))
    return {Status::kInvalidArgument, "cell width " + std::to_string(cell_width) + " is not a finite positive number"};
  const glm::vec3 far = glm::max(glm::abs(p.bounds.min), glm::abs(p.bounds.max));
  const double extent = std::max({double(far.x), double(far.y), double(far.z)});
  if (extent / double(cell_width) > kMaxGridCoordinate)
    return {Status::kInvalidArgument, "cell width " + std::to_string(cell_width) +
                                          " is too small for coordinates up to " + std::to_string(extent) +
                                          " (more than 2^30 cells along an axis)"};
  return {};
}

}  // namespace scenelod::detail
