// One level of vertex clustering: assignment (uniform subdivision, Rossignac & Borrel 1993, or
// floating cells, Low & Tan 1997 §3.2), synthesis, elimination with thick edges (§3.3.1), normals.
#include <algorithm>
#include <atomic>
#include <cmath>

#include <glm/geometric.hpp>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

#include "attribute_level.h"
#include "cluster_internal.h"
#include "test_hooks.h"

namespace scenelod {

namespace detail {

namespace {

// the largest squared distance from a vertex to its cluster's representative (unclustered vertices,
// kNone, skipped); a max of the same per-vertex values in any order is the same float
float maxSquaredDisplacementScalar(const glm::vec3* pos, const uint32_t* cluster_of, size_t n, const glm::vec3* rep,
                                   size_t begin = 0) {
  float max_d2 = 0.0f;
  for (size_t v = begin; v < n; ++v) {
    if (cluster_of[v] == kNone) continue;
    const glm::vec3 d = pos[v] - rep[cluster_of[v]];
    max_d2 = std::max(max_d2, glm::dot(d, d));
  }
  return max_d2;
}

#if defined(__x86_64__) || defined(__i386__)
// eight vertices at a time, the representatives gathered: the scalar form's operations per lane
// ((dx dx + dy dy) + dz dz, as glm::dot; no FMA), unclustered lanes masked to 0. One pass of the
// chain's per-level statistics, 0.87 M of the bunny chain's 176 M instructions (one thread)
SCENELOD_AVX2_TARGET float maxSquaredDisplacementAvx2(const glm::vec3* pos, const uint32_t* cluster_of, size_t n,
                                                       const glm::vec3* rep) {
  __m256 acc = _mm256_setzero_ps();
  const __m256i none = _mm256_set1_epi32(-1);
  const __m256i lane3 = _mm256_setr_epi32(0, 3, 6, 9, 12, 15, 18, 21);
  const float* p = &pos[0].x;
  const float* r = &rep[0].x;
  size_t v = 0;
  for (; v + 8 <= n; v += 8) {
    const __m256i c = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(cluster_of + v));
    const __m256i skip = _mm256_cmpeq_epi32(c, none);
    const __m256i c3 = _mm256_andnot_si256(skip, _mm256_add_epi32(c, _mm256_add_epi32(c, c)));
    const float* pv = p + 3 * v;
    const __m256 dx = _mm256_sub_ps(_mm256_i32gather_ps(pv, lane3, 4), _mm256_i32gather_ps(r, c3, 4));
    const __m256 dy = _mm256_sub_ps(_mm256_i32gather_ps(pv + 1, lane3, 4), _mm256_i32gather_ps(r + 1, c3, 4));
    const __m256 dz = _mm256_sub_ps(_mm256_i32gather_ps(pv + 2, lane3, 4), _mm256_i32gather_ps(r + 2, c3, 4));
    const __m256 d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
    acc = _mm256_max_ps(_mm256_andnot_ps(_mm256_castsi256_ps(skip), d2), acc);
  }
  alignas(32) float lanes[8];
  _mm256_store_ps(lanes, acc);
  float max_d2 = maxSquaredDisplacementScalar(pos, cluster_of, n, rep, v);
  for (float x : lanes) max_d2 = std::max(max_d2, x);
  return max_d2;
}
#endif

float maxSquaredDisplacement(const glm::vec3* pos, const uint32_t* cluster_of, size_t n, const glm::vec3* rep) {
#if defined(__x86_64__) || defined(__i386__)
  // (gather offsets of 32 bits: 3 * n floats must index within them)
  if (avx2Paths() && n < (size_t(1) << 31) / 3) return maxSquaredDisplacementAvx2(pos, cluster_of, n, rep);
#endif
  return maxSquaredDisplacementScalar(pos, cluster_of, n, rep);
}

// Fewer clusters than this are not renumbered (below): their per-cluster arrays (synthesis' sums
// alone take 92 bytes a cluster) stay nearer the cache, and the pass over every vertex only costs
// time. Paired timings (scripts/paired-paths, off / on, medians; AMD Zen 3): the 1 M sphere 1.115
// at 50 % (258 k clusters), 1.085 at 25 %, 1.038 at 10 % (51 k), 0.971 at 3 % (15 k), 0.962 at 1 %;
// the bunny 1.011 at 50 % (17.6 k), 0.97 at 5 %, 0.925 at 2 %
constexpr uint32_t kRenumberMinClusters = 32768;
// -1: renumber where the clusters are at least kRenumberMinClusters; 0 never, 1 always (the test
// hook setRenumberingForTest, for paired timings and tests)
std::atomic<int> g_renumber{-1};

}  // namespace

// Renumbers the clusters in the order of their first vertex by index. The assignment numbers them
// in creation order, heaviest first, which is spatially random: elimination's edge lists,
// synthesis' sums and the output's vertices, all indexed by cluster, were then read at random while
// the mesh's own order (the input triangles, the vertices) is spatially coherent. On the 1 M
// sphere's 50 % level (258 k clusters), 3.3-3.5 ms of renumbering took elimination from 47-51 ms
// to 32-35, synthesis from 31 to 22 and the output pass from 21-24 to 11 (AMD Zen 3). Which
// vertex is each cluster's heaviest is unchanged; only the ids move. Without a branch per vertex:
// a third to a half of the vertices open a cluster at fine levels, in no predictable pattern.
void renumberByFirstVertex(Assignment& a) {
  const uint32_t nc = a.cluster_count;
  const int mode = g_renumber.load(std::memory_order_relaxed);
  if (nc == 0 || mode == 0 || (mode < 0 && nc < kRenumberMinClusters)) return;
  std::vector<uint32_t> remap(nc, kNone);
  std::vector<uint32_t> heaviest(nc);
  uint32_t* cluster_of = a.cluster_of.data();
  const uint32_t* old_heaviest = a.heaviest.data();
  uint32_t* to = remap.data();
  uint32_t* h = heaviest.data();
  uint32_t next = 0;
  for (size_t v = 0, n = a.cluster_of.size(); v < n; ++v) {
    const uint32_t c = cluster_of[v];
    if (c == kNone) continue;  // unreferenced: rare, and together
    const uint32_t r = to[c];
    const uint32_t fresh = uint32_t(r == kNone);
    const uint32_t id = fresh ? next : r;
    to[c] = id;
    h[id] = old_heaviest[c];  // (the same value again when not fresh)
    next += fresh;
    cluster_of[v] = id;
  }
  a.heaviest.swap(heaviest);
}

// (test_hooks.h)
int setRenumberingForTest(int mode) { return g_renumber.exchange(mode < 0 ? -1 : mode > 0 ? 1 : 0); }

Error assign(const PreparedMesh& p, const ClusterParams& params, Assignment& a) {
  if (!p.mesh) return {Status::kInvalidArgument, "the prepared mesh holds no mesh (call prepareMesh first)"};
  if (Error e = detail::checkCellWidth(p, params.cell_width); !e.ok()) return e;
  switch (params.method) {
    case LodMethod::kUniform:
      detail::assignUniform(p, params.cell_width, a);
      return {};
    case LodMethod::kFloatingHeaviest:
    case LodMethod::kFloatingNearest:
      detail::assignFloating(p, params.cell_width, params.cell_shape, params.method == LodMethod::kFloatingNearest, a);
      return {};
    default:
      return {Status::kInvalidArgument, std::string("method '") + lodMethodName(params.method) +
                                            "' is not a vertex-clustering method"};
  }
}

Error clusterLevelParts(const PreparedMesh& prepared, const ClusterParams& params, LevelParts& parts,
                        ClusterStats* stats, void (*assigned)(void*), void* context, void (*synthesized)(void*),
                        void* synthesized_context) {
  Assignment a;
  const Error assign_error = assign(prepared, params, a);
  if (assigned) assigned(context);
  if (!assign_error.ok()) {
    parts = LevelParts();
    if (stats) *stats = ClusterStats();
    return assign_error;
  }
  return clusterLevelParts(prepared, params, a, parts, stats, synthesized, synthesized_context);
}

Error clusterLevelParts(const PreparedMesh& prepared, const ClusterParams& params, Assignment& a, LevelParts& parts,
                        ClusterStats* stats, void (*synthesized)(void*), void* context) {
  const bool keep_heaviest = parts.keep_heaviest, keep_cluster_of = parts.keep_cluster_of;
  parts = LevelParts();
  parts.keep_heaviest = keep_heaviest;
  parts.keep_cluster_of = keep_cluster_of;
  if (stats) *stats = ClusterStats();
  const Mesh& m = *prepared.mesh;
  auto releaseHeaviest = [&] {
    if (keep_heaviest) parts.heaviest = std::move(a.heaviest);
    else std::vector<uint32_t>().swap(a.heaviest);
  };
  renumberByFirstVertex(a);
  // elimination before synthesis (neither reads the other's result), so that the representatives
  // (24 bytes per cluster) are not held through elimination's scratch, the largest of a level; the
  // eliminated primitives (about 6 bytes per cluster at fine levels) are held through synthesis.
  // Synthesis first where the caller waits for it (a chain frees the prepared arrays once every
  // level is past synthesis; elimination reads only the mesh)
  Eliminated& el = parts.eliminated;
  Representatives& r = parts.representatives;
  if (synthesized) {
    synthesize(prepared, a, params.synthesis, r);
    releaseHeaviest();
    synthesized(context);
    eliminate(prepared, a, params.keep_edges, params.keep_points, true, el);
  } else {
    eliminate(prepared, a, params.keep_edges, params.keep_points, true, el);
    synthesize(prepared, a, params.synthesis, r);
    releaseHeaviest();
  }
  if (stats) {
    stats->cluster_count = a.cluster_count;
    stats->collapsed_triangles = el.collapsed_triangles;
    stats->max_error = std::sqrt(maxSquaredDisplacement(m.positions.data(), a.cluster_of.data(), a.cluster_of.size(),
                                                        r.positions.data()));
  }
  if (keep_cluster_of) parts.cluster_of = std::move(a.cluster_of);
  a = Assignment();
  return {};
}

void finishLevel(LevelParts& parts, const ClusterParams& params, Mesh& out, std::vector<uint32_t>* source_vertex,
                 std::vector<uint32_t>* vertex_cluster) {
  const Eliminated& e = parts.eliminated;
  // the triangles' cluster ids, which the output pass overwrites with vertex ids in place
  std::vector<uint32_t> corner_cluster;
  if (source_vertex || vertex_cluster) corner_cluster = e.triangles;
  buildOutputMesh(parts.eliminated, parts.representatives, params.crease_angle_deg, out);
  if (source_vertex) {
    const std::vector<uint32_t>& h = parts.heaviest;
    source_vertex->assign(out.vertexCount(), kNone);
    for (size_t i = 0; i < corner_cluster.size(); ++i) (*source_vertex)[out.triangles[i]] = h[corner_cluster[i]];
    for (size_t i = 0; i < e.edges.size(); ++i) (*source_vertex)[out.edges[i]] = h[e.edges[i]];
    for (size_t i = 0; i < e.points.size(); ++i) (*source_vertex)[out.points[i]] = h[e.points[i]];
  }
  if (vertex_cluster) {
    vertex_cluster->assign(out.vertexCount(), kNone);
    for (size_t i = 0; i < corner_cluster.size(); ++i) (*vertex_cluster)[out.triangles[i]] = corner_cluster[i];
    for (size_t i = 0; i < e.edges.size(); ++i) (*vertex_cluster)[out.edges[i]] = e.edges[i];
    for (size_t i = 0; i < e.points.size(); ++i) (*vertex_cluster)[out.points[i]] = e.points[i];
  }
  parts = LevelParts();
}

}  // namespace detail

