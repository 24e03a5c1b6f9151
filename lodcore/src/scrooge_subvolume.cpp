// SCROOGE sub-volume restriction and edge degradation, Reddy 1996 §5 and §6.
//
// Sub-volumes are the cells of a grid over the bounding box, run in up to 8 passes with the grid
// shifted by half a cell per axis (§5: offsets (w l/2, h m/2, d n/2)), so polygons on a cell face in
// one pass lie inside a cell of another. A hash grid from cell key to polygons finds the polygons
// wholly inside each cell. A point is owned by a cell when every polygon using it lies inside that
// cell; only owned points move (§6.1). Moves are also refused when they would put a point farther
// than l_max (the sub-volume diagonal) from where it started, so the passes cannot add up past it.
#include <algorithm>
#include <cmath>
#include <unordered_map>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include "scrooge_model.h"

namespace scenelod::scrooge {

namespace {

constexpr uint32_t kMixed = 0xffffffffu;  // point used by polygons of several cells or none
constexpr uint32_t kUnset = 0xfffffffeu;

struct Key {
  int64_t x, y, z;
  bool operator==(const Key& o) const { return x == o.x && y == o.y && z == o.z; }
  bool operator<(const Key& o) const { return x != o.x ? x < o.x : (y != o.y ? y < o.y : z < o.z); }
};
struct KeyHash {
  size_t operator()(const Key& k) const { return size_t(mix(uint64_t(k.x) ^ mix(uint64_t(k.y) ^ mix(uint64_t(k.z))))); }
};

// closed cell [k s, (k+1) s] along one axis holding the interval [a, b], if there is one
bool cellOfInterval(double a, double b, double s, int64_t& k) {
  const int64_t k1 = int64_t(std::floor(a / s));
  const int64_t k2 = int64_t(std::ceil(b / s)) - 1;
  if (k2 > k1) return false;
  k = k1;  // k2 < k1 only when the interval is a single grid plane: either neighbour holds it
  return true;
}

}  // namespace

size_t degradeFaces(Model& m, const std::vector<uint32_t>& faces, const std::vector<uint32_t>& owner, uint32_t cell,
                    double l_max, double theta_min, double theta_max, bool prevent_foldover) {
  // directed edges of the sub-volume's polygons (with the first polygon holding each), sorted by start
  // point (§6.3 step 2)
  struct DirectedEdge {
    uint32_t from, to, face;
    bool operator<(const DirectedEdge& o) const {
      return from != o.from ? from < o.from : (to != o.to ? to < o.to : face < o.face);
    }
  };
  std::vector<DirectedEdge> out_edges;
  for (uint32_t f : faces) {
    const std::vector<uint32_t>& pts = m.faces[f].pts;
    for (size_t i = 0; i < pts.size(); ++i) out_edges.push_back({pts[i], pts[(i + 1) % pts.size()], f});
  }
  std::sort(out_edges.begin(), out_edges.end());
  out_edges.erase(std::unique(out_edges.begin(), out_edges.end(),
                              [](const DirectedEdge& a, const DirectedEdge& b) { return a.from == b.from && a.to == b.to; }),
                  out_edges.end());
  // the uv of a point in a polygon: the corner's own, or the point's interpolated one once it moved
  auto uvAt = [&](uint32_t face, uint32_t point) {
    if (m.point_uv_moved[point]) return m.point_uv[point];
    const Face& f = m.faces[face];
    for (size_t i = 0; i < f.pts.size(); ++i)
      if (f.pts[i] == point) return m.vertex_uv[f.verts[i]];
    return glm::vec2(0.0f);
  };
  // polygons around each point, to refuse moves that would turn one over
  std::vector<std::pair<uint32_t, uint32_t>> point_faces;
  for (uint32_t f : faces)
    for (uint32_t p : m.faces[f].pts) point_faces.emplace_back(p, f);
  std::sort(point_faces.begin(), point_faces.end());
  point_faces.erase(std::unique(point_faces.begin(), point_faces.end()), point_faces.end());
  auto foldsOver = [&](uint32_t v, const glm::vec3& to) {
    auto range = std::equal_range(point_faces.begin(), point_faces.end(), std::make_pair(v, 0u),
                                  [](const auto& a, const auto& b) { return a.first < b.first; });
    for (auto it = range.first; it != range.second; ++it) {
      const std::vector<uint32_t>& pts = m.faces[it->second].pts;
      glm::dvec3 before(0.0), after(0.0);
      const glm::dvec3 o(m.points[pts[0]]);
      const glm::dvec3 o_after = pts[0] == v ? glm::dvec3(to) : o;
      for (size_t i = 0; i < pts.size(); ++i) {
        const uint32_t a = pts[i], b = pts[(i + 1) % pts.size()];
        const glm::dvec3 pa(m.points[a]), pb(m.points[b]);
        before += glm::cross(pa - o, pb - o);
        after += glm::cross((a == v ? glm::dvec3(to) : pa) - o_after, (b == v ? glm::dvec3(to) : pb) - o_after);
      }
      const double lb = glm::length(before);
      // a polygon may flatten (the one being collapsed does) but not turn its back
      if (lb > 0.0 && glm::dot(before, after) < -1e-6 * lb * lb) return true;
    }
    return false;
  };

  size_t moves = 0;
  for (uint32_t f : faces) {
    const std::vector<uint32_t>& pts = m.faces[f].pts;
    for (size_t i = 0; i < pts.size(); ++i) {
      const uint32_t v1 = pts[i], v2 = pts[(i + 1) % pts.size()];
      if (owner[v2] != cell) continue;  // shared with a polygon outside the sub-volume (§6.1)
      const glm::dvec3 p1(m.points[v1]), p2(m.points[v2]);
      const glm::dvec3 d1 = p2 - p1;
      const double l_d1 = glm::length(d1);
      if (!(l_d1 > 0.0)) continue;
      // the connected edge bending least (§6.3 step 3a)
      auto range = std::equal_range(out_edges.begin(), out_edges.end(), DirectedEdge{v2, 0u, 0u},
                                    [](const DirectedEdge& a, const DirectedEdge& b) { return a.from < b.from; });
      double best_theta = 1e9;
      uint32_t v3 = kNoPoint, v3_face = 0;
      for (auto it = range.first; it != range.second; ++it) {
        if (it->to == v1) continue;
        const glm::dvec3 d2 = glm::dvec3(m.points[it->to]) - p2;
        const double l_d2 = glm::length(d2);
        if (!(l_d2 > 0.0)) continue;
        const double theta = std::acos(std::clamp(glm::dot(d1, d2) / (l_d1 * l_d2), -1.0, 1.0));
        if (theta < best_theta) { best_theta = theta; v3 = it->to; v3_face = it->face; }
      }
      if (v3 == kNoPoint) continue;
      // l(theta) falls linearly from l_max at theta_min to 0 at theta_max (§6.2, slope sign fixed)
      const double threshold = l_max * (theta_max - best_theta) / (theta_max - theta_min);
      const glm::dvec3 p3(m.points[v3]);
      const glm::dvec3 e2 = p3 - p1;
      const double l2 = glm::dot(e2, e2);
      if (!(std::sqrt(l2) < threshold) || !(l2 > 0.0)) continue;
      // perpendicular projection of v2 onto the segment v1->v3 (§6, Fig. 3)
      const double r = glm::dot(d1, e2) / l2;
      if (!(r > 0.0 && r < 1.0)) continue;
      const glm::vec3 moved = glm::vec3(p1 + r * e2);
      if (moved == m.points[v2]) continue;
      if (glm::length(glm::dvec3(moved) - glm::dvec3(m.origin[v2])) > l_max) continue;
      if (prevent_foldover && foldsOver(v2, moved)) continue;
      m.points[v2] = moved;
      if (!m.vertex_uv.empty()) {  // v2 is inside one chart: its uv slides along the same segment
        m.point_uv[v2] = uvAt(f, v1) + float(r) * (uvAt(v3_face, v3) - uvAt(f, v1));
        m.point_uv_moved[v2] = 1;
      }
      ++moves;
    }
  }
  return moves;
}

void degradeInSubvolumes(Model& m, const ScroogeParams& params, ScroogeStats& stats) {
  if (m.points.empty()) return;
  Aabb box;
  box.min = box.max = m.points[0];
  for (const glm::vec3& p : m.points) {
    box.min = glm::min(box.min, p);
    box.max = glm::max(box.max, p);
  }
  const glm::dvec3 size(params.subvolume_size);
  const double l_max = glm::length(size);
  const double theta_min = double(params.theta_min_deg) * M_PI / 180.0;
  const double theta_max = double(params.theta_max_deg) * M_PI / 180.0;

  // points of edge and point primitives never move
  std::vector<uint8_t> pinned(m.points.size(), 0);
  for (uint32_t v : m.edge_verts) pinned[m.vertex_point[v]] = 1;
  for (uint32_t v : m.point_verts) pinned[m.vertex_point[v]] = 1;
  // with texture coordinates, neither do points on a chart border or a uv seam (corners of several
  // charts or uvs there): only a point inside one chart can take an interpolated uv
  if (!m.vertex_uv.empty()) {
    std::vector<uint32_t> first(m.points.size(), kNoPoint);  // a corner vertex at the point
    std::vector<uint32_t> chart(m.points.size(), 0);
    for (const Face& face : m.faces)
      for (size_t i = 0; face.alive && i < face.pts.size(); ++i) {
        const uint32_t p = face.pts[i], v = face.verts[i];
        if (first[p] == kNoPoint) {
          first[p] = v;
          chart[p] = face.chart;
        } else if (chart[p] != face.chart || m.vertex_uv[v] != m.vertex_uv[first[p]]) {
          pinned[p] = 1;
        }
      }
  }

  const int pass_count = params.overlap_passes ? 8 : 1;
  std::vector<uint32_t> owner(m.points.size());
  for (int pass = 0; pass < pass_count; ++pass) {
    const glm::dvec3 shift((pass & 1) ? 0.5 : 0.0, (pass & 2) ? 0.5 : 0.0, (pass & 4) ? 0.5 : 0.0);
    const glm::dvec3 grid_origin = glm::dvec3(box.min) - shift * size;

    // hash grid: cell -> polygons wholly inside it
    std::unordered_map<Key, uint32_t, KeyHash> cell_index;
    std::vector<Key> keys;
    std::vector<uint32_t> face_cell(m.faces.size(), kMixed);
    for (size_t f = 0; f < m.faces.size(); ++f) {
      const Face& face = m.faces[f];
      if (!face.alive) continue;
      glm::dvec3 lo(m.points[face.pts[0]]), hi = lo;
      for (uint32_t p : face.pts) {
        lo = glm::min(lo, glm::dvec3(m.points[p]));
        hi = glm::max(hi, glm::dvec3(m.points[p]));
      }
      lo -= grid_origin;
      hi -= grid_origin;
      Key k;
      if (!cellOfInterval(lo.x, hi.x, size.x, k.x) || !cellOfInterval(lo.y, hi.y, size.y, k.y) ||
          !cellOfInterval(lo.z, hi.z, size.z, k.z))
        continue;
      auto it = cell_index.emplace(k, uint32_t(keys.size()));
      if (it.second) keys.push_back(k);
      face_cell[f] = it.first->second;
    }
    if (keys.empty()) continue;
    // cells in key order, so the new faces come out in the same order on any thread count
    std::vector<uint32_t> order(keys.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = uint32_t(i);
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return keys[a] < keys[b]; });
    std::vector<uint32_t> rank(keys.size());
    for (size_t i = 0; i < order.size(); ++i) rank[order[i]] = uint32_t(i);
    std::vector<std::vector<uint32_t>> cell_faces(keys.size());
    for (size_t f = 0; f < m.faces.size(); ++f)
      if (face_cell[f] != kMixed) cell_faces[rank[face_cell[f]]].push_back(uint32_t(f));

    // owner of each point: the one cell all its polygons lie in, else kMixed
    std::fill(owner.begin(), owner.end(), kUnset);
    for (size_t f = 0; f < m.faces.size(); ++f) {
      const Face& face = m.faces[f];
      if (!face.alive) continue;
      const uint32_t c = face_cell[f] == kMixed ? kMixed : rank[face_cell[f]];
      for (uint32_t p : face.pts) {
        if (owner[p] == kUnset) owner[p] = c;
        else if (owner[p] != c) owner[p] = kMixed;
      }
    }
    for (size_t p = 0; p < owner.size(); ++p)
      if (pinned[p]) owner[p] = kMixed;

    std::vector<std::vector<Face>> added(keys.size());
    std::vector<size_t> moves(keys.size(), 0), merges(keys.size(), 0);
    tbb::parallel_for(size_t(0), keys.size(), [&](size_t c) {
      // cells touch disjoint points and faces: each writes only what it owns
      moves[c] = degradeFaces(m, cell_faces[c], owner, uint32_t(c), l_max, theta_min, theta_max, params.prevent_foldover);
      merges[c] = reconstructFaces(m, cell_faces[c], params, added[c]);
    });
    for (size_t c = 0; c < keys.size(); ++c) {
      stats.moved_vertices += moves[c];
      stats.merged_groups += merges[c];
      for (Face& f : added[c]) m.faces.push_back(std::move(f));
    }
    m.faces.erase(std::remove_if(m.faces.begin(), m.faces.end(), [](const Face& f) { return !f.alive; }),
                  m.faces.end());
  }
  finishFaces(m, params, l_max);
}

}  // namespace scenelod::scrooge
