// Vertex cache and vertex fetch ordering. Triangle order: Forsyth 2006, "Linear-Speed Vertex Cache
// Optimisation" (LRU cache model of 32 entries, score = cache-position term + valence boost, greedy
// best-triangle choice among triangles of cached vertices). Vertex order: first use.
#include "scenelod/scene/mesh_order.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace scenelod::scene {

namespace {

constexpr int kCacheSize = 32;
constexpr float kCacheDecayPower = 1.5f;
constexpr float kLastTriangleScore = 0.75f;
constexpr float kValenceBoostScale = 2.0f;
constexpr float kValenceBoostPower = 0.5f;
constexpr int kMaxValence = 64;  // scores of higher valences equal this one's

struct ScoreTables {
  float cache[kCacheSize + 3];
  float valence[kMaxValence + 1];
  ScoreTables() {
    for (int i = 0; i < kCacheSize + 3; ++i) {
      if (i < 3) {
        cache[i] = kLastTriangleScore;  // the three vertices of the triangle just added
      } else if (i < kCacheSize) {
        const float scaler = 1.0f / float(kCacheSize - 3);
        cache[i] = std::pow(1.0f - float(i - 3) * scaler, kCacheDecayPower);
      } else {
        cache[i] = 0.0f;
      }
    }
    valence[0] = 0.0f;  // no triangles left: the vertex does not matter
    for (int v = 1; v <= kMaxValence; ++v) valence[v] = kValenceBoostScale * std::pow(float(v), -kValenceBoostPower);
  }
};

const ScoreTables& tables() {
  static const ScoreTables t;
  return t;
}

inline float vertexScore(int cache_pos, uint32_t remaining) {
  const ScoreTables& t = tables();
  if (remaining == 0) return -1.0f;
  const float c = cache_pos < 0 ? 0.0f : t.cache[cache_pos];
  return c + t.valence[std::min<uint32_t>(remaining, kMaxValence)];
}

}  // namespace

void optimizeVertexCache(Span<uint32_t> dst, Span<const uint32_t> idx, size_t vertex_count) {
  const size_t tri_count = idx.size() / 3;
  if (tri_count == 0) return;
  // triangle lists per vertex (CSR)
  std::vector<uint32_t> offsets(vertex_count + 1, 0), remaining(vertex_count, 0);
  for (size_t i = 0; i < tri_count * 3; ++i) ++remaining[idx[i]];
  for (size_t v = 0; v < vertex_count; ++v) offsets[v + 1] = offsets[v] + remaining[v];
  std::vector<uint32_t> adjacency(tri_count * 3), fill(offsets.begin(), offsets.end() - 1);
  for (size_t t = 0; t < tri_count; ++t)
    for (int k = 0; k < 3; ++k) adjacency[fill[idx[3 * t + k]]++] = static_cast<uint32_t>(t);

  std::vector<float> vscore(vertex_count), tscore(tri_count, 0.0f);
  std::vector<int8_t> cache_pos(vertex_count, -1);
  for (size_t v = 0; v < vertex_count; ++v) vscore[v] = vertexScore(-1, remaining[v]);
  for (size_t t = 0; t < tri_count; ++t)
    tscore[t] = vscore[idx[3 * t]] + vscore[idx[3 * t + 1]] + vscore[idx[3 * t + 2]];
  std::vector<uint8_t> emitted(tri_count, 0);

  uint32_t cache[kCacheSize + 3];
  int cache_count = 0;
  size_t cursor = 0;  // input-order restart point for dead ends
  int64_t best = -1;
  // the first triangle: the best scored overall
  {
    float bs = -1e30f;
    for (size_t t = 0; t < tri_count; ++t)
      if (tscore[t] > bs) { bs = tscore[t]; best = static_cast<int64_t>(t); }
  }
  size_t out = 0;
  while (true) {
    if (best < 0) {
      // dead end: the next triangle not yet emitted in input order
      while (cursor < tri_count && emitted[cursor]) ++cursor;
      if (cursor == tri_count) break;
      best = static_cast<int64_t>(cursor);
    }
    const size_t t = static_cast<size_t>(best);
    emitted[t] = 1;
    for (int k = 0; k < 3; ++k) dst[out++] = idx[3 * t + k];
    // remove t from its vertices' triangle lists
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = idx[3 * t + k];
      uint32_t* list = adjacency.data() + offsets[v];
      const uint32_t n = remaining[v];
      for (uint32_t j = 0; j < n; ++j)
        if (list[j] == t) { list[j] = list[n - 1]; break; }
      --remaining[v];
    }
    // LRU: the triangle's vertices go to the front, the rest shift back
    uint32_t next_cache[kCacheSize + 3];
    int next_count = 0;
    for (int k = 0; k < 3; ++k) next_cache[next_count++] = idx[3 * t + k];
    for (int i = 0; i < cache_count; ++i) {
      const uint32_t v = cache[i];
      if (v != idx[3 * t] && v != idx[3 * t + 1] && v != idx[3 * t + 2]) next_cache[next_count++] = v;
    }
    // new positions and scores for every vertex that was or is in the cache
    for (int i = 0; i < next_count; ++i) {
      const uint32_t v = next_cache[i];
      cache_pos[v] = static_cast<int8_t>(i < kCacheSize ? i : -1);
      const float ns = vertexScore(cache_pos[v], remaining[v]);
      const float diff = ns - vscore[v];
      vscore[v] = ns;
      const uint32_t* list = adjacency.data() + offsets[v];
      for (uint32_t j = 0; j < remaining[v]; ++j) tscore[list[j]] += diff;
    }
    cache_count = std::min(next_count, kCacheSize);
    std::copy(next_cache, next_cache + cache_count, cache);
    // the next triangle: best among those touching the cache
    best = -1;
    float bs = -1e30f;
    for (int i = 0; i < cache_count; ++i) {
      const uint32_t v = cache[i];
      const uint32_t* list = adjacency.data() + offsets[v];
      for (uint32_t j = 0; j < remaining[v]; ++j)
        if (tscore[list[j]] > bs) { bs = tscore[list[j]]; best = list[j]; }
    }
  }
}

