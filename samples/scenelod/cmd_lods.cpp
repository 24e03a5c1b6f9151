// scenelod lods: a chain of vertex-clustering levels (Low & Tan 1997 §3.2.2: every level from the
// original, cell widths doubling) of a whole model in world space, with a table of the levels.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "args.h"
#include "cluster_options.h"
#include "command.h"
#include "zhang_options.h"
#include "progress.h"
#include "scrooge_options.h"
#include "scenelod/scene/gltf_io.h"
#include "scenelod/scene/lod_build.h"

namespace scenelod::tool {

namespace {

const std::string kUsage = std::string(
    "usage: scenelod lods IN -o OUT [--levels N] [--cell W1 | --cell-rel F] [--method M] [--grading G]\n"
    "                     [--synthesis S] [--cell-shape C] [--nested | --independent] [--split]\n"
    "\n"
    "Builds LOD chains of IN (.obj, .gltf, .glb): level 0 is the original, levels 1..N use cell widths\n"
    "w_k = w_1 x 2^(k-1), each derived from the original.\n"
    "OUT.glb or OUT.gltf: the scene with every unique mesh's chain (meshes in parallel, object space),\n"
    "each mesh node written with MSFT_lod (the full node first, then the coarser level nodes) and\n"
    "extras.MSFT_screencoverage; prints the levels summed over the scene and a table per mesh. For a\n"
    "glTF input, OUT is IN with the levels added: materials, textures, images, skins, animations,\n"
    "cameras, lights, extras and extensions are kept, and level 0 is IN's mesh unchanged (docs/IO.md).\n"
    "OUT may be IN for a .glb (written only once everything succeeded); OUT.gltf writes OUT.bin and\n"
    "the images beside it.\n"
    "With --flatten, --split or for OUT.obj: one chain of the whole model in world space; --split and\n"
    "OUT.obj write every level to its own file OUT-level<k>.<ext>; prints the table of the levels.\n"
    "\n"
    "  --levels N    simplified levels (default 8)\n"
    "  --cell W1     first cell width, object space (default: level 1 has about half the triangles)\n"
    "  --cell-rel F  first cell width as F x the bounding-box diagonal\n"
    "  --nested      clustering: each level clusters the level before, so that its geomorph ends\n"
    "                exactly on the next level (docs/CLUSTERING.md, \"Nested or independent levels\")\n"
    "  --independent clustering: each level clusters the original\n"
    "  --split       one file per level (the whole model in world space)\n"
    "  --flatten     OUT.glb holds one chain of the whole model in world space\n"
    "  --thick-edges prisms|lines  glTF input: a level's thick edges as 3-sided prisms and its points\n"
    "                as octahedra, triangles any viewer draws (prisms, the default), or as LINES with\n"
    "                _THICKNESS and POINTS, for engines drawing through scenelod's adapter (lines)\n") +
    kClusterOptionsHelp + kZhangOptionsHelp +
    "  zhang levels halve the triangle count; their cell width is 2 x d / sqrt(3), d a bound of the\n"
    "  original vertices' distance to the level (docs/ZHANG.md)\n" +
    kScroogeOptionsHelp +
    "  scrooge levels in OUT.glb without --split/--flatten are per mesh in object space: --cell-rel only\n";

// every unique mesh's chain in object space, written as one GLB with MSFT_lod per mesh node
int runSceneLods(const std::string& in, const std::string& out, const ChainParams& cp, float cell, float rel,
                 scene::ThickEdges thick_edges) {
  scene::SceneData s;
  if (Error e = scene::loadScene(in, s); !e.ok()) return runError("lods", e.message);
  const std::string in_ext = scene::lowerExtension(in);
  const bool pass_through = in_ext == ".glb" || in_ext == ".gltf";
  if (!pass_through) scene::bakeMaterialColors(s);  // an OBJ's levels are written with their colours
  if (!pass_through && scene::lowerExtension(out) == ".gltf")
    return usageError("lods", "a .gltf output needs a glTF input (" + in + " is not one): write a .glb");
  scene::LodBuildParams params;
  params.chain = cp;
  params.chain.first_cell_width = cell;
  params.first_cell_rel = rel;
  ProgressBar bar("lods");
  params.progress = bar.callback();
  scene::SceneLods lods;
  if (Error e = scene::buildLods(s, params, lods, nullptr, in); !e.ok()) return runError("lods", e.message);
  bar.finish();
  std::vector<const LodChain*> chains;
  for (const LodChain& c : lods.chains) chains.push_back(&c);
  std::vector<std::string> notes;
  const Error written =
      pass_through ? scene::exportGltfLods(in, out, s, chains, &notes, thick_edges) : scene::exportGlb(out, s, &chains);
  if (!written.ok()) return runError("lods", written.message);
  for (const std::string& note : notes) std::printf("%s: %s\n", in.c_str(), note.c_str());

  const std::vector<int32_t> objects = scene::objectNodes(s);
  std::vector<size_t> instances(s.meshes.size(), 0);
  for (int32_t n : objects) ++instances[s.nodes[n].mesh];
  size_t max_levels = 0, total_levels = 0;
  for (const LodChain& c : lods.chains) {
    max_levels = std::max(max_levels, c.levelCount());
    total_levels += c.levelCount();
  }
  std::printf("wrote %s (%zu objects, %zu unique meshes, %zu levels, MSFT_lod%s)\n", out.c_str(), objects.size(),
              s.meshes.size(), total_levels, pass_through ? "; everything else of the input kept" : "");
  std::printf("%s: method %s, grading %s, synthesis %s, cells %s; chains in object space\n", in.c_str(),
              lodMethodName(cp.cluster.method), gradingName(cp.cluster.grading), synthesisName(cp.cluster.synthesis),
              cellShapeName(cp.cluster.cell_shape));
  // the scene's levels: drawn counts (instances counted) when every object shows level k (its last
  // level when its chain is shorter)
  std::printf("%5s %8s %12s %12s %10s %10s %12s\n", "level", "meshes", "vertices", "triangles", "edges", "points",
              "max error");
  for (size_t k = 0; k < max_levels; ++k) {
    size_t meshes = 0, v = 0, t = 0, e = 0, p = 0;
    float err = 0.0f;
    for (size_t m = 0; m < s.meshes.size(); ++m) {
      const LodChain& c = lods.chains[m];
      if (c.empty()) continue;
      if (k < c.levelCount()) ++meshes;
      const LodLevel& l = c.levels[std::min(k, c.levelCount() - 1)];
      v += instances[m] * l.mesh.vertexCount();
      t += instances[m] * l.mesh.triangleCount();
      e += instances[m] * l.mesh.edgeCount();
      p += instances[m] * l.mesh.pointCount();
      err = std::max(err, l.max_error);
    }
    std::printf("%5zu %8zu %12zu %12zu %10zu %10zu %12.6g\n", k, meshes, v, t, e, p, double(err));
  }
  std::printf("\n%-5s %-28s %9s %6s %10s %10s %9s\n", "mesh", "name", "instances", "levels", "tris L0", "tris last",
              "time ms");
  const size_t shown = std::min<size_t>(s.meshes.size(), 40);
  for (size_t m = 0; m < shown; ++m) {
    const LodChain& c = lods.chains[m];
    const std::string name = s.meshes[m].name.size() > 28 ? s.meshes[m].name.substr(0, 25) + "..." : s.meshes[m].name;
    std::printf("%-5zu %-28s %9zu %6zu %10zu %10zu %9.1f\n", m, name.c_str(), instances[m], c.levelCount(),
                c.empty() ? size_t(0) : c.levels.front().mesh.triangleCount(),
                c.empty() ? size_t(0) : c.levels.back().mesh.triangleCount(), lods.build_seconds[m] * 1e3);
  }
  if (shown < s.meshes.size()) std::printf("... %zu more meshes\n", s.meshes.size() - shown);
  std::printf("time: whole scene %.1f ms (meshes in parallel)\n", lods.total_seconds * 1e3);
  return 0;
}

int runLods(const std::vector<std::string>& argv) {
  std::vector<std::string> options = clusterOptionNames();
  for (const char* o : {"--out", "--levels", "--cell", "--cell-rel", "--thick-edges"}) options.push_back(o);
  for (const std::string& o : zhangOptionNames()) options.push_back(o);
  for (const std::string& o : scroogeOptionNames()) options.push_back(o);
  Args args(argv, {"--split", "--flatten", "--nested", "--independent"}, options);
  if (!args.ok()) return usageError("lods", args.error());
  if (args.positional().size() != 1) return usageError("lods", "expected one input file");
  if (!args.has("--out")) return usageError("lods", "missing -o OUT");
  const std::string in = args.positional()[0], out = args.get("--out");
  const std::string ext = scene::lowerExtension(out);
  if (ext != ".obj" && ext != ".glb" && ext != ".gltf")
    return usageError("lods", "the output must end in .obj, .glb or .gltf: " + out);
  if (ext == ".gltf" && (args.has("--split") || args.has("--flatten")))
    return usageError("lods", "--split and --flatten write .glb or .obj files, not .gltf");
  if (args.has("--cell") && args.has("--cell-rel")) return usageError("lods", "give only one of --cell, --cell-rel");
  ChainParams cp;
  std::string err;
  const bool scrooge = isScroogeMethod(args);
  ScroogeParams sp;
  if (scrooge) {
    if (!parseScroogeOptions(args, sp, err)) return usageError("lods", err);
    cp.cluster.method = LodMethod::kScrooge;
  } else if (!parseClusterOptions(args, cp.cluster, err)) {
    return usageError("lods", err);
  } else if (args.has("--subvolume") || args.has("--theta-max")) {
    return usageError("lods", "--subvolume and --theta-max need --method scrooge");
  }
  ZhangParams zp;
  if (!parseZhangOptions(args, zp, err)) return usageError("lods", err);
  if (cp.cluster.method == LodMethod::kZhang && (args.has("--cell") || args.has("--cell-rel")))
    return usageError("lods", "--method zhang chooses its levels by triangle count, not --cell or --cell-rel");
  long levels = 8;
  double cell = 0.0, rel = 0.0;
  if (args.has("--levels") && (!args.getInt("--levels", levels) || levels < 0 || levels > 64))
    return usageError("lods", args.ok() ? "--levels must be an integer from 0 to 64" : args.error());
  if (args.has("--cell") && (!args.getDouble("--cell", cell) || !(cell > 0.0)))
    return usageError("lods", args.ok() ? "--cell must be a finite number > 0" : args.error());
  if (args.has("--cell-rel") && (!args.getDouble("--cell-rel", rel) || !(rel > 0.0)))
    return usageError("lods", args.ok() ? "--cell-rel must be a finite number > 0" : args.error());
  cp.level_count = size_t(levels);
  if (std::string nerr; !parseNesting(args, cp, nerr)) return usageError("lods", nerr);
  const std::string thick = args.get("--thick-edges", "prisms");
  if (thick != "prisms" && thick != "lines")
    return usageError("lods", "--thick-edges takes prisms or lines, not '" + thick + "'");
  const scene::ThickEdges thick_edges = thick == "lines" ? scene::ThickEdges::kLines : scene::ThickEdges::kPrisms;
  if (ext != ".obj" && !args.has("--split") && !args.has("--flatten")) {
    for (const std::string& o : zhangOptionNames())  // per-mesh chains go through buildChain's defaults
      if (args.has(o)) return usageError("lods", o + " needs --flatten or --split (per-mesh chains use the zhang defaults)");
    if (scrooge && (args.has("--subvolume") || args.has("--theta-max")))
      return usageError("lods", "per-mesh scrooge chains take --cell or --cell-rel; use --flatten or --split for "
                                "--subvolume and --theta-max");
    // scrooge: --cell-rel F is the sub-volume diagonal, so the cube edge is F / sqrt(3) x the diagonal
    return runSceneLods(in, out, cp, float(cell), float(scrooge ? rel / std::sqrt(3.0) : rel), thick_edges);
  }

  Mesh mesh;
  if (Error e = loadWorldMesh(in, mesh); !e.ok()) return runError("lods", e.message);
  if (scrooge) {  // --cell-rel F: sub-volume diagonal = F x bbox diagonal; --subvolume 1/64|1/8|1
    float w = 0.0f;
    if (!scroogeFirstWidth(args, mesh, w, err)) return usageError("lods", in + ": " + err);
    cell = w;
  } else if (rel > 0.0) {
    cell = rel * double(computeBounds(mesh).diagonal());
  }
  cp.first_cell_width = float(cell);
  ProgressBar bar("lods");
  cp.progress = bar.callback();
  LodChain chain;
  ChainStats stats;
  const auto t_build = std::chrono::steady_clock::now();
  const Error built = cp.cluster.method == LodMethod::kZhang ? buildZhangChain(mesh, cp, zp, chain)
                      : scrooge                             ? buildScroogeChain(mesh, cp, sp, chain)
                                                            : buildChain(mesh, cp, chain, &stats);
  if (cp.cluster.method == LodMethod::kZhang || scrooge)  // one run for all levels: only the total is known
    stats.total_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_build).count();
  if (!built.ok()) return runError("lods", in + ": " + built.message);
  bar.finish();

