// LOD chains from the vision-characteristic edge collapse of Zhang, Shu & Luo 2003: every level is
// cut from one greedy run on the original at its triangle target, which is the same mesh a separate
// run to that target gives (the collapse order never depends on the target).
#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "chain_internal.h"
#include "scenelod/lodcore/zhang.h"

namespace scenelod {
namespace {

Sphere boundingSphere(const Mesh& m) {
  Sphere s;
  if (m.positions.empty()) return s;
  s.center = computeBounds(m).center();
  float r2 = 0.0f;
  for (const glm::vec3& p : m.positions) r2 = std::max(r2, glm::dot(p - s.center, p - s.center));
  s.radius = std::sqrt(r2);
  return s;
}

}  // namespace

Error buildZhangChain(const Mesh& original, const ChainParams& params, const ZhangParams& zhang, LodChain& out) {
  out = LodChain{};
  if (Error e = validateMesh(original, "zhang chain input"); !e.ok()) return e;
  LodLevel base;
  base.mesh = original;
  base.method = LodMethod::kOriginal;
  base.bounds = boundingSphere(original);
  out.levels.push_back(std::move(base));
  const size_t t0 = original.triangleCount();
  std::vector<size_t> targets;
  for (size_t k = 1, t = t0 / 2; k <= params.level_count && t >= 4; ++k, t /= 2) targets.push_back(t);
  if (targets.empty()) return {};

  std::vector<Mesh> meshes;
  std::vector<ZhangStats> stats;
  if (Error e = simplifyZhangMulti(original, targets, zhang, meshes, &stats, params.progress); !e.ok()) {
    out = LodChain{};
    return e;
  }
  // the smallest positive step keeps widths strictly increasing when the measured error does not grow
  const float min_width = 1e-6f * std::max(computeBounds(original).diagonal(), 1e-30f);
  size_t previous_triangles = t0;
  float previous_width = 0.0f;
  // the geomorphs, each made once its two levels are: an input vertex's cluster is the vertex it
  // collapsed into (level 0's map, the identity, is not stored)
  detail::LevelMap prev_map, map;
  std::vector<float> area;
  for (size_t i = 0; i < meshes.size(); ++i) {
    if (stats[i].output_triangles >= previous_triangles) break;  // no collapse possible any more
    previous_triangles = stats[i].output_triangles;
    LodLevel level;
    level.max_error = stats[i].max_displacement;
    level.cell_width = std::max({zhangEquivalentCellWidth(stats[i].max_surface_distance), min_width,
                                 std::nextafter(previous_width, INFINITY) * (1.0f + 1e-6f)});
    previous_width = level.cell_width;
    level.method = LodMethod::kZhang;
    level.bounds = boundingSphere(meshes[i]);
    level.mesh = std::move(meshes[i]);
    level.source_vertex = std::move(stats[i].source_vertex);
    out.levels.push_back(std::move(level));
    if (params.morphs) {
      map.cluster_of = std::move(stats[i].collapsed_into);
      map.vertex_cluster = std::move(stats[i].output_vertex_of);
      const size_t k = out.levels.size() - 2;  // the pair (k, k + 1)
      if (k > 0 && area.empty()) area = detail::sourceAreas(original);
      detail::computeMorph(k == 0 ? nullptr : &area, k == 0 ? nullptr : &prev_map, out.levels[k].mesh, map,
                           out.levels[k + 1].mesh, out.levels[k].morph);
      prev_map = std::move(map);
    }
    std::vector<uint32_t>().swap(stats[i].collapsed_into);
  }
  return {};
}

Error buildZhangChain(const Mesh& original, const ChainParams& params, LodChain& out) {
  return buildZhangChain(original, params, ZhangParams{}, out);
}

}  // namespace scenelod
