#include "scrooge_options.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include <glm/geometric.hpp>

#include "cluster_options.h"

namespace scenelod::tool {

const char kScroogeOptionsHelp[] =
    "  --method scrooge  SCROOGE (Reddy 1996): edge degradation and coplanar merging restricted to\n"
    "                    sub-volumes (docs/SCROOGE.md); no vertex moves farther than a sub-volume diagonal\n"
    "  --subvolume S     scrooge: 1/64, 1/8 or 1 of the bounding volume (4, 2, 1 sub-volumes per axis)\n"
    "  --cell-rel F      scrooge: cubic sub-volumes whose diagonal is F x the bounding-box diagonal\n"
    "  --cell W          scrooge: cubic sub-volumes of edge W\n"
    "  --theta-max D     scrooge: edge pairs bending more than D degrees never degrade (default 45)\n";

bool isScroogeMethod(const Args& args) { return args.get("--method") == "scrooge"; }

bool parseScroogeOptions(Args& args, ScroogeParams& p, std::string& error) {
  p = ScroogeParams();
  if (args.has("--theta-max")) {
    double t = 0.0;
    if (!args.getDouble("--theta-max", t) || !std::isfinite(t) || t <= double(p.theta_min_deg) || t > 180.0) {
      error = args.ok() ? "--theta-max must be a number of degrees in (5, 180]" : args.error();
      return false;
    }
    p.theta_max_deg = float(t);
  }
  return true;
}

namespace {

bool parseFraction(const std::string& s, int& divisions) {
  if (s == "1/64") divisions = 4;
  else if (s == "1/8") divisions = 2;
  else if (s == "1") divisions = 1;
  else return false;
  return true;
}

// the size options shared by simplify and lods; exactly one or none
bool readSize(Args& args, double& cell, double& rel, int& divisions, std::string& error) {
  if (int(args.has("--cell")) + int(args.has("--cell-rel")) + int(args.has("--subvolume")) > 1) {
    error = "give only one of --cell, --cell-rel, --subvolume";
    return false;
  }
  if (args.has("--target-triangles")) {
    error = "--target-triangles is not available with --method scrooge (SCROOGE is driven by sub-volume size)";
    return false;
  }
  if (args.has("--cell") && (!args.getDouble("--cell", cell) || !std::isfinite(cell) || cell <= 0.0)) {
    error = args.ok() ? "--cell must be a finite number > 0" : args.error();
    return false;
  }
  if (args.has("--cell-rel") && (!args.getDouble("--cell-rel", rel) || !std::isfinite(rel) || rel <= 0.0)) {
    error = args.ok() ? "--cell-rel must be a finite number > 0" : args.error();
    return false;
  }
  if (args.has("--subvolume") && !parseFraction(args.get("--subvolume"), divisions)) {
    error = "--subvolume must be 1/64, 1/8 or 1, not '" + args.get("--subvolume") + "'";
    return false;
  }
  return true;
}

}  // namespace

bool scroogeSubvolume(Args& args, const Mesh& mesh, glm::vec3& size, std::string& error) {
  double cell = 0.0, rel = 0.0;
  int divisions = 4;
  if (!readSize(args, cell, rel, divisions, error)) return false;
  const Aabb box = computeBounds(mesh);
  if (cell > 0.0) size = glm::vec3(float(cell));
  else if (rel > 0.0) size = scroogeSubvolumeForCellRel(box, float(rel));
  else size = scroogeSubvolumeForDivisions(box, divisions);
  if (!(size.x > 0.0f && size.y > 0.0f && size.z > 0.0f)) {
    error = "the model's bounding box has no size, so it has no sub-volumes";
    return false;
  }
  return true;
}

bool scroogeFirstWidth(Args& args, const Mesh& mesh, float& width, std::string& error) {
  double cell = 0.0, rel = 0.0;
  int divisions = 0;
  if (!readSize(args, cell, rel, divisions, error)) return false;
  const Aabb box = computeBounds(mesh);
  width = 0.0f;
  if (cell > 0.0) width = float(cell);
  else if (rel > 0.0) width = scroogeSubvolumeForCellRel(box, float(rel)).x;
  else if (divisions > 0) {
    const glm::vec3 s = scroogeSubvolumeForDivisions(box, divisions);
    width = std::max({s.x, s.y, s.z});
  }
  return true;
}

int runScroogeSimplify(Args& args, const std::string& in, const std::string& out) {
  ScroogeParams params;
  std::string err;
  if (!parseScroogeOptions(args, params, err)) return usageError("simplify", err);
  Mesh mesh;
  if (Error e = loadWorldMesh(in, mesh); !e.ok()) return runError("simplify", e.message);
  if (!scroogeSubvolume(args, mesh, params.subvolume_size, err)) return usageError("simplify", in + ": " + err);
  using Clock = std::chrono::steady_clock;
  const Clock::time_point t0 = Clock::now();
  Mesh result;
  ScroogeStats stats;
  if (Error e = scroogeMesh(mesh, params, result, &stats, in.c_str()); !e.ok()) return runError("simplify", e.message);
  const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  if (Error e = writeMeshFile(out, result, "simplified"); !e.ok()) return runError("simplify", e.message);
  const float diag = computeBounds(mesh).diagonal();
  const glm::vec3 s = params.subvolume_size;
  std::printf("%s: %zu vertices, %zu triangles, %zu polygons read\n", in.c_str(), mesh.vertexCount(),
              mesh.triangleCount(), stats.input_polygons);
  std::printf("method scrooge, sub-volume %.6g x %.6g x %.6g (diagonal %.4g x bbox diagonal), theta %g..%g deg\n",
              double(s.x), double(s.y), double(s.z), double(glm::length(s)) / std::max(1e-30, double(diag)),
              double(params.theta_min_deg), double(params.theta_max_deg));
  std::printf("normalised: %zu welded vertices, %zu duplicate, %zu degenerate, %zu sub-polygons removed\n",
              stats.welded_vertices, stats.duplicate_polygons, stats.degenerate_polygons, stats.sub_polygons);
  std::printf("%s: %zu vertices, %zu polygons, %zu triangles, %zu edges, %zu points; %zu moves, %zu merges, "
              "max vertex move %.6g\n",
              out.c_str(), result.vertexCount(), stats.output_polygons, result.triangleCount(), result.edgeCount(),
              result.pointCount(), stats.moved_vertices, stats.merged_groups, double(stats.max_displacement));
  std::printf("time: %.1f ms\n", ms);
  return 0;
}

}  // namespace scenelod::tool
