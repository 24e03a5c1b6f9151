// SCROOGE driver, optimisation and chain, Reddy 1996 §4 (steps 1-4) and §8: normalise, degrade and
// rebuild per sub-volume, then rebuild a Mesh from the live polygons keeping only used vertices
// (step 4), with the §7.1 output options (convex pieces, triangles).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <unordered_map>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include "scrooge_model.h"

namespace scenelod {

namespace scrooge {

namespace {

struct OutKey {
  uint32_t point, vert;
  uint32_t color[3];  // bits of a blended colour, all ones when the vertex keeps its own
  bool operator==(const OutKey& o) const {
    return point == o.point && vert == o.vert && std::memcmp(color, o.color, sizeof(color)) == 0;
  }
};
struct OutKeyHash {
  size_t operator()(const OutKey& k) const {
    return (size_t(k.point) * 2654435761u) ^ (size_t(k.vert) * 40503u) ^ k.color[0] ^ (size_t(k.color[1]) << 7) ^
           (size_t(k.color[2]) << 13);
  }
};

bool degenerateTriangle(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
  const double cross = glm::length(glm::cross(glm::dvec3(b - a), glm::dvec3(c - a)));
  const double longest = std::max({glm::length(glm::dvec3(b - a)), glm::length(glm::dvec3(c - b)),
                                    glm::length(glm::dvec3(a - c))});
  // also in float, the precision a renderer (and the output's user) sees
  return !(cross > 1e-12 * longest * longest) || !(longest > 0.0) || !(glm::length(glm::cross(b - a, c - a)) > 0.0f);
}

double minAngle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
  auto angle = [](const glm::dvec3& p, const glm::dvec3& q, const glm::dvec3& r) {
    const glm::dvec3 u = q - p, v = r - p;
    const double lu = glm::length(u), lv = glm::length(v);
    return lu > 0.0 && lv > 0.0 ? std::acos(std::clamp(glm::dot(u, v) / (lu * lv), -1.0, 1.0)) : 0.0;
  };
  return std::min({angle(a, b, c), angle(b, c, a), angle(c, a, b)});
}

// Triangulates out's faces into out.triangles. A face convex in its Newell plane is clipped ear by
// ear, always taking the ear with the largest smallest angle (a fan over a many-cornered curved
// polygon makes slivers whose normals stand across the surface); other faces use the general ear
// clipping of mesh.cpp, their triangles after the others'. With `face_group` (one per face), every
// triangle gets its face's group in out.triangle_groups. Cost O(k^2) per convex face of k corners.
void triangulatePolygons(Mesh& out, const std::vector<uint32_t>& face_group) {
  std::vector<uint32_t> concave_tris, concave_groups;
  out.triangles.clear();
  out.triangle_groups.clear();
  auto emit = [&](std::vector<uint32_t>& tris, std::vector<uint32_t>& groups, size_t f, const uint32_t* corners,
                  size_t count) {
    tris.insert(tris.end(), corners, corners + count);
    if (!face_group.empty()) groups.insert(groups.end(), count / 3, face_group[f]);
  };
  std::vector<uint32_t> ring;
  std::vector<glm::dvec2> q;
  for (size_t f = 0; f < out.faceCount(); ++f) {
    const size_t b = out.face_offsets[f], k = out.face_offsets[f + 1] - b;
    if (k < 3) continue;
    ring.assign(out.face_corners.begin() + std::ptrdiff_t(b), out.face_corners.begin() + std::ptrdiff_t(b + k));
    glm::dvec3 n(0.0);
    for (size_t i = 0; i < k; ++i) n += glm::cross(glm::dvec3(out.positions[ring[i]]), glm::dvec3(out.positions[ring[(i + 1) % k]]));
    bool convex = glm::length(n) > 0.0;
    if (convex) {
      n = glm::normalize(n);
      const glm::dvec3 t = glm::normalize(std::fabs(n.x) > 0.9 ? glm::cross(n, glm::dvec3(0, 1, 0)) : glm::cross(n, glm::dvec3(1, 0, 0)));
      const glm::dvec3 s = glm::cross(n, t);
      q.resize(k);
      double extent = 0.0;
      for (size_t i = 0; i < k; ++i) {
        const glm::dvec3 p(out.positions[ring[i]]);
        q[i] = glm::dvec2(glm::dot(p, t), glm::dot(p, s));
        extent = std::max(extent, glm::length(q[i] - q[0]));
      }
      for (size_t i = 0; i < k && convex; ++i) {
        const glm::dvec2 a = q[(i + k - 1) % k], c = q[i], d = q[(i + 1) % k];
        if ((c.x - a.x) * (d.y - a.y) - (c.y - a.y) * (d.x - a.x) < -1e-9 * extent * extent) convex = false;
      }
    }
    if (!convex) {  // the general ear clipping, on this face alone
      Mesh one;
      for (uint32_t v : ring) one.positions.push_back(out.positions[v]);
      one.face_offsets = {0, uint32_t(k)};
      for (uint32_t i = 0; i < k; ++i) one.face_corners.push_back(i);
      triangulateFaces(one);
      for (uint32_t& v : one.triangles) v = ring[v];
      emit(concave_tris, concave_groups, f, one.triangles.data(), one.triangles.size());
      continue;
    }
    while (ring.size() > 3) {
      size_t best = 0;
      double best_angle = -1.0;
      for (size_t i = 0; i < ring.size(); ++i) {
        const size_t m = ring.size();
        const double a = minAngle(glm::dvec3(out.positions[ring[(i + m - 1) % m]]), glm::dvec3(out.positions[ring[i]]),
                                  glm::dvec3(out.positions[ring[(i + 1) % m]]));
        if (a > best_angle) { best_angle = a; best = i; }
      }
      const size_t m = ring.size();
      const uint32_t ear[3] = {ring[(best + m - 1) % m], ring[best], ring[(best + 1) % m]};
      emit(out.triangles, out.triangle_groups, f, ear, 3);
      ring.erase(ring.begin() + std::ptrdiff_t(best));
    }
    emit(out.triangles, out.triangle_groups, f, ring.data(), 3);
  }
  out.triangles.insert(out.triangles.end(), concave_tris.begin(), concave_tris.end());
  out.triangle_groups.insert(out.triangle_groups.end(), concave_groups.begin(), concave_groups.end());
}

}  // namespace

void assembleMesh(const Mesh& in, const Model& m, const ScroogeParams& params, Mesh& out, ScroogeStats& stats) {
  out = Mesh{};
  const size_t n = in.vertexCount();
  const bool has_colors = in.colors.size() == n && n > 0;
  const bool has_uvs = in.uvs.size() == n && n > 0;
  const bool has_normals = in.normals.size() == n && n > 0;

  std::vector<Face> faces;
  for (const Face& f : m.faces) {
    if (!f.alive) continue;
    if (params.convex_polygons && f.rebuilt) splitConcave(m, f, faces);
    else faces.push_back(f);
  }

  std::unordered_map<OutKey, uint32_t, OutKeyHash> index;
  std::vector<uint32_t> out_vert;  // input vertex of each output vertex
  std::vector<uint32_t> out_point;
  auto vertexFor = [&](uint32_t point, uint32_t vert, const glm::vec3* blended) {
    OutKey k{point, vert, {~0u, ~0u, ~0u}};
    if (blended) std::memcpy(k.color, blended, sizeof(k.color));
    auto it = index.emplace(k, uint32_t(out.positions.size()));
    if (it.second) {
      out.positions.push_back(m.points[point]);
      if (has_colors) out.colors.push_back(blended ? *blended : in.colors[vert]);
      if (has_uvs) out.uvs.push_back(m.point_uv_moved[point] ? m.point_uv[point] : in.uvs[vert]);
      out_vert.push_back(vert);
      out_point.push_back(point);
    }
    return it.first->second;
  };

  std::vector<uint32_t> face_group;  // carried when the input has groups
  out.face_offsets.push_back(0);
  for (const Face& f : faces) {
    if (!in.triangle_groups.empty()) face_group.push_back(f.group);
    for (size_t c = 0; c < f.pts.size(); ++c) {
      // a merged polygon's corners take its blended colour where it differs from their own
      const bool blend = f.blended && has_colors && glm::length(in.colors[f.verts[c]] - f.color) > 1e-6f;
      out.face_corners.push_back(vertexFor(f.pts[c], f.verts[c], blend ? &f.color : nullptr));
    }
    out.face_offsets.push_back(uint32_t(out.face_corners.size()));
  }
  for (size_t e = 0; e + 1 < m.edge_verts.size(); e += 2) {
    out.edges.push_back(vertexFor(m.vertex_point[m.edge_verts[e]], m.edge_verts[e], nullptr));
    out.edges.push_back(vertexFor(m.vertex_point[m.edge_verts[e + 1]], m.edge_verts[e + 1], nullptr));
  }
  if (!out.edges.empty()) {
    out.edge_thickness = m.edge_thickness;
    bool any = false;
    for (float t : out.edge_thickness) any = any || t > 0.0f;
    if (!any) out.edge_thickness.clear();
  }
  for (uint32_t v : m.point_verts) out.points.push_back(vertexFor(m.vertex_point[v], v, nullptr));
  if (out.faceCount() == 0) {
    out.face_offsets.clear();
    out.face_corners.clear();
  }

  // triangles of the polygons, without the zero-area ones a fan over co-linear corners can make
  triangulatePolygons(out, face_group);
  std::vector<uint32_t> tris, groups;
  for (size_t t = 0; t + 2 < out.triangles.size(); t += 3) {
    const uint32_t a = out.triangles[t], b = out.triangles[t + 1], c = out.triangles[t + 2];
    if (a == b || b == c || a == c || degenerateTriangle(out.positions[a], out.positions[b], out.positions[c])) continue;
    tris.insert(tris.end(), {a, b, c});
    if (!out.triangle_groups.empty()) groups.push_back(out.triangle_groups[t / 3]);
  }
  out.triangles = std::move(tris);
  out.triangle_groups = std::move(groups);
  stats.output_polygons = out.faceCount();
  if (params.triangulate_faces && out.faceCount() > 0) {
    out.face_corners = out.triangles;
    out.face_offsets.resize(out.triangleCount() + 1);
    for (size_t t = 0; t <= out.triangleCount(); ++t) out.face_offsets[t] = uint32_t(3 * t);
    stats.output_polygons = out.triangleCount();
  }
  stats.output_triangles = out.triangleCount();

  // normals: kept where nothing moved, else from the new faces
  if (has_normals) {
    Mesh tmp;
    tmp.positions = out.positions;
    tmp.triangles = out.triangles;
    computeVertexNormals(tmp);
    std::vector<uint8_t> in_triangle(out.positions.size(), 0);
    for (uint32_t v : out.triangles) in_triangle[v] = 1;
    out.normals.resize(out.positions.size());
    for (size_t v = 0; v < out.positions.size(); ++v) {
      const bool moved = out.positions[v] != in.positions[out_vert[v]];
      out.normals[v] = (moved && in_triangle[v]) ? tmp.normals[v] : in.normals[out_vert[v]];
    }
  }

  stats.source_vertex = out_vert;
  stats.vertex_origin.resize(out.positions.size());
  for (size_t v = 0; v < out.positions.size(); ++v) stats.vertex_origin[v] = m.point_source[out_point[v]];
  double worst = 0.0;
  for (size_t p = 0; p < m.points.size(); ++p)
    worst = std::max(worst, glm::length(glm::dvec3(m.points[p]) - glm::dvec3(in.positions[m.point_source[p]])));
  stats.max_displacement = float(worst);
  if (double(stats.max_displacement) < worst)  // round up: the value is a bound
    stats.max_displacement = std::nextafter(stats.max_displacement, std::numeric_limits<float>::infinity());
}

}  // namespace scrooge

