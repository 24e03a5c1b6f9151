// scenelod consistency: the experiment of Low & Tan 1997 §3.2.2 (plate 5). The model is simplified
// alone and with one more object added far away, which moves the bounding box; we count the output
// triangles of the original part that changed. Floating cells sit on the heaviest vertices and do
// not move; uniform-subdivision cells are anchored to the bounding box and shift.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "scenelod/eval/consistency.h"
#include "scenelod/scene/scene_data.h"

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
  if (Error e = loadWorldMesh(in, model); !e.ok()) return runError("consistency", e.message);
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
    for (std::vector<glm::vec2>& set : scene.extra_uvs) set.resize(scene.positions.size(), glm::vec2(0.0f));
    if (!scene.tangents.empty()) scene.tangents.resize(scene.positions.size(), glm::vec4(1, 0, 0, 1));
    if (!scene.triangle_groups.empty()) scene.triangle_groups.resize(scene.triangleCount(), scene::kNoMaterial);
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
    if (Error e = clusterMesh(model, p, a); !e.ok()) return runError("consistency", in + ": " + e.message);
    if (Error e = clusterMesh(scene, p, b); !e.ok()) return runError("consistency", in + ": " + e.message);
    const eval::TriangleChangeCount count = eval::countChangedTriangles(a, b, region, 1e-5f * diag);
    std::printf("%-18s %12zu %12zu %9.2f%%\n", lodMethodName(method), count.compared, count.changed,
                count.compared == 0 ? 0.0 : 100.0 * double(count.changed) / double(count.compared));
  }
  return 0;
}

const CommandRegistration kRegister({"consistency", "Low & Tan's consistency experiment: floating vs uniform cells",
                                     kUsage.c_str(), &runConsistency});

}  // namespace

}  // namespace scenelod::tool
