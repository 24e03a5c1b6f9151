// Geomorph targets between two levels of a chain (Hoppe 1996, "Progressive meshes", §4.2): every
// vertex of a level goes to the vertex of the next level that stands for most of its cluster's
// original surface.
#include <algorithm>

#include <glm/geometric.hpp>

#include "chain_internal.h"

namespace scenelod {

size_t LevelMorph::byteSize() const {
  size_t bytes = positions.size() * sizeof(glm::vec3) + normals.size() * sizeof(glm::vec3) +
                 colors.size() * sizeof(glm::vec3) + uvs.size() * sizeof(glm::vec2) + tangents.size() * sizeof(glm::vec4);
  for (const std::vector<glm::vec2>& set : extra_uvs) bytes += set.size() * sizeof(glm::vec2);
  return bytes;
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

// The second step, from the levels' meshes: each vertex of `ma` (of cluster a_vertex_cluster[u], or
// u itself where that is null: level 0) to a vertex of `mb` in the cluster `best` gives it
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
  // the vertex of b each vertex of a goes to (kNone: stays)
  std::vector<uint32_t> target(n, kNone);
  for (size_t u = 0; u < n; ++u) {
    const uint32_t ca = a_vertex_cluster ? (*a_vertex_cluster)[u] : static_cast<uint32_t>(u);
    const uint32_t cb = ca == kNone || ca >= best.size() ? kNone : best[ca];
    if (cb == kNone || cb >= nb) continue;
    // lexicographic: group mismatch, texture coordinate distance, normal (larger dot first)
    bool best_other = true;
    float best_d2 = 0.0f, best_dot = 0.0f;
    for (uint32_t i = offset[cb]; i < offset[cb + 1]; ++i) {
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
  fill(out.normals, ma.normals, mb.normals);
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