size_t vertexFetchRemap(Span<uint32_t> remap, Span<const uint32_t> indices, size_t vertex_count) {
  std::fill(remap.begin(), remap.begin() + vertex_count, 0xffffffffu);
  uint32_t next = 0;
  for (uint32_t v : indices)
    if (remap[v] == 0xffffffffu) remap[v] = next++;
  const size_t used = next;
  for (size_t v = 0; v < vertex_count; ++v)
    if (remap[v] == 0xffffffffu) remap[v] = next++;
  return used;
}

double computeAcmr(Span<const uint32_t> indices, size_t vertex_count, size_t cache_size) {
  const size_t tri_count = indices.size() / 3;
  if (tri_count == 0) return 0.0;
  // fifo of cache_size entries: a vertex is a hit while fewer than cache_size misses happened since
  // it was last loaded
  std::vector<uint64_t> loaded_at(vertex_count, 0);
  uint64_t misses = 0;
  for (size_t i = 0; i < tri_count * 3; ++i) {
    const uint32_t v = indices[i];
    if (loaded_at[v] == 0 || misses + 1 - loaded_at[v] > cache_size) {
      ++misses;
      loaded_at[v] = misses;
    }
  }
  return double(misses) / double(tri_count);
}

void optimizeMeshOrder(Mesh& m, std::vector<uint32_t>* vertex_remap) {
  const size_t n = m.vertexCount();
  if (!m.triangles.empty()) {
    // each triangle group (primitive) on its own, groups in increasing order, so that a group stays
    // one contiguous range of triangles
    std::vector<uint32_t> order(m.triangleCount());
    for (size_t t = 0; t < order.size(); ++t) order[t] = static_cast<uint32_t>(t);
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return m.triangleGroup(a) < m.triangleGroup(b); });
    std::vector<uint32_t> grouped(m.triangles.size()), tri(m.triangles.size());
    for (size_t t = 0; t < order.size(); ++t)
      for (size_t k = 0; k < 3; ++k) grouped[3 * t + k] = m.triangles[3 * size_t(order[t]) + k];
    for (size_t begin = 0; begin < order.size();) {
      size_t end = begin + 1;
      while (end < order.size() && m.triangleGroup(order[end]) == m.triangleGroup(order[begin])) ++end;
      optimizeVertexCache(Span<uint32_t>(tri.data() + 3 * begin, 3 * (end - begin)),
                          Span<const uint32_t>(grouped.data() + 3 * begin, 3 * (end - begin)), n);
      begin = end;
    }
    if (!m.triangle_groups.empty()) {
      std::vector<uint32_t> groups(order.size());
      for (size_t t = 0; t < order.size(); ++t) groups[t] = m.triangle_groups[order[t]];
      m.triangle_groups.swap(groups);
    }
    m.triangles.swap(tri);
  }
  // first use across triangles, then edges, then points
  std::vector<uint32_t> all;
  all.reserve(m.triangles.size() + m.edges.size() + m.points.size());
  all.insert(all.end(), m.triangles.begin(), m.triangles.end());
  all.insert(all.end(), m.edges.begin(), m.edges.end());
  all.insert(all.end(), m.points.begin(), m.points.end());
  std::vector<uint32_t> remap(n);
  vertexFetchRemap(Span<uint32_t>(remap.data(), n), Span<const uint32_t>(all.data(), all.size()), n);
  auto permute = [&](auto& attr) {
    if (attr.empty()) return;
    std::remove_reference_t<decltype(attr)> out(attr.size());
    for (size_t v = 0; v < n; ++v) out[remap[v]] = attr[v];
    attr.swap(out);
  };
  permute(m.positions);
  permute(m.normals);
  permute(m.colors);
  permute(m.uvs);
  for (std::vector<glm::vec2>& set : m.extra_uvs) permute(set);
  permute(m.tangents);
  permute(m.joints);
  permute(m.weights);
  for (uint32_t& i : m.triangles) i = remap[i];
  for (uint32_t& i : m.edges) i = remap[i];
  for (uint32_t& i : m.points) i = remap[i];
  for (uint32_t& i : m.face_corners) i = remap[i];
  if (vertex_remap) vertex_remap->swap(remap);
}

}  // namespace scenelod::scene
