// SCROOGE normalisation, Reddy 1996 §4 step 1 and §7.2: weld multiply-defined vertices, remove
// degenerate and multiply-defined polygons, edges and points, and coplanar sub-polygons.
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <map>
#include <unordered_map>

#include <glm/geometric.hpp>

#include "scenelod/lodcore/color_blend.h"
#include "scenelod/lodcore/mesh_attributes.h"
#include "scrooge_model.h"

namespace scenelod::scrooge {

namespace {

struct CellKey {
  int64_t x, y, z;
  bool operator==(const CellKey& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct CellHash {
  size_t operator()(const CellKey& k) const {
    return size_t(mix(uint64_t(k.x) ^ mix(uint64_t(k.y) ^ mix(uint64_t(k.z)))));
  }
};

// a vertex's full attribute record, compared bitwise so that only true duplicates merge
struct AttrKey {
  uint32_t point;
  float data[11];
  bool operator==(const AttrKey& o) const { return point == o.point && std::memcmp(data, o.data, sizeof(data)) == 0; }
};
struct AttrHash {
  size_t operator()(const AttrKey& k) const {
    size_t h = k.point * 2654435761u;
    uint32_t bits[11];
    std::memcpy(bits, k.data, sizeof(bits));
    for (uint32_t b : bits) h = h * 1000003u ^ b;
    return h;
  }
};

// welds positions: exact equality when eps is 0, else within eps (the first vertex of a cluster
// stays; later ones join the first point found within eps in the hash cells around them)
void weldPoints(const Mesh& in, float eps, Model& m) {
  const size_t n = in.vertexCount();
  m.vertex_point.assign(n, kNoPoint);
  std::unordered_map<CellKey, std::vector<uint32_t>, CellHash> grid;
  grid.reserve(n);
  for (size_t v = 0; v < n; ++v) {
    const glm::vec3 p = in.positions[v] + glm::vec3(0.0f);  // -0 becomes +0
    // cells of 4 eps: a point within eps of a neighbour cell also looks there, else only at home
    const double cell = 4.0 * double(eps);
    CellKey k;
    int lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    if (eps > 0.0f) {
      const double c[3] = {double(p.x) / cell, double(p.y) / cell, double(p.z) / cell};
      int64_t ki[3];
      for (int a = 0; a < 3; ++a) {
        ki[a] = int64_t(std::floor(c[a]));
        const double frac = (c[a] - double(ki[a])) * cell;
        lo[a] = frac <= double(eps) ? -1 : 0;
        hi[a] = frac >= cell - double(eps) ? 1 : 0;
      }
      k = {ki[0], ki[1], ki[2]};
    } else {
      uint32_t b[3];
      std::memcpy(b, &p, sizeof(b));
      k = {b[0], b[1], b[2]};
    }
    uint32_t found = kNoPoint;
    if (eps > 0.0f) {
      for (int dz = lo[2]; dz <= hi[2] && found == kNoPoint; ++dz)
        for (int dy = lo[1]; dy <= hi[1] && found == kNoPoint; ++dy)
          for (int dx = lo[0]; dx <= hi[0] && found == kNoPoint; ++dx) {
            auto it = grid.find({k.x + dx, k.y + dy, k.z + dz});
            if (it == grid.end()) continue;
            for (uint32_t q : it->second)
              if (glm::length(m.origin[q] - p) <= eps) { found = q; break; }
          }
    } else {
      auto it = grid.find(k);
      if (it != grid.end()) found = it->second.front();
    }
    if (found == kNoPoint) {
      found = uint32_t(m.points.size());
      m.points.push_back(p);
      m.origin.push_back(p);
      m.point_source.push_back(uint32_t(v));
      grid[k].push_back(found);
    }
    m.vertex_point[v] = found;
  }
}

}  // namespace

glm::dvec3 newellNormal(const Model& m, const std::vector<uint32_t>& pts) {
  glm::dvec3 n(0.0);
  const size_t k = pts.size();
  if (k < 3) return n;
  const glm::dvec3 o(m.points[pts[0]]);
  for (size_t i = 0; i < k; ++i) {
    const glm::dvec3 a = glm::dvec3(m.points[pts[i]]) - o, b = glm::dvec3(m.points[pts[(i + 1) % k]]) - o;
    n += glm::cross(a, b);
  }
  return n;  // twice the vector area
}

double faceArea(const Model& m, const std::vector<uint32_t>& pts) { return 0.5 * glm::length(newellNormal(m, pts)); }

bool isDegenerate(const Model& m, const std::vector<uint32_t>& pts) {
  if (pts.size() < 3) return true;
  double longest = 0.0, scale = 0.0;
  for (size_t i = 0; i < pts.size(); ++i) {
    const glm::dvec3 a(m.points[pts[i]]), b(m.points[pts[(i + 1) % pts.size()]]);
    longest = std::max(longest, glm::length(b - a));
    scale = std::max({scale, std::fabs(a.x), std::fabs(a.y), std::fabs(a.z)});
  }
  if (longest <= 0.0) return true;
  // thickness of the polygon across its longest edge against float resolution and its own size:
  // a polygon flattened by degradation is thinner than both
  const double thickness = 2.0 * faceArea(m, pts) / longest;
  return thickness <= std::max(1e-6 * longest, 16.0 * FLT_EPSILON * scale);
}

glm::vec3 faceMeanColor(const Mesh& in, const Model& m, const Face& f) {
  if (in.colors.size() != in.vertexCount()) return glm::vec3(1.0f);
  std::vector<glm::vec3> p(f.pts.size()), c(f.pts.size());
  for (size_t i = 0; i < f.pts.size(); ++i) {
    p[i] = m.points[f.pts[i]];
    c[i] = in.colors[f.verts[i]];
  }
  return polygonMeanColor(p.data(), c.data(), p.size());
}

namespace {

// the triangle group and uv chart of each input polygon (a face, or a triangle without faces). A face
// takes the group of its first triangle when the triangles are its triangulation (k - 2 per face of k
// corners, in face order), else group 0; charts are those of computeUvCharts on a fan of each face
void polygonChartsAndGroups(const Mesh& in, std::vector<uint32_t>& chart, std::vector<uint32_t>& group) {
  if (in.faceCount() == 0) {
    computeUvCharts(in, chart);
    group.resize(in.triangleCount());
    for (size_t t = 0; t < group.size(); ++t) group[t] = in.triangleGroup(t);
    return;
  }
  size_t expected = 0;
  for (size_t f = 0; f < in.faceCount(); ++f) {
    const size_t k = in.face_offsets[f + 1] - in.face_offsets[f];
    expected += k >= 3 ? k - 2 : 0;
  }
  const bool groups_match = !in.triangle_groups.empty() && expected == in.triangleCount();
  Mesh fans;
  fans.positions = in.positions;
  fans.uvs = in.uvs;
  fans.extra_uvs = in.extra_uvs;
  group.assign(in.faceCount(), 0);
  std::vector<uint32_t> first_fan(in.faceCount(), kNoPoint);
  size_t triangle = 0;
  for (size_t f = 0; f < in.faceCount(); ++f) {
    const size_t b = in.face_offsets[f], k = in.face_offsets[f + 1] - b;
    if (groups_match && k >= 3) group[f] = in.triangle_groups[triangle];
    triangle += k >= 3 ? k - 2 : 0;
    if (k < 3) continue;
    first_fan[f] = uint32_t(fans.triangleCount());
    for (size_t c = 1; c + 1 < k; ++c) {
      fans.triangles.insert(fans.triangles.end(), {in.face_corners[b], in.face_corners[b + c], in.face_corners[b + c + 1]});
      fans.triangle_groups.push_back(group[f]);
    }
  }
  std::vector<uint32_t> fan_chart;
  computeUvCharts(fans, fan_chart);
  chart.assign(in.faceCount(), 0);
  for (size_t f = 0; f < in.faceCount(); ++f)
    if (first_fan[f] != kNoPoint) chart[f] = fan_chart[first_fan[f]];
}

}  // namespace

void normaliseModel(const Mesh& in, const ScroogeParams& params, Model& m, ScroogeStats& stats) {
  m = Model{};
  const Aabb box = computeBounds(in);
  m.diagonal = box.diagonal();
  const float eps = params.weld_epsilon_rel * m.diagonal;
  weldPoints(in, eps, m);
  stats.input_vertices = in.vertexCount();
  stats.welded_vertices = in.vertexCount() - m.points.size();

  // canonical vertex per (point, attributes)
  const size_t n = in.vertexCount();
  std::vector<uint32_t> canon(n);
  {
    std::unordered_map<AttrKey, uint32_t, AttrHash> seen;
    seen.reserve(n);
    for (size_t v = 0; v < n; ++v) {
      AttrKey k{};
      k.point = m.vertex_point[v];
      if (!in.normals.empty()) std::memcpy(k.data + 0, &in.normals[v], 12);
      if (!in.colors.empty()) std::memcpy(k.data + 3, &in.colors[v], 12);
      if (!in.uvs.empty()) std::memcpy(k.data + 6, &in.uvs[v], 8);
      canon[v] = seen.emplace(k, uint32_t(v)).first->second;
    }
  }

  m.vertex_uv = in.uvs;
  m.point_uv.assign(in.uvs.empty() ? 0 : m.points.size(), glm::vec2(0.0f));
  m.point_uv_moved.assign(m.point_uv.size(), 0);
  std::vector<uint32_t> poly_chart, poly_group;
  polygonChartsAndGroups(in, poly_chart, poly_group);

  // polygons: the original faces when present, else the triangles
  const bool use_faces = in.faceCount() > 0;
  const size_t poly_count = use_faces ? in.faceCount() : in.triangleCount();
  stats.input_polygons = poly_count;
  std::map<std::vector<uint32_t>, uint32_t> seen_rings;
  for (size_t f = 0; f < poly_count; ++f) {
    const size_t begin = use_faces ? in.face_offsets[f] : 3 * f;
    const size_t end = use_faces ? in.face_offsets[f + 1] : 3 * f + 3;
    Face face;
    for (size_t c = begin; c < end; ++c) {
      const uint32_t v = canon[use_faces ? in.face_corners[c] : in.triangles[c]];
      const uint32_t p = m.vertex_point[v];
      if (!face.pts.empty() && face.pts.back() == p) continue;  // repeated corner
      face.pts.push_back(p);
      face.verts.push_back(v);
    }
    while (face.pts.size() > 1 && face.pts.front() == face.pts.back()) {
      face.pts.pop_back();
      face.verts.pop_back();
    }
    if (isDegenerate(m, face.pts)) {
      ++stats.degenerate_polygons;
      continue;
    }
    // same ring in the same orientation is a duplicate; the opposite orientation is a two-sided pair
    std::vector<uint32_t> ring = face.pts;
    std::rotate(ring.begin(), std::min_element(ring.begin(), ring.end()), ring.end());
    if (!seen_rings.emplace(std::move(ring), uint32_t(m.faces.size())).second) {
      ++stats.duplicate_polygons;
      continue;
    }
    face.color = faceMeanColor(in, m, face);
    face.group = poly_group[f];
    // without uvs, charts (exact position links) would split polygons that welding joined
    face.chart = in.uvs.empty() ? face.group : poly_chart[f];
    m.faces.push_back(std::move(face));
  }

  // edges and points: one per distinct point pair or point; zero-length edges become nothing
  {
    std::map<std::pair<uint32_t, uint32_t>, bool> seen;
    for (size_t e = 0; e < in.edgeCount(); ++e) {
      const uint32_t a = canon[in.edges[2 * e]], b = canon[in.edges[2 * e + 1]];
      const uint32_t pa = m.vertex_point[a], pb = m.vertex_point[b];
      if (pa == pb) continue;
      if (!seen.emplace(std::minmax(pa, pb), true).second) continue;
      m.edge_verts.insert(m.edge_verts.end(), {a, b});
      m.edge_thickness.push_back(in.edgeThickness(e));
    }
    std::vector<uint8_t> has_point(m.points.size(), 0);
    for (uint32_t v : in.points) {
      const uint32_t c = canon[v];
      if (has_point[m.vertex_point[c]]) continue;
      has_point[m.vertex_point[c]] = 1;
      m.point_verts.push_back(c);
    }
  }

  if (params.remove_sub_polygons) stats.sub_polygons = removeSubPolygons(m);
  stats.normalised_polygons = 0;
  for (const Face& f : m.faces) stats.normalised_polygons += f.alive ? 1 : 0;
}

size_t removeSubPolygons(Model& m) {
  const size_t fc = m.faces.size();
  if (fc < 2) return 0;
  struct Info {
    glm::dvec3 normal;
    double area;
    glm::dvec3 lo, hi;
  };
  std::vector<Info> info(fc);
  double mean_extent = 0.0;
  for (size_t f = 0; f < fc; ++f) {
    const Face& face = m.faces[f];
    glm::dvec3 n = newellNormal(m, face.pts);
    const double len = glm::length(n);
    info[f].normal = len > 0.0 ? n / len : glm::dvec3(0.0);
    info[f].area = 0.5 * len;
    info[f].lo = info[f].hi = glm::dvec3(m.points[face.pts[0]]);
    for (uint32_t p : face.pts) {
      info[f].lo = glm::min(info[f].lo, glm::dvec3(m.points[p]));
      info[f].hi = glm::max(info[f].hi, glm::dvec3(m.points[p]));
    }
    const glm::dvec3 ext = info[f].hi - info[f].lo;
    mean_extent += std::max({ext.x, ext.y, ext.z});
  }
  mean_extent /= double(fc);
  const double cell = std::max(mean_extent * 2.0, 1e-9 * std::max(double(m.diagonal), 1e-30));
  const double tol = std::max(1e-6 * double(m.diagonal), 1e-12);
  const double cos_tol = std::cos(1.0 * M_PI / 180.0);

  // hash grid over face boxes; faces covering very many cells are checked against everything
  std::unordered_map<CellKey, std::vector<uint32_t>, CellHash> grid;
  std::vector<uint32_t> big;
  auto cellOf = [&](const glm::dvec3& p) {
    return CellKey{int64_t(std::floor(p.x / cell)), int64_t(std::floor(p.y / cell)), int64_t(std::floor(p.z / cell))};
  };
  for (size_t f = 0; f < fc; ++f) {
    const CellKey a = cellOf(info[f].lo - tol), b = cellOf(info[f].hi + tol);
    const double count = double(b.x - a.x + 1) * double(b.y - a.y + 1) * double(b.z - a.z + 1);
    if (count > 64.0) { big.push_back(uint32_t(f)); continue; }
    for (int64_t z = a.z; z <= b.z; ++z)
      for (int64_t y = a.y; y <= b.y; ++y)
        for (int64_t x = a.x; x <= b.x; ++x) grid[{x, y, z}].push_back(uint32_t(f));
  }

  auto insideQ = [&](size_t q, const glm::dvec3& p, double& boundary_dist) {
    // point in polygon q in q's plane: crossing test in 2D plus distance to the outline
    const Face& Q = m.faces[q];
    const glm::dvec3 n = info[q].normal;
    const glm::dvec3 t = glm::normalize(std::fabs(n.x) > 0.9 ? glm::cross(n, glm::dvec3(0, 1, 0)) : glm::cross(n, glm::dvec3(1, 0, 0)));
    const glm::dvec3 s = glm::cross(n, t);
    const double px = glm::dot(p, t), py = glm::dot(p, s);
    bool in = false;
    boundary_dist = 1e300;
    const size_t k = Q.pts.size();
    for (size_t i = 0, j = k - 1; i < k; j = i++) {
      const glm::dvec3 a3(m.points[Q.pts[i]]), b3(m.points[Q.pts[j]]);
      const double ax = glm::dot(a3, t), ay = glm::dot(a3, s), bx = glm::dot(b3, t), by = glm::dot(b3, s);
      if ((ay > py) != (by > py) && px < (bx - ax) * (py - ay) / (by - ay) + ax) in = !in;
      const double ex = bx - ax, ey = by - ay, l2 = ex * ex + ey * ey;
      double r = l2 > 0.0 ? ((px - ax) * ex + (py - ay) * ey) / l2 : 0.0;
      r = std::clamp(r, 0.0, 1.0);
      boundary_dist = std::min(boundary_dist, std::hypot(ax + r * ex - px, ay + r * ey - py));
    }
    return in;
  };

  size_t removed = 0;
  std::vector<uint32_t> candidates;
  for (size_t p = 0; p < fc; ++p) {
    const Face& P = m.faces[p];
    if (info[p].area <= 0.0) continue;
    candidates.clear();
    auto it = grid.find(cellOf(glm::dvec3(m.points[P.pts[0]])));
    if (it != grid.end()) candidates = it->second;
    candidates.insert(candidates.end(), big.begin(), big.end());
    glm::dvec3 centroid(0.0);
    for (uint32_t v : P.pts) centroid += glm::dvec3(m.points[v]);
    centroid /= double(P.pts.size());
    for (uint32_t q : candidates) {
      if (q == p || !m.faces[q].alive) continue;
      if (info[q].area < info[p].area || (info[q].area == info[p].area && q > p)) continue;
      if (glm::dot(info[p].normal, info[q].normal) < cos_tol) continue;
      bool contained = true;
      for (int a = 0; a < 3 && contained; ++a)
        if (info[p].lo[a] < info[q].lo[a] - tol || info[p].hi[a] > info[q].hi[a] + tol) contained = false;
      if (!contained) continue;
      const glm::dvec3 q0(m.points[m.faces[q].pts[0]]);
      for (uint32_t v : P.pts) {
        const glm::dvec3 pv(m.points[v]);
        double d;
        if (std::fabs(glm::dot(pv - q0, info[q].normal)) > tol || (!insideQ(q, pv, d) && d > tol)) {
          contained = false;
          break;
        }
      }
      double d;
      if (!contained || !insideQ(q, centroid, d) || d <= tol) continue;
      m.faces[p].alive = false;
      ++removed;
      break;
    }
  }
  return removed;
}

}  // namespace scenelod::scrooge