namespace {

// clusterPrepared, with source vertices when `source_vertex` is given
Error clusterPreparedWith(const PreparedMesh& prepared, const ClusterParams& params, Mesh& out, ClusterStats* stats,
                          std::vector<uint32_t>* source_vertex) {
  out = Mesh();
  if (source_vertex) source_vertex->clear();
  if (prepared.mesh && detail::hasAttributes(*prepared.mesh))
    return detail::clusterAttributeMesh(prepared, params, out, source_vertex, stats);
  detail::LevelParts parts;
  parts.keep_heaviest = source_vertex != nullptr;
  if (Error e = detail::clusterLevelParts(prepared, params, parts, stats); !e.ok()) return e;
  detail::finishLevel(parts, params, out, source_vertex);
  detail::carryUniformGroup(*prepared.mesh, out);
  return {};
}

// clusterMesh, with source vertices when `source_vertex` is given
Error clusterMeshWith(const Mesh& in, const ClusterParams& params, Mesh& out, ClusterStats& stats,
                      std::vector<uint32_t>* source_vertex) {
  out = Mesh();
  stats = ClusterStats();
  if (source_vertex) source_vertex->clear();
  if (!std::isfinite(params.cell_width) || !(params.cell_width > 0.0f))
    return {Status::kInvalidArgument,
            "cell width " + std::to_string(params.cell_width) + " is not a finite positive number"};
  // a mesh with attributes is prepared once, welded
  if (detail::hasAttributes(in)) {
    if (Error e = validateMesh(in, "mesh"); !e.ok()) return e;
    detail::AttributeMesh am;
    detail::makeAttributeMesh(in, am);
    PreparedMesh p;
    if (Error e = prepareMesh(am.mesh(), params, p); !e.ok()) return e;
    if (p.order.empty()) return {};
    return detail::clusterAttributeLevel(p, am, params, out, source_vertex, &stats);
  }
  PreparedMesh p;
  if (Error e = prepareMesh(in, params, p); !e.ok()) return e;
  if (p.order.empty()) return {};
  return clusterPreparedWith(p, params, out, &stats, source_vertex);
}

}  // namespace