  const std::string stem = out.substr(0, out.size() - ext.size());
  if (ext == ".glb" && !args.has("--split")) {
    scene::SceneData s;
    scene::MeshData md;
    md.name = "model";
    md.mesh = chain.levels[0].mesh;
    s.meshes.push_back(std::move(md));
    scene::NodeData node;
    node.name = "model";
    node.mesh = 0;
    s.nodes.push_back(node);
    s.roots.push_back(0);
    std::vector<const LodChain*> chains{&chain};
    if (Error e = scene::exportGlb(out, s, &chains); !e.ok()) return runError("lods", e.message);
    std::printf("wrote %s (%zu levels, MSFT_lod)\n", out.c_str(), chain.levelCount());
  } else {
    for (size_t k = 1; k < chain.levelCount(); ++k) {
      const std::string path = stem + "-level" + std::to_string(k) + ext;
      if (Error e = writeMeshFile(path, chain.levels[k].mesh, "level" + std::to_string(k)); !e.ok())
        return runError("lods", e.message);
    }
    std::printf("wrote %s-level1%s .. %s-level%zu%s\n", stem.c_str(), ext.c_str(), stem.c_str(),
                chain.levelCount() - 1, ext.c_str());
  }
  if (scrooge) {
    std::printf("%s: method scrooge, theta %g..%g deg; cell width = sub-volume edge, max error = largest vertex move\n",
                in.c_str(), double(sp.theta_min_deg), double(sp.theta_max_deg));
  } else if (cp.cluster.method == LodMethod::kZhang) {
    std::printf("%s: method zhang (%s, placement %s, influence %s)\n", in.c_str(), zhangModeName(zp.mode),
                zhangPlacementName(zp.placement), zhangInfluenceName(zp.influence));
  } else {
    std::printf("%s: method %s, grading %s, synthesis %s, cells %s\n", in.c_str(), lodMethodName(cp.cluster.method),
                gradingName(cp.cluster.grading), synthesisName(cp.cluster.synthesis),
                cellShapeName(cp.cluster.cell_shape));
  }
  printLevelTable(chain, &stats);
  std::printf("time: grading and sort %.1f ms, w1 search %.1f ms (%zu probe%s), whole chain %.1f ms (levels in parallel)\n",
              stats.prepare_seconds * 1e3, stats.first_width_seconds * 1e3, stats.first_width_probes,
              stats.first_width_probes == 1 ? "" : "s", stats.total_seconds * 1e3);
  return 0;
}

const CommandRegistration kRegister({"lods", "build a vertex-clustering LOD chain and print its levels", kUsage.c_str(),
                                     &runLods});

}  // namespace

}  // namespace scenelod::tool
