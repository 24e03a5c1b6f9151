// Geomorph targets between two levels of a chain (Hoppe 1996, "Progressive meshes", §4.2): every
// vertex of a level goes to the vertex of the next level that its triangles are drawn with there,
// in the cluster that stands for most of its cluster's original surface.
#include <algorithm>
#include <array>
#include <cstring>

#include <glm/geometric.hpp>

#include "chain_internal.h"
#include "scenelod/lodcore/mesh.h"

namespace scenelod {

size_t LevelMorph::byteSize() const {
  size_t bytes = positions.size() * sizeof(glm::vec3) + normals.size() * sizeof(glm::vec3) +
                 colors.size() * sizeof(glm::vec3) + uvs.size() * sizeof(glm::vec2) + tangents.size() * sizeof(glm::vec4);
  for (const std::vector<glm::vec2>& set : extra_uvs) bytes += set.size() * sizeof(glm::vec2);
  return bytes;
}

std::vector<uint32_t> morphCornerVertices(const LodLevel& level, const Mesh& next, std::vector<uint32_t>* next_triangle) {
  const Mesh& a = level.mesh;
  const std::vector<glm::vec3>& target = level.morph.positions;
  std::vector<uint32_t> corner(a.triangles.size(), UINT32_MAX);
  if (next_triangle) next_triangle->assign(a.triangleCount(), UINT32_MAX);
  if (target.size() != a.vertexCount() || next.triangles.empty()) return corner;
  using Key = std::array<uint32_t, 3>;
  auto bits = [](const glm::vec3& p) {
    Key k;
    std::memcpy(k.data(), &p, sizeof(k));
    return k;
  };
  using Triple = std::array<Key, 3>;
  auto sortedTriple = [](Triple t) {
    std::sort(t.begin(), t.end());
    return t;
  };
  std::vector<std::pair<Triple, uint32_t>> tris;
  tris.reserve(next.triangleCount());
  for (size_t t = 0; t < next.triangleCount(); ++t) {
    const uint32_t* w = &next.triangles[3 * t];
    tris.push_back({sortedTriple({bits(next.positions[w[0]]), bits(next.positions[w[1]]), bits(next.positions[w[2]])}),
                    static_cast<uint32_t>(t)});
  }
  std::sort(tris.begin(), tris.end());
  const bool uvs = !a.uvs.empty() && !next.uvs.empty();
  for (size_t t = 0; t < a.triangleCount(); ++t) {
    const uint32_t* u = &a.triangles[3 * t];
    const Triple c = {bits(target[u[0]]), bits(target[u[1]]), bits(target[u[2]])};
    if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) continue;
    const Triple key = sortedTriple(c);
    auto it = std::lower_bound(tris.begin(), tris.end(), std::make_pair(key, uint32_t(0)));
    int best_rank = 0;
    float best_d2 = 0.0f;
    bool found = false;
    for (; it != tris.end() && it->first == key; ++it) {
      const uint32_t* w = &next.triangles[3 * it->second];
      uint32_t at[3] = {w[0], w[0], w[0]};  // the vertex of the match at each corner's target
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          if (bits(next.positions[w[j]]) == c[i]) at[i] = w[j];
      int j0 = 0;
      while (j0 < 2 && w[j0] != at[0]) ++j0;
      const bool same_orientation = w[(j0 + 1) % 3] == at[1];
      const int rank = (a.triangleGroup(t) == next.triangleGroup(it->second) ? 0 : 2) + (same_orientation ? 0 : 1);
      float d2 = 0.0f;
      if (uvs)
        for (int i = 0; i < 3; ++i) d2 += glm::dot(a.uvs[u[i]] - next.uvs[at[i]], a.uvs[u[i]] - next.uvs[at[i]]);
      if (!found || rank < best_rank || (rank == best_rank && d2 < best_d2)) {
        found = true, best_rank = rank, best_d2 = d2;
        std::copy(at, at + 3, &corner[3 * t]);
        if (next_triangle) (*next_triangle)[t] = it->second;
      }
    }
  }
  return corner;
}