namespace {

bool finite(float x) { return std::isfinite(x); }

Error checkParams(const ScroogeParams& p, bool need_size, const std::string& what) {
  if (need_size) {
    const glm::vec3 s = p.subvolume_size;
    if (!finite(s.x) || !finite(s.y) || !finite(s.z) || !(s.x > 0.0f) || !(s.y > 0.0f) || !(s.z > 0.0f))
      return {Status::kInvalidArgument, what + ": SCROOGE sub-volume size (" + std::to_string(s.x) + ", " +
                                            std::to_string(s.y) + ", " + std::to_string(s.z) +
                                            ") must be finite and > 0 on every axis"};
  }
  if (!finite(p.theta_min_deg) || !finite(p.theta_max_deg) || p.theta_min_deg < 0.0f ||
      !(p.theta_max_deg > p.theta_min_deg) || p.theta_max_deg > 180.0f)
    return {Status::kInvalidArgument, what + ": SCROOGE angles need 0 <= theta_min < theta_max <= 180 degrees, got " +
                                          std::to_string(p.theta_min_deg) + " and " + std::to_string(p.theta_max_deg)};
  if (!finite(p.coplanar_deg) || p.coplanar_deg < 0.0f || p.coplanar_deg > 90.0f)
    return {Status::kInvalidArgument, what + ": SCROOGE coplanar tolerance " + std::to_string(p.coplanar_deg) +
                                          " degrees is outside [0, 90]"};
  if (!finite(p.weld_epsilon_rel) || p.weld_epsilon_rel < 0.0f || p.weld_epsilon_rel >= 1.0f)
    return {Status::kInvalidArgument, what + ": SCROOGE weld epsilon " + std::to_string(p.weld_epsilon_rel) +
                                          " (relative to the bbox diagonal) is outside [0, 1)"};
  return {};
}

Sphere boundingSphere(const Mesh& m) {
  Sphere s;
  if (m.positions.empty()) return s;
  s.center = computeBounds(m).center();
  float r2 = 0.0f;
  for (const glm::vec3& p : m.positions) {
    const glm::vec3 d = p - s.center;
    r2 = std::max(r2, glm::dot(d, d));
  }
  s.radius = std::sqrt(r2) * (1.0f + 1e-6f);
  return s;
}

}  // namespace

