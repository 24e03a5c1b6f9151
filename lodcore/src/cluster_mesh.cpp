// One level of vertex clustering: assignment (uniform subdivision, Rossignac & Borrel 1993, or
// floating cells, Low & Tan 1997 §3.2), synthesis, elimination with thick edges (§3.3.1), normals.
#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "cluster_internal.h"

namespace scenelod {

namespace detail {

Error assign(const PreparedMesh& p, const ClusterParams& params, Assignment& a) {
  if (!p.mesh) return {Status::kInvalidArgument, "the prepared mesh holds no mesh (call prepareMesh first)"};
  if (Error e = detail::checkCellWidth(p, params.cell_width)) return e;
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
                        ClusterStats* stats, void (*assigned)(void*), void* context) {
  Assignment a;
  const Error assign_error = assign(prepared, params, a);
  if (assigned) assigned(context);
  if (assign_error) {
    parts = LevelParts();
    if (stats) *stats = ClusterStats();
    return assign_error;
  }
  return clusterLevelParts(prepared, params, a, parts, stats);
}

Error clusterLevelParts(const PreparedMesh& prepared, const ClusterParams& params, Assignment& a, LevelParts& parts,
                        ClusterStats* stats) {
  parts = LevelParts();
  if (stats) *stats = ClusterStats();
  const Mesh& m = *prepared.mesh;
  // elimination before synthesis (neither reads the other's result), so that the representatives
  // (24 bytes per cluster) are not held through elimination's scratch, the largest of a level; the
  // eliminated primitives (about 6 bytes per cluster at fine levels) are held through synthesis
  Eliminated& el = parts.eliminated;
  eliminate(prepared, a, params.keep_edges, params.keep_points, true, el);
  Representatives& r = parts.representatives;
  synthesize(prepared, a, params.synthesis, r);
  std::vector<uint32_t>().swap(a.heaviest);
  if (stats) {
    stats->cluster_count = a.cluster_count;
    stats->collapsed_triangles = el.collapsed_triangles;
    float max_d2 = 0.0f;
    for (size_t v = 0; v < a.cluster_of.size(); ++v) {
      if (a.cluster_of[v] == kNone) continue;
      const glm::vec3 d = m.positions[v] - r.positions[a.cluster_of[v]];
      max_d2 = std::max(max_d2, glm::dot(d, d));
    }
    stats->max_error = std::sqrt(max_d2);
  }
  a = Assignment();
  return {};
}

void finishLevel(LevelParts& parts, const ClusterParams& params, Mesh& out) {
  buildOutputMesh(parts.eliminated, parts.representatives, params.crease_angle_deg, out);
  parts = LevelParts();
}

}  // namespace detail

Error clusterPrepared(const PreparedMesh& prepared, const ClusterParams& params, Mesh& out, ClusterStats* stats) {
  out = Mesh();
  detail::LevelParts parts;
  if (Error e = detail::clusterLevelParts(prepared, params, parts, stats)) return e;
  detail::finishLevel(parts, params, out);
  return {};
}

Error assignClusters(const PreparedMesh& prepared, const ClusterParams& params, ClusterAssignment& out) {
  out = ClusterAssignment();
  detail::Assignment a;
  if (Error e = detail::assign(prepared, params, a)) return e;
  out.cluster_of = std::move(a.cluster_of);
  out.heaviest = std::move(a.heaviest);
  return {};
}

Error countClusteredTriangles(const PreparedMesh& prepared, const ClusterParams& params, size_t& triangle_count) {
  triangle_count = 0;
  detail::Assignment a;
  if (Error e = detail::assign(prepared, params, a)) return e;
  detail::Eliminated el;
  detail::eliminate(prepared, a, false, false, false, el);
  triangle_count = el.triangles.size() / 3;
  return {};
}

Error clusterMesh(const Mesh& in, const ClusterParams& params, Mesh& out, float* max_error) {
  out = Mesh();
  if (max_error) *max_error = 0.0f;
  if (!std::isfinite(params.cell_width) || !(params.cell_width > 0.0f))
    return {Status::kInvalidArgument,
            "cell width " + std::to_string(params.cell_width) + " is not a finite positive number"};
  PreparedMesh p;
  if (Error e = prepareMesh(in, params, p)) return e;
  if (p.order.empty()) return {};
  ClusterStats stats;
  if (Error e = clusterPrepared(p, params, out, &stats)) return e;
  if (max_error) *max_error = stats.max_error;
  return {};
}

}  // namespace scenelod