namespace detail {

namespace {

// ids below `n` grouped: items of id i at list[offset[i] .. offset[i + 1]) in index order
// (kNone ids left out)
void groupBy(const std::vector<uint32_t>& id, size_t n, std::vector<uint32_t>& offset, std::vector<uint32_t>& list) {
  offset.assign(n + 1, 0);
  for (uint32_t c : id)
    if (c != kNone) ++offset[c + 1];
  for (size_t i = 0; i < n; ++i) offset[i + 1] += offset[i];
  list.resize(offset[n]);
  std::vector<uint32_t> next(offset.begin(), offset.end() - 1);
  for (size_t v = 0; v < id.size(); ++v)
    if (id[v] != kNone) list[next[id[v]]++] = static_cast<uint32_t>(v);
}

// per vertex: the group of the first triangle (else edge, else point) that uses it, 0 when none
std::vector<uint32_t> vertexGroups(const Mesh& m) {
  std::vector<uint32_t> g(m.vertexCount(), kNone);
  for (size_t t = 0; t < m.triangleCount(); ++t)
    for (int c = 0; c < 3; ++c)
      if (g[m.triangles[3 * t + c]] == kNone) g[m.triangles[3 * t + c]] = m.triangleGroup(t);
  for (size_t e = 0; e < m.edgeCount(); ++e)
    for (int c = 0; c < 2; ++c)
      if (g[m.edges[2 * e + c]] == kNone) g[m.edges[2 * e + c]] = m.edgeGroup(e);
  for (size_t i = 0; i < m.pointCount(); ++i)
    if (g[m.points[i]] == kNone) g[m.points[i]] = m.pointGroup(i);
  for (uint32_t& x : g)
    if (x == kNone) x = 0;
  return g;
}

}  // namespace

void identityMap(size_t vertex_count, LevelMap& out) {
  out.cluster_of.resize(vertex_count);
  out.vertex_cluster.resize(vertex_count);
  for (size_t v = 0; v < vertex_count; ++v) out.cluster_of[v] = out.vertex_cluster[v] = static_cast<uint32_t>(v);
}

std::vector<float> sourceAreas(const Mesh& m) {
  std::vector<float> area(m.vertexCount(), 0.0f);
  double total = 0.0;
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    const uint32_t* i = &m.triangles[3 * t];
    const float a = glm::length(glm::cross(m.positions[i[1]] - m.positions[i[0]], m.positions[i[2]] - m.positions[i[0]])) / 6.0f;
    if (!(a > 0.0f)) continue;
    for (int c = 0; c < 3; ++c) area[i[c]] += a;
    total += 3.0 * double(a);
  }
  const float floor = total > 0.0 && !area.empty() ? float(1e-6 * total / double(area.size())) : 1.0f;
  for (float& a : area) a += floor;
  return area;
}

