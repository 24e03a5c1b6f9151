// scenelod lods: a chain of vertex-clustering levels (Low & Tan 1997 §3.2.2: every level from the
// original, cell widths doubling) of a whole model in world space, with a table of the levels.
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "args.h"
#include "cluster_options.h"
#include "command.h"
#include "progress.h"
#include "scrooge_options.h"
#include "scenelod/scene/gltf_io.h"

namespace scenelod::tool {

namespace {

const std::string kUsage = std::string(
    "usage: scenelod lods IN -o OUT [--levels N] [--cell W1 | --cell-rel F] [--method M] [--grading G]\n"
    "                     [--synthesis S] [--cell-shape C] [--split]\n"
    "\n"
    "Builds an LOD chain of IN (.obj, .gltf, .glb; the whole model in world space): level 0 is the\n"
    "original, levels 1..N use cell widths w_k = w_1 x 2^(k-1), each derived from the original. Prints\n"
    "a table of the levels. OUT.glb holds the chain with MSFT_lod; with --split, or for OUT.obj, every\n"
    "level is written to its own file OUT-level<k>.<ext>.\n"
    "\n"
    "  --levels N    simplified levels (default 8)\n"
    "  --cell W1     first cell width, object space (default: level 1 has about half the triangles)\n"
    "  --cell-rel F  first cell width as F x the bounding-box diagonal\n"
    "  --split       one file per level\n") +
    kClusterOptionsHelp + kScroogeOptionsHelp;

int runLods(const std::vector<std::string>& argv) {
  std::vector<std::string> options = clusterOptionNames();
  for (const char* o : {"--out", "--levels", "--cell", "--cell-rel"}) options.push_back(o);
  for (const std::string& o : scroogeOptionNames()) options.push_back(o);
  Args args(argv, {"--split"}, options);
  if (!args.ok()) return usageError("lods", args.error());
  if (args.positional().size() != 1) return usageError("lods", "expected one input file");
  if (!args.has("--out")) return usageError("lods", "missing -o OUT");
  const std::string in = args.positional()[0], out = args.get("--out");
  const std::string ext = fileExtension(out);
  if (ext != ".obj" && ext != ".glb") return usageError("lods", "the output must end in .obj or .glb: " + out);
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
  long levels = 8;
  double cell = 0.0, rel = 0.0;
  if (args.has("--levels") && (!args.getInt("--levels", levels) || levels < 0 || levels > 64))
    return usageError("lods", args.ok() ? "--levels must be an integer from 0 to 64" : args.error());
  if (args.has("--cell") && (!args.getDouble("--cell", cell) || !(cell > 0.0)))
    return usageError("lods", args.ok() ? "--cell must be a finite number > 0" : args.error());
  if (args.has("--cell-rel") && (!args.getDouble("--cell-rel", rel) || !(rel > 0.0)))
    return usageError("lods", args.ok() ? "--cell-rel must be a finite number > 0" : args.error());
  cp.level_count = size_t(levels);

  Mesh mesh;
  if (Error e = loadWorldMesh(in, mesh)) return runError("lods", e.message);
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
  const auto t0 = std::chrono::steady_clock::now();
  if (Error e = scrooge ? buildScroogeChain(mesh, cp, sp, chain) : buildChain(mesh, cp, chain, &stats))
    return runError("lods", in + ": " + e.message);
  if (scrooge) stats.total_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
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
    if (Error e = scene::exportGlb(out, s, &chains)) return runError("lods", e.message);
    std::printf("wrote %s (%zu levels, MSFT_lod)\n", out.c_str(), chain.levelCount());
  } else {
    for (size_t k = 1; k < chain.levelCount(); ++k) {
      const std::string path = stem + "-level" + std::to_string(k) + ext;
      if (Error e = writeMeshFile(path, chain.levels[k].mesh, "level" + std::to_string(k)))
        return runError("lods", e.message);
    }
    std::printf("wrote %s-level1%s .. %s-level%zu%s\n", stem.c_str(), ext.c_str(), stem.c_str(),
                chain.levelCount() - 1, ext.c_str());
  }
  if (scrooge)
    std::printf("%s: method scrooge, theta %g..%g deg; cell width = sub-volume edge, max error = largest vertex move\n",
                in.c_str(), double(sp.theta_min_deg), double(sp.theta_max_deg));
  else
    std::printf("%s: method %s, grading %s, synthesis %s, cells %s\n", in.c_str(), lodMethodName(cp.cluster.method),
                gradingName(cp.cluster.grading), synthesisName(cp.cluster.synthesis), cellShapeName(cp.cluster.cell_shape));
  printLevelTable(chain, scrooge ? nullptr : &stats);
  std::printf("time: grading and sort %.1f ms, w1 search %.1f ms, whole chain %.1f ms (levels in parallel)\n",
              stats.prepare_seconds * 1e3, stats.first_width_seconds * 1e3, stats.total_seconds * 1e3);
  return 0;
}

const CommandRegistration kRegister({"lods", "build a vertex-clustering LOD chain and print its levels", kUsage.c_str(),
                                     &runLods});

}  // namespace

}  // namespace scenelod::tool