namespace {

// normalisation (§2), then with `degrade` the subvolumes' reduction (§3), then the output mesh
Error runScrooge(const Mesh& in, const ScroogeParams& params, bool degrade, Mesh& out, ScroogeStats* stats,
                 const char* what) {
  const std::string name = what ? what : "mesh";
  if (Error e = checkParams(params, degrade, name); !e.ok()) return e;
  if (Error e = validateMesh(in, name); !e.ok()) return e;
  if (degrade) {
    // sub-volume indices are int64: a coordinate more than 2^30 sub-volumes from the origin (a huge
    // coordinate over a tiny sub-volume) has none
    const Aabb b = computeBounds(in);
    const glm::vec3 far = glm::max(glm::abs(b.min), glm::abs(b.max));
    for (int a = 0; a < 3; ++a)
      if (double(far[a]) / double(params.subvolume_size[a]) > 1073741824.0)
        return {Status::kInvalidArgument, name + ": SCROOGE sub-volume size " + std::to_string(params.subvolume_size[a]) +
                                              " is too small for coordinates up to " + std::to_string(far[a]) +
                                              " (more than 2^30 sub-volumes along an axis)"};
  }
  ScroogeStats local;
  ScroogeStats& st = stats ? *stats : local;
  st = ScroogeStats{};
  out = Mesh{};
  if (in.vertexCount() == 0) return {};
  scrooge::Model model;
  scrooge::normaliseModel(in, params, model, st);
  ScroogeParams p = params;
  if (degrade)
    scrooge::degradeInSubvolumes(model, params, st);
  else
    p.convex_polygons = false;  // nothing was rebuilt
  scrooge::assembleMesh(in, model, p, out, st);
  return {};
}

}  // namespace

