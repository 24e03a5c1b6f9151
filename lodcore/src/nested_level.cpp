// Nested clustering levels: level k + 1 clusters the vertices of level k (its representatives), which
// carry the heaviest weight and the summed face sums of the original vertices they stand for, so that
// the next level's cells float on the same grading and its representatives minimise the same
// quadrics as an independent level's would, while every primitive of level k maps to one primitive
// of level k + 1 (or vanishes): the geomorph from k to k + 1 is exact and no level gains primitives.
#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "chain_internal.h"
#include "scenelod/lodcore/chain.h"

namespace scenelod::detail {

namespace {

// the face sums of several vertices added: quadric and normal sums decoded, summed and encoded again
struct SumAccumulator {
  float area = 0.0f;
  float s[9] = {};
  void add(const VertexFaceSums& f) {
    if (!(f.area > 0.0f)) return;
    float d[9];
    f.decode(d);
    for (int i = 0; i < 9; ++i) s[i] += d[i];
    area += f.area;
  }
  VertexFaceSums encoded() const {
    VertexFaceSums f;
    f.encode(area, s);
    return f;
  }
};

}  // namespace

Error prepareNested(const Mesh& prev, const Carried* carried, const ClusterParams& params, NestedInput& in) {
  in.attributes = hasAttributes(prev);
  in.am = AttributeMesh();
  in.p = PreparedMesh();
  if (in.attributes) makeAttributeMesh(prev, in.am);
  const Mesh& m = in.attributes ? in.am.mesh() : prev;
  if (Error e = prepareMesh(m, params, in.p, "level"); !e.ok()) return e;
  if (!carried || in.p.order.empty()) return {};
  const size_t n = m.vertexCount();
  const bool welded = in.attributes && in.am.did_weld;
  std::vector<float> weight(n, 0.0f);
  std::vector<SumAccumulator> sums(n);
  const bool colors = !carried->colors.empty() && in.p.face_colors.size() == n;
  std::vector<glm::vec4> face_colors(colors ? n : 0, glm::vec4(0.0f));
  for (size_t u = 0; u < prev.vertexCount(); ++u) {
    const size_t x = welded ? in.am.welded_of[u] : u;
    weight[x] = std::max(weight[x], carried->weight[u]);
    sums[x].add(carried->sums[u]);
    if (colors) face_colors[x] += carried->colors[u];
  }
  for (size_t x = 0; x < n; ++x) in.p.face_sums[x] = sums[x].encoded();
  in.p.weights = std::move(weight);
  if (colors) in.p.face_colors = std::move(face_colors);
  // the order by the carried weights: heaviest first, ties by index, as prepareMesh sorts
  const std::vector<float>& w = in.p.weights;
  std::sort(in.p.order.begin(), in.p.order.end(), [&](uint32_t a, uint32_t b) { return w[a] > w[b] || (w[a] == w[b] && a < b); });
  if (!in.p.sorted_positions.empty())
    for (size_t i = 0; i < in.p.order.size(); ++i) in.p.sorted_positions[i] = m.positions[in.p.order[i]];
  return {};
}

Error nestedLevel(NestedInput& in, const Mesh& prev, const LevelMap* prev_map, const std::vector<uint32_t>* prev_source,
                  float prev_error, const Mesh& original, const ClusterParams& params, LodLevel& out, LevelMap* out_map,
                  Carried* out_carried) {
  out = LodLevel();
  out.cell_width = params.cell_width;
  out.method = params.method;
  out.max_error = prev_error;
  const Mesh& m = in.attributes ? in.am.mesh() : prev;
  const bool welded = in.attributes && in.am.did_weld;
  auto clustered = [&](size_t u) { return welded ? in.am.welded_of[u] : static_cast<uint32_t>(u); };
  std::vector<uint32_t> cc, vc, sv;  // cluster per clustered vertex, per output vertex; sources (prev's indices)
  ClusterStats cs;
  if (!in.p.order.empty()) {
    if (in.attributes) {
      AttributeLevelParts parts;
      if (Error e = clusterAttributeParts(in.p, params, parts, &cs); !e.ok()) return e;
      finishAttributeLevel(in.am, params, parts, out.mesh, &sv, &cc, &vc);
    } else {
      LevelParts parts;
      parts.keep_heaviest = true;
      parts.keep_cluster_of = true;
      if (Error e = clusterLevelParts(in.p, params, parts, &cs); !e.ok()) return e;
      cc = std::move(parts.cluster_of);
      finishLevel(parts, params, out.mesh, &sv, &vc);
      carryUniformGroup(prev, out.mesh);
    }
  } else {
    cc.assign(m.vertexCount(), kNone);
  }
  out.bounds = computeBoundingSphere(out.mesh);
  if (in.attributes && (!prev_source || !prev_source->empty())) {
    out.source_vertex.resize(sv.size());
    for (size_t w = 0; w < sv.size(); ++w) out.source_vertex[w] = prev_source ? (*prev_source)[sv[w]] : sv[w];
  }
  const size_t clusters = [&] {
    uint32_t top = 0;
    for (uint32_t c : cc)
      if (c != kNone) top = std::max(top, c + 1);
    return size_t(top);
  }();
  // every cluster's representative (the position of its output vertices), for the error
  std::vector<glm::vec3> rep(clusters);
  std::vector<uint8_t> has_rep(clusters, 0);
  for (size_t w = 0; w < vc.size(); ++w) rep[vc[w]] = out.mesh.positions[w], has_rep[vc[w]] = 1;
  if (prev_map && !prev_map->empty()) {
    // the original vertices' clusters through a vertex of their cluster in prev
    std::vector<uint32_t> first_vertex;
    for (size_t u = 0; u < prev_map->vertex_cluster.size(); ++u) {
      const uint32_t pc = prev_map->vertex_cluster[u];
      if (pc == kNone) continue;
      if (pc >= first_vertex.size()) first_vertex.resize(size_t(pc) + 1, kNone);
      if (first_vertex[pc] == kNone) first_vertex[pc] = static_cast<uint32_t>(u);
    }
    LevelMap local;
    LevelMap& map = out_map ? *out_map : local;
    map.cluster_of.assign(prev_map->cluster_of.size(), kNone);
    float max_d2 = 0.0f;
    for (size_t v = 0; v < map.cluster_of.size(); ++v) {
      const uint32_t pc = prev_map->cluster_of[v];
      if (pc == kNone || pc >= first_vertex.size() || first_vertex[pc] == kNone) continue;
      const uint32_t c = cc[clustered(first_vertex[pc])];
      map.cluster_of[v] = c;
      if (c != kNone && has_rep[c]) {
        const glm::vec3 d = original.positions[v] - rep[c];
        max_d2 = std::max(max_d2, glm::dot(d, d));
      }
    }
    out.max_error = std::sqrt(max_d2);
    map.vertex_cluster = vc;
  } else {
    out.max_error = prev_error + cs.max_error;
  }
  if (out_carried) {
    // per cluster: the heaviest weight and the summed sums of its clustered vertices
    std::vector<float> weight(clusters, 0.0f);
    std::vector<SumAccumulator> sums(clusters);
    const bool colors = !in.p.face_colors.empty();
    std::vector<glm::vec4> face_colors(colors ? clusters : 0, glm::vec4(0.0f));
    for (size_t x = 0; x < cc.size(); ++x) {
      const uint32_t c = cc[x];
      if (c == kNone) continue;
      if (!in.p.weights.empty()) weight[c] = std::max(weight[c], in.p.weights[x]);
      if (!in.p.face_sums.empty()) sums[c].add(in.p.face_sums[x]);
      if (colors) face_colors[c] += in.p.face_colors[x];
    }
    Carried& k = *out_carried;
    const size_t n = out.mesh.vertexCount();
    k.weight.assign(n, 0.0f);
    k.sums.assign(n, VertexFaceSums());
    k.colors.assign(colors ? n : 0, glm::vec4(0.0f));
    std::vector<uint8_t> given(clusters, 0);
    for (size_t w = 0; w < n; ++w) {
      const uint32_t c = vc[w];
      k.weight[w] = weight[c];
      if (given[c]) continue;
      given[c] = 1;
      k.sums[w] = sums[c].encoded();
      if (colors) k.colors[w] = face_colors[c];
    }
  }
  return {};
}

}  // namespace scenelod::detail