namespace {

size_t idCount(const std::vector<uint32_t>& ids) {
  uint32_t top = 0;
  bool any = false;
  for (uint32_t c : ids)
    if (c != kNone) top = std::max(top, c), any = true;
  return any ? size_t(top) + 1 : 0;
}

// The first step of a geomorph (a level's clusters' targets in the next level's, from the two
// assignments): per cluster of `a`, the cluster of `b` holding the largest area of its original
// vertices (ties: the lower id); kNone where none of them is in one
std::vector<uint32_t> nextClusters(const std::vector<float>& area, const std::vector<uint32_t>& a,
                                   const std::vector<uint32_t>& b) {
  const size_t na = idCount(a), nb = idCount(b);
  std::vector<uint32_t> best(na, kNone);
  std::vector<uint32_t> offset, members;
  groupBy(a, na, offset, members);
  std::vector<float> sum(nb, 0.0f);
  std::vector<uint32_t> touched;
  for (size_t c = 0; c < na; ++c) {
    touched.clear();
    for (uint32_t i = offset[c]; i < offset[c + 1]; ++i) {
      const uint32_t v = members[i], cb = b[v];
      if (cb == kNone) continue;
      if (sum[cb] == 0.0f) touched.push_back(cb);
      sum[cb] += area[v];
    }
    float top = -1.0f;
    for (uint32_t cb : touched) {
      if (sum[cb] > top || (sum[cb] == top && cb < best[c])) top = sum[cb], best[c] = cb;
      sum[cb] = 0.0f;
    }
  }
  return best;
}

bool hasGroups(const Mesh& m) {
  return !m.triangle_groups.empty() || !m.edge_groups.empty() || !m.point_groups.empty();
}

// Per vertex of `ma`, the vertex of `mb` its triangles are drawn with there: each triangle of `ma`
// whose corners go to three distinct clusters of `mb` (`cb`) is matched to a triangle of `mb` on
// those clusters (the same triangle group and orientation preferred, then the nearest texture
// coordinates), and each corner votes, with the triangle's area, for the vertex of `mb` at its
// cluster there. The vertex with the most area wins (ties: the lower index); kNone where no
// triangle of the vertex has a match (it collapses, or the levels are not nested there).
std::vector<uint32_t> triangleTargets(const std::vector<uint32_t>& cb, const Mesh& ma,
                                      const std::vector<uint32_t>& b_vertex_cluster, const Mesh& mb) {
  const size_t n = ma.vertexCount();
  std::vector<uint32_t> target(n, kNone);
  if (ma.triangles.empty() || mb.triangles.empty()) return target;
  using Triple = std::array<uint32_t, 3>;
  auto sortedTriple = [](uint32_t a, uint32_t b, uint32_t c) {
    Triple t{a, b, c};
    std::sort(t.begin(), t.end());
    return t;
  };
  // mb's triangles by their sorted cluster triples
  std::vector<std::pair<Triple, uint32_t>> next;
  next.reserve(mb.triangleCount());
  for (size_t t = 0; t < mb.triangleCount(); ++t) {
    const uint32_t* w = &mb.triangles[3 * t];
    const uint32_t c0 = b_vertex_cluster[w[0]], c1 = b_vertex_cluster[w[1]], c2 = b_vertex_cluster[w[2]];
    if (c0 == kNone || c1 == kNone || c2 == kNone) continue;
    next.push_back({sortedTriple(c0, c1, c2), static_cast<uint32_t>(t)});
  }
  std::sort(next.begin(), next.end());
  const bool uvs = !ma.uvs.empty() && !mb.uvs.empty();
  struct Vote {
    uint32_t u, w;
    double area;
  };
  std::vector<Vote> votes;
  votes.reserve(ma.triangles.size());
  for (size_t t = 0; t < ma.triangleCount(); ++t) {
    const uint32_t* u = &ma.triangles[3 * t];
    const uint32_t c[3] = {cb[u[0]], cb[u[1]], cb[u[2]]};
    if (c[0] == kNone || c[1] == kNone || c[2] == kNone || c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) continue;
    const Triple key = sortedTriple(c[0], c[1], c[2]);
    auto it = std::lower_bound(next.begin(), next.end(), std::make_pair(key, uint32_t(0)));
    // the best match: same group, same orientation, nearest texture coordinates
    uint32_t best = kNone, best_corner[3] = {0, 0, 0};
    int best_rank = 0;
    float best_d2 = 0.0f;
    for (; it != next.end() && it->first == key; ++it) {
      const uint32_t* w = &mb.triangles[3 * it->second];
      uint32_t corner[3] = {kNone, kNone, kNone};  // the match's vertex at each corner's cluster
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          if (b_vertex_cluster[w[j]] == c[i]) corner[i] = w[j];
      // same orientation: corner 0 -> 1 -> 2 runs as in the match
      int j0 = 0;
      while (w[j0] != corner[0]) ++j0;
      const bool same_orientation = w[(j0 + 1) % 3] == corner[1];
      const int rank = (ma.triangleGroup(t) == mb.triangleGroup(it->second) ? 0 : 2) + (same_orientation ? 0 : 1);
      float d2 = 0.0f;
      if (uvs)
        for (int i = 0; i < 3; ++i) d2 += glm::dot(ma.uvs[u[i]] - mb.uvs[corner[i]], ma.uvs[u[i]] - mb.uvs[corner[i]]);
      if (best == kNone || rank < best_rank || (rank == best_rank && d2 < best_d2)) {
        best = it->second, best_rank = rank, best_d2 = d2;
        std::copy(corner, corner + 3, best_corner);
      }
    }
    if (best == kNone) continue;
    const glm::vec3& p = ma.positions[u[0]];
    const double area = 0.5 * double(glm::length(glm::cross(ma.positions[u[1]] - p, ma.positions[u[2]] - p))) + 1e-30;
    for (int i = 0; i < 3; ++i) votes.push_back({u[i], best_corner[i], area});
  }
  std::sort(votes.begin(), votes.end(), [](const Vote& a, const Vote& b) { return a.u != b.u ? a.u < b.u : a.w < b.w; });
  for (size_t i = 0; i < votes.size();) {
    const uint32_t u = votes[i].u;
    double top = -1.0;
    while (i < votes.size() && votes[i].u == u) {
      const uint32_t w = votes[i].w;
      double sum = 0.0;
      for (; i < votes.size() && votes[i].u == u && votes[i].w == w; ++i) sum += votes[i].area;
      if (sum > top) target[u] = w, top = sum;
    }
  }
  return target;
}

// The second step, from the levels' meshes: each vertex of `ma` (of cluster a_vertex_cluster[u], or
// u itself where that is null: level 0) to a vertex of `mb` in the cluster `best` gives it: the one
// its triangles are drawn with in `mb` (triangleTargets), else by the rule of computeMorph
void morphTargets(const std::vector<uint32_t>& best, const std::vector<uint32_t>* a_vertex_cluster, const Mesh& ma,
                  const std::vector<uint32_t>& b_vertex_cluster, const Mesh& mb, LevelMorph& out) {
  out = LevelMorph();
  const size_t nb = idCount(b_vertex_cluster);
  std::vector<uint32_t> offset, vertices;
  groupBy(b_vertex_cluster, nb, offset, vertices);
  // (all in group 0 where neither mesh has groups)
  const bool groups = hasGroups(ma) || hasGroups(mb);
  const std::vector<uint32_t> ga = groups ? vertexGroups(ma) : std::vector<uint32_t>();
  const std::vector<uint32_t> gb = groups ? vertexGroups(mb) : std::vector<uint32_t>();
  const size_t n = ma.vertexCount();
  const bool uvs = !ma.uvs.empty() && !mb.uvs.empty(), normals = !ma.normals.empty() && !mb.normals.empty();
  // every vertex's cluster in b
  std::vector<uint32_t> cb(n, kNone);
  for (size_t u = 0; u < n; ++u) {
    const uint32_t ca = a_vertex_cluster ? (*a_vertex_cluster)[u] : static_cast<uint32_t>(u);
    const uint32_t c = ca == kNone || ca >= best.size() ? kNone : best[ca];
    cb[u] = c == kNone || c >= nb ? kNone : c;
  }
  // the vertex of b each vertex of a goes to (kNone: stays)
  std::vector<uint32_t> target = triangleTargets(cb, ma, b_vertex_cluster, mb);
  for (size_t u = 0; u < n; ++u) {
    if (target[u] != kNone || cb[u] == kNone) continue;
    // lexicographic: group mismatch, texture coordinate distance, normal (larger dot first)
    bool best_other = true;
    float best_d2 = 0.0f, best_dot = 0.0f;
    for (uint32_t i = offset[cb[u]]; i < offset[cb[u] + 1]; ++i) {
      const uint32_t w = vertices[i];
      const bool other = groups && ga[u] != gb[w];
      const float d2 = uvs ? glm::dot(ma.uvs[u] - mb.uvs[w], ma.uvs[u] - mb.uvs[w]) : 0.0f;
      const float dot = normals ? glm::dot(ma.normals[u], mb.normals[w]) : 0.0f;
      const bool better = target[u] == kNone ||
                          (other != best_other ? !other
                                               : d2 != best_d2 ? d2 < best_d2 : dot > best_dot);
      if (better) target[u] = w, best_other = other, best_d2 = d2, best_dot = dot;
    }
  }
  // the targets' values; a vertex that stays takes its own
  auto fill = [&](auto& dst, const auto& own, const auto& next) {
    if (own.empty() || next.empty()) return;
    dst.resize(n);
    for (size_t u = 0; u < n; ++u) dst[u] = target[u] == kNone ? own[u] : next[target[u]];
  };
  fill(out.positions, ma.positions, mb.positions);
  if (ma.normals.empty() && !mb.normals.empty() && !ma.triangles.empty()) {
    // a level without normals (an OBJ without vn at level 0) is drawn with the normals a renderer
    // computes (computeVertexNormals); it gets targets all the same, so that at factor 1 it is
    // shaded as the next level is
    Mesh shape;
    shape.positions = ma.positions;
    shape.triangles = ma.triangles;
    computeVertexNormals(shape);
    fill(out.normals, shape.normals, mb.normals);
  } else {
    fill(out.normals, ma.normals, mb.normals);
  }
  fill(out.colors, ma.colors, mb.colors);
  fill(out.uvs, ma.uvs, mb.uvs);
  fill(out.tangents, ma.tangents, mb.tangents);
  out.extra_uvs.resize(std::min(ma.extra_uvs.size(), mb.extra_uvs.size()));
  for (size_t s = 0; s < out.extra_uvs.size(); ++s) fill(out.extra_uvs[s], ma.extra_uvs[s], mb.extra_uvs[s]);
  while (!out.extra_uvs.empty() && out.extra_uvs.back().empty()) out.extra_uvs.pop_back();
}

// moves `v` to `freed` (to be freed outside a lock) when its last use is done
void release(std::vector<uint32_t>& v, uint8_t& uses, std::vector<std::vector<uint32_t>>& freed) {
  if (--uses == 0) freed.push_back(std::move(v));
}

}  // namespace

