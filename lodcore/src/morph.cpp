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

size_t idCount(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b) {
  uint32_t top = 0;
  bool any = false;
  for (const std::vector<uint32_t>* ids : {&a, &b})
    for (uint32_t c : *ids)
      if (c != kNone) top = std::max(top, c), any = true;
  return any ? size_t(top) + 1 : 0;
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

// per cluster of `a` (null: level 0, every vertex its own cluster), the cluster of `b` holding the
// largest area of its original vertices (ties: the lower id); kNone where none of them is in one
std::vector<uint32_t> bestClusters(const std::vector<float>* area, const LevelMap* a, const LevelMap& b, size_t na,
                                   size_t nb) {
  if (!a) return b.cluster_of;  // (one original vertex per cluster: its own cluster of b wins)
  std::vector<uint32_t> best(na, kNone);
  std::vector<uint32_t> offset, members;
  groupBy(a->cluster_of, na, offset, members);
  std::vector<float> sum(nb, 0.0f);
  std::vector<uint32_t> touched;
  for (size_t c = 0; c < na; ++c) {
    touched.clear();
    for (uint32_t i = offset[c]; i < offset[c + 1]; ++i) {
      const uint32_t v = members[i], cb = b.cluster_of[v];
      if (cb == kNone) continue;
      if (sum[cb] == 0.0f) touched.push_back(cb);
      sum[cb] += (*area)[v];
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

}  // namespace

void computeMorph(const std::vector<float>* area, const LevelMap* a, const Mesh& ma, const LevelMap& b, const Mesh& mb,
                  LevelMorph& out) {
  out = LevelMorph();
  const size_t na = a ? idCount(a->cluster_of, a->vertex_cluster) : ma.vertexCount();
  const size_t nb = idCount(b.cluster_of, b.vertex_cluster);
  const std::vector<uint32_t> best = bestClusters(area, a, b, na, nb);
  std::vector<uint32_t> offset, vertices;
  groupBy(b.vertex_cluster, nb, offset, vertices);
  // (all in group 0 where neither mesh has groups)
  const bool groups = hasGroups(ma) || hasGroups(mb);
  const std::vector<uint32_t> ga = groups ? vertexGroups(ma) : std::vector<uint32_t>();
  const std::vector<uint32_t> gb = groups ? vertexGroups(mb) : std::vector<uint32_t>();
  const size_t n = ma.vertexCount();
  const bool uvs = !ma.uvs.empty() && !mb.uvs.empty(), normals = !ma.normals.empty() && !mb.normals.empty();
  // the vertex of b each vertex of a goes to (kNone: stays)
  std::vector<uint32_t> target(n, kNone);
  for (size_t u = 0; u < n; ++u) {
    const uint32_t ca = a ? a->vertex_cluster[u] : static_cast<uint32_t>(u);
    const uint32_t cb = ca == kNone || ca >= na ? kNone : best[ca];
    if (cb == kNone) continue;
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

MorphPairs::MorphPairs(const Mesh& original, std::vector<LodLevel>& levels, size_t level_count)
    : original_(original), levels_(levels), n_(level_count) {
  reset();
}

void MorphPairs::reset() {
  std::lock_guard<std::mutex> lock(mutex_);
  built_.assign(n_ + 1, 0);
  built_[0] = 1;
  pending_.assign(n_ + 1, 2);
  pending_[0] = 1;
  pending_[n_] = n_ > 0 ? 1 : 0;
  maps_.clear();
  maps_.resize(n_ + 1);
  area_pairs_ = n_ > 0 ? n_ - 1 : 0;
}

void MorphPairs::levelBuilt(size_t k, LevelMap map) {
  bool below = false, above = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    maps_[k] = std::move(map);
    built_[k] = 1;
    below = built_[k - 1] != 0;
    above = k < n_ && built_[k + 1] != 0;
  }
  if (below) makePair(k - 1);
  if (above) makePair(k);
}

void MorphPairs::makePair(size_t a) {
  const std::vector<float>* area = nullptr;
  if (a > 0) {
    std::call_once(area_once_, [this] { area_ = sourceAreas(original_); });
    area = &area_;
  }
  const Mesh& ma = a == 0 ? original_ : levels_[a].mesh;
  computeMorph(area, a == 0 ? nullptr : &maps_[a], ma, maps_[a + 1], levels_[a + 1].mesh, levels_[a].morph);
  // (freed outside the lock)
  LevelMap done_a, done_b;
  std::vector<float> done_area;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (--pending_[a] == 0) done_a = std::move(maps_[a]);
    if (--pending_[a + 1] == 0) done_b = std::move(maps_[a + 1]);
    if (a > 0 && --area_pairs_ == 0) done_area = std::move(area_);
  }
}

}  // namespace detail
}  // namespace scenelod
