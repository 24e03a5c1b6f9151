// scenelod simplify: one level of vertex clustering (Low & Tan 1997 floating cells, or the Rossignac
// & Borrel uniform grid) of a whole model in world space.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "args.h"
#include "cluster_options.h"
#include "command.h"
#include "scrooge_options.h"
#include "zhang_options.h"
#include "scenelod/scene/gltf_io.h"

namespace scenelod::tool {

namespace {

const std::string kUsage = std::string(
    "usage: scenelod simplify IN -o OUT [--method M] [--cell W | --cell-rel F | --target-triangles N]\n"
    "                         [--grading G] [--synthesis S] [--cell-shape C]\n"
    "\n"
    "Simplifies IN (.obj, .gltf, .glb; the whole model in world space) by vertex clustering into OUT\n"
    "(.obj: triangles as f, edges as l with '#t' thickness comments, points as p; .glb: one node with\n"
    "TRIANGLES, LINES with _THICKNESS, POINTS).\n"
    "\n"
    "  --cell W              absolute object-space cell width\n"
    "  --cell-rel F          F x the bounding-box diagonal (default 0.02)\n"
    "  --target-triangles N  search the cell width that gives about N triangles\n") +
    kClusterOptionsHelp + kZhangOptionsHelp +
    "  zhang takes --target-triangles N (default: half the triangles); --cell and --cell-rel do not apply\n" +
    kScroogeOptionsHelp;

// --method zhang: edge collapse to a triangle count
int runZhangSimplify(const std::string& in, const std::string& out, const Mesh& mesh, long target,
                     const ZhangParams& zp) {
  const size_t t = target > 0 ? size_t(target) : mesh.triangleCount() / 2;
  const auto t0 = std::chrono::steady_clock::now();
  Mesh result;
  ZhangStats st;
  if (Error e = simplifyZhang(mesh, t, zp, result, &st); !e.ok()) return runError("simplify", in + ": " + e.message);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (Error e = writeMeshFile(out, result, "simplified"); !e.ok()) return runError("simplify", e.message);
  std::printf("%s: %zu vertices, %zu triangles\n", in.c_str(), mesh.vertexCount(), mesh.triangleCount());
  std::printf("method zhang (%s, placement %s, influence %s), target %zu triangles\n", zhangModeName(zp.mode),
              zhangPlacementName(zp.placement), zhangInfluenceName(zp.influence), t);
  std::printf("%s: %zu vertices, %zu triangles; %zu collapses, %s, max vertex displacement %.6g, surface "
              "distance bound %.6g\n", out.c_str(), result.vertexCount(), result.triangleCount(), st.collapses,
              zhangStopReasonName(st.stop_reason), double(st.max_displacement), double(st.max_surface_distance));
  std::printf("rejected: %zu fold-over, %zu topology; dropped input triangles: %zu degenerate, %zu duplicate\n",
              st.rejected_fold, st.rejected_topology, st.dropped_degenerate, st.dropped_duplicate);
  std::printf("kept vertices: %zu edge (border), %zu complex, %zu corner; %zu movable vertices left; "
              "%zu seam vertices\n",
              st.kept_edge_vertices, st.kept_complex_vertices, st.kept_angle_vertices, st.free_vertices_left,
              st.seam_vertices);
  std::printf("time: %.1f ms\n", ms);
  return 0;
}

int runSimplify(const std::vector<std::string>& argv) {
  std::vector<std::string> options = clusterOptionNames();
  for (const char* o : {"--out", "--cell", "--cell-rel", "--target-triangles"}) options.push_back(o);
  for (const std::string& o : zhangOptionNames()) options.push_back(o);
  for (const std::string& o : scroogeOptionNames()) options.push_back(o);
  Args args(argv, {}, options);
  if (!args.ok()) return usageError("simplify", args.error());
  if (args.positional().size() != 1) return usageError("simplify", "expected one input file");
  if (!args.has("--out")) return usageError("simplify", "missing -o OUT");
  const std::string in = args.positional()[0], out = args.get("--out");
  const std::string ext = scene::lowerExtension(out);
  if (ext != ".obj" && ext != ".glb") return usageError("simplify", "the output must end in .obj or .glb: " + out);
  if (isScroogeMethod(args)) return runScroogeSimplify(args, in, out);
  if (args.has("--subvolume") || args.has("--theta-max"))
    return usageError("simplify", "--subvolume and --theta-max need --method scrooge");
  int size_options = int(args.has("--cell")) + int(args.has("--cell-rel")) + int(args.has("--target-triangles"));
  if (size_options > 1) return usageError("simplify", "give only one of --cell, --cell-rel, --target-triangles");
  ClusterParams params;
  std::string err;
  if (!parseClusterOptions(args, params, err)) return usageError("simplify", err);
  double cell = 0.0, rel = 0.02;
  long target = 0;
  Args& a = args;
  if (args.has("--cell") && (!a.getDouble("--cell", cell) || !std::isfinite(cell) || cell <= 0.0))
    return usageError("simplify", a.ok() ? "--cell must be a finite number > 0" : a.error());
  if (args.has("--cell-rel") && (!a.getDouble("--cell-rel", rel) || !std::isfinite(rel) || rel <= 0.0))
    return usageError("simplify", a.ok() ? "--cell-rel must be a finite number > 0" : a.error());
  if (args.has("--target-triangles") && (!a.getInt("--target-triangles", target) || target <= 0))
    return usageError("simplify", a.ok() ? "--target-triangles must be an integer > 0" : a.error());

  ZhangParams zp;
  if (!parseZhangOptions(args, zp, err)) return usageError("simplify", err);
  if (params.method == LodMethod::kZhang && (args.has("--cell") || args.has("--cell-rel")))
    return usageError("simplify", "--method zhang takes --target-triangles, not --cell or --cell-rel");

  Mesh mesh;
  if (Error e = loadWorldMesh(in, mesh); !e.ok()) return runError("simplify", e.message);
  if (params.method == LodMethod::kZhang) return runZhangSimplify(in, out, mesh, target, zp);
  using Clock = std::chrono::steady_clock;
  const Clock::time_point t0 = Clock::now();
  PreparedMesh prepared;
  if (Error e = prepareMesh(mesh, params, prepared, in); !e.ok()) return runError("simplify", e.message);
  const double prepare_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  if (prepared.order.empty()) return runError("simplify", in + ": the model has no triangles, edges or points");
  if (target > 0) {
    float w = 0.0f;
    if (Error e = findCellWidthForTarget(prepared, params, size_t(target), w); !e.ok()) return runError("simplify", in + ": " + e.message);
    params.cell_width = w;
  } else if (cell > 0.0) {
    params.cell_width = float(cell);
  } else {
    params.cell_width = float(rel * double(prepared.bounds.diagonal()));
  }
  const Clock::time_point t1 = Clock::now();
  Mesh result;
  ClusterStats stats;
  if (Error e = clusterPrepared(prepared, params, result, &stats); !e.ok()) return runError("simplify", in + ": " + e.message);
  const double level_ms = std::chrono::duration<double, std::milli>(Clock::now() - t1).count();
  if (Error e = writeMeshFile(out, result, "simplified"); !e.ok()) return runError("simplify", e.message);
  std::printf("%s: %zu vertices, %zu triangles, %zu edges, %zu points\n", in.c_str(), mesh.vertexCount(),
              mesh.triangleCount(), mesh.edgeCount(), mesh.pointCount());
  std::printf("method %s, grading %s, synthesis %s, cells %s, cell width %.6g (%.4g x diagonal)\n",
              lodMethodName(params.method), gradingName(params.grading), synthesisName(params.synthesis),
              cellShapeName(params.cell_shape), double(params.cell_width),
              double(params.cell_width) / std::max(1e-30, double(prepared.bounds.diagonal())));
  std::printf("%s: %zu vertices, %zu triangles, %zu edges, %zu points; %zu clusters, max error %.6g\n", out.c_str(),
              result.vertexCount(), result.triangleCount(), result.edgeCount(), result.pointCount(),
              stats.cluster_count, double(stats.max_error));
  std::printf("time: grading and sort %.1f ms, clustering %.1f ms\n", prepare_ms, level_ms);
  return 0;
}

const CommandRegistration kRegister({"simplify", "simplify a model by vertex clustering (one level)", kUsage.c_str(),
                                     &runSimplify});

}  // namespace

}  // namespace scenelod::tool
