// scenelod consistency: the experiment of Low & Tan 1997 §3.2.2 (plate 5). The model is simplified
// alone and with one more object added far away, which moves the bounding box; we count the output
// triangles of the original part that changed. Floating cells sit on the heaviest vertices and do
// not move; uniform-subdivision cells are anchored to the bounding box and shift.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <unordered_map>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "args.h"
#include "cluster_options.h"
#include "command.h"

namespace scenelod::tool {

namespace {

const std::string kUsage =
    "usage: scenelod consistency IN [--cell-rel F] [--far D]\n"
    "\n"
    "Simplifies IN (world space) alone and with a small box added D x the diagonal away (default\n"
    "0.7, below and behind the model: it moves the bounding-box minimum), with floating cells\n"
    "(nearest and heaviest variants) and uniform subdivision at the same cell width, and prints how\n"
    "many output triangles of the original part changed (a triangle is unchanged when the other run\n"
    "has one with the same corners within 1e-5 x the diagonal, in the same rotation order).\n"
    "\n"
    "  --cell-rel F  cell width as F x the model's bounding-box diagonal (default 0.01)\n"
    "  --far D       distance of the added box, in diagonals (default 0.7)";

struct Tri {
  glm::vec3 c[3];
};

bool lessVec(const glm::vec3& a, const glm::vec3& b) {
  return a.x != b.x ? a.x < b.x : a.y != b.y ? a.y < b.y : a.z < b.z;
}

std::vector<Tri> trianglesInside(const Mesh& m, const Aabb& region) {
  std::vector<Tri> out;
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    Tri tr;
    bool in = true;
    for (int k = 0; k < 3; ++k) {
      tr.c[k] = m.positions[m.triangles[3 * t + k]];
      in = in && glm::all(glm::greaterThanEqual(tr.c[k], region.min)) && glm::all(glm::lessThanEqual(tr.c[k], region.max));
    }
    if (!in) continue;
    int first = 0;
    for (int k = 1; k < 3; ++k)
      if (lessVec(tr.c[k], tr.c[first])) first = k;
    std::rotate(tr.c, tr.c + first, tr.c + 3);
    out.push_back(tr);
  }
  return out;
}

// triangles of `a` with no match in `b` (corners within eps), found through a grid of centroids
size_t countChanged(const std::vector<Tri>& a, const std::vector<Tri>& b, float cell, float eps) {
  auto key = [&](const glm::vec3& p) {
    const glm::ivec3 q = glm::ivec3(glm::floor(p / cell));
    return (uint64_t(uint32_t(q.x) & 0x1fffff) << 42) | (uint64_t(uint32_t(q.y) & 0x1fffff) << 21) |
           uint64_t(uint32_t(q.z) & 0x1fffff);
  };
  std::unordered_map<uint64_t, std::vector<uint32_t>> grid;
  for (size_t i = 0; i < b.size(); ++i) grid[key((b[i].c[0] + b[i].c[1] + b[i].c[2]) / 3.0f)].push_back(uint32_t(i));
  size_t changed = 0;
  for (const Tri& x : a) {
    const glm::vec3 centroid = (x.c[0] + x.c[1] + x.c[2]) / 3.0f;
    bool found = false;
    for (int dx = -1; dx <= 1 && !found; ++dx)
      for (int dy = -1; dy <= 1 && !found; ++dy)
        for (int dz = -1; dz <= 1 && !found; ++dz) {
          auto it = grid.find(key(centroid + glm::vec3(float(dx), float(dy), float(dz)) * cell));
          if (it == grid.end()) continue;
          for (uint32_t j : it->second) {
            const Tri& y = b[j];
            if (glm::length(x.c[0] - y.c[0]) <= eps && glm::length(x.c[1] - y.c[1]) <= eps &&
                glm::length(x.c[2] - y.c[2]) <= eps) {
              found = true;
              break;
            }
          }
        }
    if (!found) ++changed;
  }
  return changed;
}

int runConsistency(const std::vector<std::string>& argv) {
  Args args(argv, {}, {"--cell-rel", "--far"});
  if (!args.ok()) return usageError("consistency", args.error());
  if (args.positional().size() != 1) return usageError("consistency", "expected one input file");
  double rel = 0.01, far = 0.7;
  if (args.has("--cell-rel") && (!args.getDouble("--cell-rel", rel) || !(rel > 0.0) || !std::isfinite(rel)))
    return usageError("consistency", args.ok() ? "--cell-rel must be a finite number > 0" : args.error());
  if (args.has("--far") && (!args.getDouble("--far", far) || !(far > 0.0) || !std::isfinite(far)))
    return usageError("consistency", args.ok() ? "--far must be a finite number > 0" : args.error());
  const std::string in = args.positional()[0];
  Mesh model;
  if (Error e = loadWorldMesh(in, model)) return runError("consistency", e.message);
  if (model.triangleCount() == 0) return runError("consistency", in + ": the model has no triangles");
  const Aabb box = computeBounds(model);
  const float diag = box.diagonal();
  const float cell = float(rel) * diag;

  // the extra object: a box of 2 % of the diagonal, away along (-0.37, -0.41, -0.53)
  Mesh scene = model;
  {
    const glm::vec3 lo = box.min - glm::normalize(glm::vec3(0.37f, 0.41f, 0.53f)) * float(far) * diag;
    const glm::vec3 hi = lo + glm::vec3(0.02f * diag);
    const uint32_t b = uint32_t(scene.positions.size());
    for (int i = 0; i < 8; ++i)
      scene.positions.push_back({(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z});
    const uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : quads)
      scene.triangles.insert(scene.triangles.end(), {b + q[0], b + q[1], b + q[2], b + q[0], b + q[2], b + q[3]});
    if (!scene.normals.empty()) scene.normals.resize(scene.positions.size(), glm::vec3(0, 0, 1));
    if (!scene.colors.empty()) scene.colors.resize(scene.positions.size(), glm::vec3(1.0f));
    if (!scene.uvs.empty()) scene.uvs.resize(scene.positions.size(), glm::vec2(0.0f));
    if (!scene.face_offsets.empty()) {
      for (size_t t = model.triangleCount(); t < scene.triangleCount(); ++t) {
        for (int k = 0; k < 3; ++k) scene.face_corners.push_back(scene.triangles[3 * t + k]);
        scene.face_offsets.push_back(uint32_t(scene.face_corners.size()));
      }
    }
  }
  Aabb region = box;
  region.min -= glm::vec3(cell);
  region.max += glm::vec3(cell);
  std::printf("%s: %zu triangles, diagonal %.6g, cell width %.6g (%.4g x diagonal), extra box %.2g diagonals away\n",
              in.c_str(), model.triangleCount(), double(diag), double(cell), rel, far);
  std::printf("%-18s %12s %12s %10s\n", "method", "triangles", "changed", "changed %");
  for (LodMethod method : {LodMethod::kFloatingNearest, LodMethod::kFloatingHeaviest, LodMethod::kUniform}) {
    ClusterParams p;
    p.method = method;
    p.cell_width = cell;
    Mesh a, b;
    if (Error e = clusterMesh(model, p, a)) return runError("consistency", in + ": " + e.message);
    if (Error e = clusterMesh(scene, p, b)) return runError("consistency", in + ": " + e.message);
    const std::vector<Tri> ta = trianglesInside(a, region), tb = trianglesInside(b, region);
    const size_t changed = countChanged(ta, tb, cell, 1e-5f * diag);
    std::printf("%-18s %12zu %12zu %9.2f%%\n", lodMethodName(method), ta.size(), changed,
                ta.empty() ? 0.0 : 100.0 * double(changed) / double(ta.size()));
  }
  return 0;
}

const CommandRegistration kRegister({"consistency", "Low & Tan's consistency experiment: floating vs uniform cells",
                                     kUsage.c_str(), &runConsistency});

}  // namespace

}  // namespace scenelod::tool