void computeMorph(const std::vector<float>* area, const LevelMap* a, const Mesh& ma, const LevelMap& b, const Mesh& mb,
                  LevelMorph& out) {
  // (level 0: one original vertex per cluster, whose own cluster of b wins)
  if (!a) return morphTargets(b.cluster_of, nullptr, ma, b.vertex_cluster, mb, out);
  morphTargets(nextClusters(*area, a->cluster_of, b.cluster_of), &a->vertex_cluster, ma, b.vertex_cluster, mb, out);
}

MorphPairs::MorphPairs(const Mesh& original, std::vector<LodLevel>& levels, size_t level_count)
    : original_(original), levels_(levels), n_(level_count) {
  reset();
}

void MorphPairs::reset() {
  std::lock_guard<std::mutex> lock(mutex_);
  clustered_.assign(n_ + 1, 0);
  built_.assign(n_ + 1, 0);
  clustered_[0] = built_[0] = 1;
  cluster_of_.assign(n_ + 1, {});
  vertex_cluster_.assign(n_ + 1, {});
  // level k's assignment is read by the first step of the pairs (k - 1, k) and (k, k + 1), level 1's
  // by the second step of (0, 1) instead of the first; its vertices' clusters by both second steps
  cluster_uses_.assign(n_ + 1, 2);
  vertex_uses_.assign(n_ + 1, 2);
  if (n_ > 0) cluster_uses_[n_] = vertex_uses_[n_] = 1;
  best_.assign(n_, {});
  best_done_.assign(n_, 0);
  first_steps_ = n_ > 0 ? n_ - 1 : 0;
}