Error clusterPrepared(const PreparedMesh& prepared, const ClusterParams& params, Mesh& out, ClusterStats* stats) {
  return clusterPreparedWith(prepared, params, out, stats, nullptr);
}

Error clusterPrepared(const PreparedMesh& prepared, const ClusterParams& params, Mesh& out, ClusterOutputs& outputs) {
  return clusterPreparedWith(prepared, params, out, &outputs.stats, &outputs.source_vertex);
}

Error assignClusters(const PreparedMesh& prepared, const ClusterParams& params, ClusterAssignment& out) {
  out = ClusterAssignment();
  detail::Assignment a;
  if (Error e = detail::assign(prepared, params, a); !e.ok()) return e;
  out.cluster_of = std::move(a.cluster_of);
  out.heaviest = std::move(a.heaviest);
  return {};
}

Error countClusteredTriangles(const PreparedMesh& prepared, const ClusterParams& params, size_t& triangle_count) {
  triangle_count = 0;
  detail::Assignment a;
  if (Error e = detail::assign(prepared, params, a); !e.ok()) return e;
  detail::Eliminated el;
  detail::eliminate(prepared, a, false, false, false, el);
  triangle_count = el.triangles.size() / 3;
  return {};
}

Error clusterMesh(const Mesh& in, const ClusterParams& params, Mesh& out, ClusterOutputs& outputs) {
  return clusterMeshWith(in, params, out, outputs.stats, &outputs.source_vertex);
}

Error clusterMesh(const Mesh& in, const ClusterParams& params, Mesh& out, float* max_error) {
  ClusterStats stats;
  const Error e = clusterMeshWith(in, params, out, stats, nullptr);
  if (max_error) *max_error = stats.max_error;
  return e;
}

}  // namespace scenelod
