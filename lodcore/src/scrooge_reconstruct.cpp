// SCROOGE surface reconstruction, Reddy 1996 §7: merge neighbouring coplanar polygons (within a
// tolerance of the group's first polygon), blend their colours by area (§7.3), remove co-linear
// vertices (§7.1.1) and split concave polygons into convex ones (§7.1.2). The convex split ear-clips
// and then drops diagonals whose removal keeps both end corners convex (Hertel & Mehlhorn 1983).
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <map>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include "scrooge_model.h"

namespace scenelod::scrooge {

namespace {

double pointScale(const Model& m, const std::vector<uint32_t>& pts) {
  double s = 0.0;
  for (uint32_t p : pts) s = std::max({s, double(std::fabs(m.points[p].x)), double(std::fabs(m.points[p].y)),
                                        double(std::fabs(m.points[p].z))});
  return s;
}

// drops corners lying on the segment between their neighbours; returns true when any went
bool removeColinear(const Model& m, Face& f, double l_max) {
  const double tol = std::max(1e-6 * l_max, 16.0 * FLT_EPSILON * pointScale(m, f.pts));
  bool any = false;
  bool changed = true;
  while (changed && f.pts.size() > 3) {
    changed = false;
    for (size_t i = 0; i < f.pts.size() && f.pts.size() > 3; ++i) {
      const size_t k = f.pts.size();
      const glm::dvec3 a(m.points[f.pts[(i + k - 1) % k]]), b(m.points[f.pts[i]]), c(m.points[f.pts[(i + 1) % k]]);
      const glm::dvec3 e = c - a;
      const double l2 = glm::dot(e, e);
      if (!(l2 > 0.0)) continue;
      const double r = glm::dot(b - a, e) / l2;
      if (r < 0.0 || r > 1.0) continue;
      if (glm::length(a + r * e - b) > tol) continue;
      f.pts.erase(f.pts.begin() + std::ptrdiff_t(i));
      f.verts.erase(f.verts.begin() + std::ptrdiff_t(i));
      changed = any = true;
      --i;
    }
  }
  return any;
}

struct Plane2 {
  glm::dvec3 t, s;
  glm::dvec2 project(const glm::dvec3& p) const { return {glm::dot(p, t), glm::dot(p, s)}; }
};

Plane2 planeOf(const glm::dvec3& normal) {
  const glm::dvec3 n = glm::normalize(normal);
  const glm::dvec3 t =
      glm::normalize(std::fabs(n.x) > 0.9 ? glm::cross(n, glm::dvec3(0, 1, 0)) : glm::cross(n, glm::dvec3(1, 0, 0)));
  return {t, glm::cross(n, t)};
}

double cross2(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

}  // namespace

size_t reconstructFaces(Model& m, const std::vector<uint32_t>& faces, const ScroogeParams& params,
                        std::vector<Face>& added) {
  // polygons flattened by degradation stay until the end (dropping one now would leave its middle
  // vertex as a T-junction that a later pass could move off the edge, opening a crack); they join any
  // neighbouring group but never start one
  std::vector<uint32_t> live;
  for (uint32_t f : faces) {
    if (!m.faces[f].alive) continue;
    m.faces[f].inside = true;
    live.push_back(f);
  }
  const size_t n = live.size();
  std::vector<glm::dvec3> normal(n);
  std::vector<double> area(n);
  std::vector<uint8_t> flat(n);
  for (size_t i = 0; i < n; ++i) {
    const glm::dvec3 nn = newellNormal(m, m.faces[live[i]].pts);
    area[i] = 0.5 * glm::length(nn);
    flat[i] = isDegenerate(m, m.faces[live[i]].pts) ? 1 : 0;
    normal[i] = flat[i] ? glm::dvec3(0.0) : glm::normalize(nn);
  }
  // undirected edge -> (local face, forward?) for adjacency
  struct EdgeUse {
    uint32_t a, b, face;
    bool forward;
  };
  std::vector<EdgeUse> uses;
  for (size_t i = 0; i < n; ++i) {
    const std::vector<uint32_t>& pts = m.faces[live[i]].pts;
    for (size_t c = 0; c < pts.size(); ++c) {
      const uint32_t a = pts[c], b = pts[(c + 1) % pts.size()];
      uses.push_back({std::min(a, b), std::max(a, b), uint32_t(i), a < b});
    }
  }
  std::sort(uses.begin(), uses.end(), [](const EdgeUse& x, const EdgeUse& y) {
    return x.a != y.a ? x.a < y.a : (x.b != y.b ? x.b < y.b : x.face < y.face);
  });
  std::vector<std::vector<uint32_t>> neighbours(n);
  for (size_t i = 0; i < uses.size();) {
    size_t j = i;
    while (j < uses.size() && uses[j].a == uses[i].a && uses[j].b == uses[i].b) ++j;
    // a manifold edge used once in each direction joins two polygons
    if (j - i == 2 && uses[i].forward != uses[i + 1].forward && uses[i].face != uses[i + 1].face) {
      neighbours[uses[i].face].push_back(uses[i + 1].face);
      neighbours[uses[i + 1].face].push_back(uses[i].face);
    }
    i = j;
  }

  const double cos_tol = std::cos(double(params.coplanar_deg) * M_PI / 180.0);
  std::vector<uint8_t> grouped(n, 0);
  std::vector<uint32_t> group, queue;
  size_t merged = 0;
  for (size_t seed = 0; seed < n; ++seed) {
    if (grouped[seed] || flat[seed]) continue;
    group.assign(1, uint32_t(seed));
    grouped[seed] = 1;
    // a group stays inside the seed's uv chart (and so its triangle group): merged corners keep
    // their own uvs, which only fit together within one chart
    const uint32_t chart = m.faces[live[seed]].chart;
    for (size_t q = 0; q < group.size(); ++q)
      for (uint32_t g : neighbours[group[q]])
        if (!grouped[g] && m.faces[live[g]].chart == chart &&
            (flat[g] || glm::dot(normal[g], normal[seed]) >= cos_tol)) {
          grouped[g] = 1;
          group.push_back(g);
        }
    if (group.size() < 2) continue;

    // outline: directed edges whose reverse is not in the group
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> directed;  // edge -> vertex at its start
    bool ok = true;
    for (uint32_t g : group) {
      const Face& f = m.faces[live[g]];
      for (size_t c = 0; c < f.pts.size() && ok; ++c)
        if (!directed.emplace(std::make_pair(f.pts[c], f.pts[(c + 1) % f.pts.size()]), f.verts[c]).second) ok = false;
    }
    std::map<uint32_t, std::pair<uint32_t, uint32_t>> next;  // start -> (end, vertex)
    for (const auto& [e, v] : directed) {
      if (directed.count({e.second, e.first})) continue;
      if (!next.emplace(e.first, std::make_pair(e.second, v)).second) ok = false;  // pinched outline
    }
    if (!ok || next.empty()) continue;
    std::vector<Face> loops;
    std::map<uint32_t, uint8_t> used;
    for (const auto& [start, unused] : next) {
      (void)unused;
      if (used.count(start)) continue;
      Face loop;
      uint32_t p = start;
      while (!used.count(p)) {
        used[p] = 1;
        auto it = next.find(p);
        if (it == next.end()) { ok = false; break; }
        loop.pts.push_back(p);
        loop.verts.push_back(it->second.second);
        p = it->second.first;
      }
      if (!ok || p != start) { ok = false; break; }
      loops.push_back(std::move(loop));
    }
    if (!ok || loops.empty()) continue;
    if (loops.size() > 1 && !params.fill_holes) continue;
    size_t outer = 0;
    double outer_area = -1e300;
    for (size_t l = 0; l < loops.size(); ++l) {
      const double a = glm::dot(newellNormal(m, loops[l].pts), normal[seed]);
      if (a > outer_area) { outer_area = a; outer = l; }
    }
    if (!(outer_area > 0.0) || isDegenerate(m, loops[outer].pts)) continue;

    // §7.3: the merged polygon's colour is the area-weighted mean of its parts
    Face merged_face = std::move(loops[outer]);
    glm::dvec3 color(0.0);
    double total = 0.0;
    for (uint32_t g : group) {
      color += area[g] * glm::dvec3(m.faces[live[g]].color);
      total += area[g];
      m.faces[live[g]].alive = false;
    }
    merged_face.color = total > 0.0 ? glm::vec3(color / total) : m.faces[live[seed]].color;
    merged_face.blended = true;
    merged_face.rebuilt = true;
    merged_face.inside = true;
    merged_face.chart = chart;
    merged_face.group = m.faces[live[seed]].group;
    added.push_back(std::move(merged_face));
    ++merged;
  }

  return merged;
}

void finishFaces(Model& m, const ScroogeParams& params, double l_max) {
  for (Face& f : m.faces) {
    if (!f.alive) continue;
    if (isDegenerate(m, f.pts)) {  // flattened by degradation: no area, nothing moves any more
      f.alive = false;
      continue;
    }
    if (params.remove_colinear && f.inside && removeColinear(m, f, l_max)) f.rebuilt = true;
  }
}

void splitConcave(const Model& m, const Face& face, std::vector<Face>& pieces) {
  const size_t k = face.pts.size();
  const glm::dvec3 nn = newellNormal(m, face.pts);
  if (k <= 3 || !(glm::length(nn) > 0.0)) {
    pieces.push_back(face);
    return;
  }
  const Plane2 plane = planeOf(nn);
  std::vector<glm::dvec2> q(k);
  for (size_t i = 0; i < k; ++i) q[i] = plane.project(glm::dvec3(m.points[face.pts[i]]));
  double extent = 0.0;
  for (size_t i = 0; i < k; ++i) extent = std::max(extent, glm::length(q[i] - q[0]));
  const double tol = 1e-9 * extent * extent;
  bool convex = true;
  for (size_t i = 0; i < k && convex; ++i)
    if (cross2(q[(i + k - 1) % k], q[i], q[(i + 1) % k]) < -tol) convex = false;
  if (convex) {
    pieces.push_back(face);
    return;
  }
  // ear clipping into triangles of local corner indices
  std::vector<std::vector<uint32_t>> parts;
  std::vector<uint32_t> ring(k);
  for (size_t i = 0; i < k; ++i) ring[i] = uint32_t(i);
  while (ring.size() > 3) {
    bool clipped = false;
    for (size_t i = 0; i < ring.size(); ++i) {
      const uint32_t a = ring[(i + ring.size() - 1) % ring.size()], b = ring[i], c = ring[(i + 1) % ring.size()];
      if (cross2(q[a], q[b], q[c]) <= tol) continue;
      bool inside = false;
      for (uint32_t j : ring) {
        if (j == a || j == b || j == c) continue;
        if (cross2(q[a], q[b], q[j]) >= 0.0 && cross2(q[b], q[c], q[j]) >= 0.0 && cross2(q[c], q[a], q[j]) >= 0.0) {
          inside = true;
          break;
        }
      }
      if (inside) continue;
      parts.push_back({a, b, c});
      ring.erase(ring.begin() + std::ptrdiff_t(i));
      clipped = true;
      break;
    }
    if (!clipped) break;  // self-intersecting outline: the rest goes as one fan
  }
  for (size_t i = 1; i + 1 < ring.size(); ++i) parts.push_back({ring[0], ring[i], ring[i + 1]});

  // Hertel-Mehlhorn: remove a diagonal when both its end corners stay convex in the union
  std::map<std::pair<uint32_t, uint32_t>, uint32_t> edge_part;  // directed edge -> piece holding it
  for (size_t i = 0; i < parts.size(); ++i)
    for (size_t x = 0; x < parts[i].size(); ++x)
      edge_part[{parts[i][x], parts[i][(x + 1) % parts[i].size()]}] = uint32_t(i);
  std::vector<std::pair<uint32_t, uint32_t>> diagonals;
  for (const auto& [e, part] : edge_part)
    if (e.first < e.second && edge_part.count({e.second, e.first})) diagonals.push_back(e);
  std::vector<uint8_t> part_alive(parts.size(), 1);
  for (const auto& [a, b] : diagonals) {
    const uint32_t i = edge_part[{a, b}], j = edge_part[{b, a}];
    if (i == j) continue;
    const std::vector<uint32_t>& A = parts[i];
    const std::vector<uint32_t>& B = parts[j];
    size_t x = 0, y = 0;
    while (x < A.size() && !(A[x] == a && A[(x + 1) % A.size()] == b)) ++x;
    while (y < B.size() && !(B[y] == b && B[(y + 1) % B.size()] == a)) ++y;
    if (x == A.size() || y == B.size()) continue;
    // union: A from b round to a, then B from after a round to before b
    std::vector<uint32_t> u;
    for (size_t s = 0; s < A.size(); ++s) u.push_back(A[(x + 1 + s) % A.size()]);
    for (size_t s = 2; s < B.size(); ++s) u.push_back(B[(y + s) % B.size()]);
    bool ok = true;
    for (size_t s = 0; s < u.size() && ok; ++s)
      if (u[s] == a || u[s] == b)
        if (cross2(q[u[(s + u.size() - 1) % u.size()]], q[u[s]], q[u[(s + 1) % u.size()]]) < -tol) ok = false;
    if (!ok) continue;
    edge_part.erase({a, b});
    edge_part.erase({b, a});
    for (size_t s = 0; s < u.size(); ++s) edge_part[{u[s], u[(s + 1) % u.size()]}] = i;
    parts[i] = std::move(u);
    part_alive[j] = 0;
  }
  for (size_t i = 0; i < parts.size(); ++i) {
    if (!part_alive[i]) continue;
    const std::vector<uint32_t>& p = parts[i];
    Face f = face;
    f.pts.clear();
    f.verts.clear();
    for (uint32_t c : p) {
      f.pts.push_back(face.pts[c]);
      f.verts.push_back(face.verts[c]);
    }
    pieces.push_back(std::move(f));
  }
}

}  // namespace scenelod::scrooge