Error scroogeMesh(const Mesh& in, const ScroogeParams& params, Mesh& out, ScroogeStats* stats, const char* what) {
  return runScrooge(in, params, true, out, stats, what);
}

Error scroogeNormalise(const Mesh& in, const ScroogeParams& params, Mesh& out, ScroogeStats* stats, const char* what) {
  return runScrooge(in, params, false, out, stats, what);
}

glm::vec3 scroogeSubvolumeForCellRel(const Aabb& bounds, float cell_rel) {
  const float d = bounds.diagonal();
  if (!(cell_rel > 0.0f) || !(d > 0.0f) || !std::isfinite(cell_rel)) return glm::vec3(0.0f);
  return glm::vec3(cell_rel * d / std::sqrt(3.0f));
}

glm::vec3 scroogeSubvolumeForDivisions(const Aabb& bounds, int divisions) {
  if (divisions <= 0) return glm::vec3(0.0f);
  glm::vec3 s = bounds.extent() / float(divisions);
  const float largest = std::max({s.x, s.y, s.z});
  if (!(largest > 0.0f)) return glm::vec3(0.0f);
  for (int a = 0; a < 3; ++a)
    if (!(s[a] > 0.0f)) s[a] = largest;
  return s;
}

Error buildScroogeChain(const Mesh& original, const ChainParams& params, const ScroogeParams& scrooge_params,
                        LodChain& out) {
  out = LodChain{};
  const std::string what = "SCROOGE chain";
  if (Error e = checkParams(scrooge_params, false, what); !e.ok()) return e;
  if (Error e = validateMesh(original, what); !e.ok()) return e;
  if (!std::isfinite(params.first_cell_width) || params.first_cell_width < 0.0f)
    return {Status::kInvalidArgument, what + ": first sub-volume width " + std::to_string(params.first_cell_width) +
                                          " must be finite and >= 0 (0 = automatic)"};
  if (params.level_count > 1 && (!std::isfinite(params.growth) || !(params.growth > 1.0f)))
    return {Status::kInvalidArgument, what + ": growth " + std::to_string(params.growth) +
                                          " must be > 1 for more than one level"};
  LodLevel base;
  base.mesh = original;
  base.bounds = boundingSphere(original);
  out.levels.push_back(std::move(base));
  if (original.vertexCount() == 0 || params.level_count == 0) return {};

  const glm::vec3 ext = computeBounds(original).extent();
  float w1 = params.first_cell_width;
  if (w1 == 0.0f) {
    const float longest = std::max({ext.x, ext.y, ext.z});
    if (!(longest > 0.0f)) return {};  // a single point: nothing to reduce
    w1 = longest / std::pow(params.growth > 1.0f ? params.growth : 2.0f, float(params.level_count - 1));
  }
  const size_t count = params.level_count;
  std::vector<LodLevel> levels(count);
  std::vector<Error> errors(count);
  tbb::parallel_for(size_t(0), count, [&](size_t k) {
    const float w = w1 * std::pow(params.growth, float(k));
    ScroogeParams p = scrooge_params;
    p.subvolume_size = glm::vec3(w);
    ScroogeStats st;
    errors[k] = scroogeMesh(original, p, levels[k].mesh, &st, what.c_str());
    levels[k].cell_width = w;
    levels[k].max_error = st.max_displacement;
    levels[k].method = LodMethod::kScrooge;
    levels[k].bounds = boundingSphere(levels[k].mesh);
    levels[k].source_vertex = std::move(st.source_vertex);
  });
  size_t done = 0;
  for (size_t k = 0; k < count; ++k) {
    if (!errors[k].ok()) return errors[k];
    params.progress(double(++done) / double(count), "scrooge");
    out.levels.push_back(std::move(levels[k]));
  }
  return {};
}

Error buildScroogeChain(const Mesh& original, const ChainParams& params, LodChain& out) {
  return buildScroogeChain(original, params, ScroogeParams{}, out);
}

}  // namespace scenelod