void MorphPairs::levelClustered(size_t k, std::vector<uint32_t> cluster_of) {
  std::vector<size_t> first, second;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    cluster_of_[k] = std::move(cluster_of);
    clustered_[k] = 1;
    for (size_t a : {k - 1, k}) {
      if (a >= n_ || !clustered_[a] || !clustered_[a + 1]) continue;
      if (a > 0) first.push_back(a);
      else if (pairReady(0)) second.push_back(0);  // (no first step: level 1's assignment is its result)
    }
  }
  for (size_t a : first) firstStep(a);
  for (size_t a : second) secondStep(a);
}

void MorphPairs::levelBuilt(size_t k, std::vector<uint32_t> vertex_cluster) {
  std::vector<size_t> second;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    vertex_cluster_[k] = std::move(vertex_cluster);
    built_[k] = 1;
    for (size_t a : {k - 1, k})
      if (a < n_ && pairReady(a)) second.push_back(a);
  }
  for (size_t a : second) secondStep(a);
}

bool MorphPairs::pairReady(size_t a) const {
  return built_[a] && built_[a + 1] && (a == 0 ? clustered_[1] != 0 : best_done_[a] != 0);
}

void MorphPairs::firstStep(size_t a) {
  std::call_once(area_once_, [this] { area_ = sourceAreas(original_); });
  std::vector<uint32_t> best = nextClusters(area_, cluster_of_[a], cluster_of_[a + 1]);
  std::vector<std::vector<uint32_t>> freed;
  std::vector<float> freed_area;
  bool ready = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    best_[a] = std::move(best);
    best_done_[a] = 1;
    release(cluster_of_[a], cluster_uses_[a], freed);
    release(cluster_of_[a + 1], cluster_uses_[a + 1], freed);
    if (--first_steps_ == 0) freed_area = std::move(area_);
    ready = pairReady(a);
  }
  if (ready) secondStep(a);
}

void MorphPairs::secondStep(size_t a) {
  const std::vector<uint32_t>& best = a == 0 ? cluster_of_[1] : best_[a];
  morphTargets(best, a == 0 ? nullptr : &vertex_cluster_[a], a == 0 ? original_ : levels_[a].mesh,
               vertex_cluster_[a + 1], levels_[a + 1].mesh, levels_[a].morph);
  std::vector<std::vector<uint32_t>> freed;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    freed.push_back(std::move(best_[a]));
    if (a == 0) release(cluster_of_[1], cluster_uses_[1], freed);
    else release(vertex_cluster_[a], vertex_uses_[a], freed);
    release(vertex_cluster_[a + 1], vertex_uses_[a + 1], freed);
  }
}

}  // namespace detail
}  // namespace scenelod
