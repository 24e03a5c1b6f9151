// scenelod pack: precompute every unique mesh's LOD chain of a scene and write a LOD pack; or check
// a pack and time its loading.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "args.h"
#include "cluster_options.h"
#include "command.h"
#include "progress.h"
#include "scenelod/scene/demo_scene.h"
#include "scenelod/scene/gltf_io.h"
#include "scenelod/scene/lod_build.h"
#include "scenelod/scene/pack.h"

namespace scenelod::tool {

namespace {

const std::string kUsage = std::string(
    "usage: scenelod pack IN -o OUT.slodpack [--levels N] [--no-order] [cluster options]\n"
    "       scenelod pack --demo -o OUT.slodpack [...]\n"
    "       scenelod pack --check PACK.slodpack\n"
    "\n"
    "Builds the LOD chain of every unique mesh of IN (.obj, .gltf, .glb) in parallel, each level from\n"
    "the original with cell widths doubling, and writes a LOD pack: the scene's nodes, objects and\n"
    "transforms and every chain, ordered for the vertex cache and vertex fetch (docs/SCENE.md), and\n"
    "each level's material of every triangle group, edge and point, the materials referring to IN.\n"
    "Prints a table per mesh, the totals, and the time to load the pack back.\n"
    "\n"
    "  -o, --out FILE  the pack to write\n"
    "  --demo          use the built-in demo scene instead of IN\n"
    "  --levels N      simplified levels per chain (default 8)\n"
    "  --no-order      keep the levels' triangle and vertex order (no vertex cache optimisation)\n"
    "  --check PACK    load PACK (all checks), print what it holds and the load time\n") +
    kClusterOptionsHelp;

double millisecondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// best of `repeats` loads: the first one also pays for the page cache
double timeLoad(const std::string& path, int repeats, Error& error) {
  double best = 1e30;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    scene::Pack p;
    error = scene::Pack::load(path, p);
    if (!error.ok()) return 0.0;
    best = std::min(best, millisecondsSince(t0));
  }
  return best;
}

int runCheck(const std::string& path) {
  scene::Pack p;
  if (Error e = scene::Pack::load(path, p); !e.ok()) return runError("pack", e.message);
  size_t levels = 0, tris = 0;
  for (size_t c = 0; c < p.chainCount(); ++c) {
    levels += p.levelCount(c);
    for (size_t l = 0; l < p.levelCount(c); ++l) tris += p.level(c, l).triangles.size() / 3;
  }
  Error e;
  const double ms = timeLoad(path, 5, e);
  if (!e.ok()) return runError("pack", e.message);
  std::printf("%s: %zu bytes, %zu nodes, %zu objects, %zu chains, %zu levels, %zu triangles over all levels\n",
              path.c_str(), p.byteSize(), p.nodeCount(), p.objectCount(), p.chainCount(), levels, tris);
  if (p.materialCount() > 0) {
    std::printf("%zu materials of %s:", p.materialCount(), p.material(0).source);
    for (size_t i = 0; i < p.materialCount(); ++i) std::printf("%s '%s'", i ? "," : "", p.material(i).name);
    std::printf("\n");
  }
  std::printf("load (one read + checks, best of 5): %.2f ms\n", ms);
  return 0;
}

int runPack(const std::vector<std::string>& argv) {
  std::vector<std::string> options = clusterOptionNames();
  for (const char* o : {"--out", "--levels", "--check"}) options.push_back(o);
  Args args(argv, {"--demo", "--no-order"}, options);
  if (!args.ok()) return usageError("pack", args.error());
  if (args.has("--check")) {
    if (!args.positional().empty() || args.has("--out")) return usageError("pack", "--check takes only the pack");
    return runCheck(args.get("--check"));
  }
  const bool demo = args.has("--demo");
  if (demo != args.positional().empty()) return usageError("pack", "expected one input file, or --demo");
  if (!args.has("--out")) return usageError("pack", "missing -o OUT.slodpack");
  const std::string out = args.get("--out");
  scene::LodBuildParams params;
  std::string err;
  if (!parseClusterOptions(args, params.chain.cluster, err)) return usageError("pack", err);
  long levels = 8;
  if (args.has("--levels") && (!args.getInt("--levels", levels) || levels < 0 || levels > 64))
    return usageError("pack", args.ok() ? "--levels must be an integer from 0 to 64" : args.error());
  params.chain.level_count = size_t(levels);

  const std::string in = demo ? std::string("demo scene") : args.positional()[0];
  scene::SceneData s;
  if (demo) {
    scene::DemoSceneInfo info;
    if (Error e = scene::makeDemoScene(s, {}, &info); !e.ok()) return runError("pack", e.message);
    std::fprintf(stderr, "%s\n", info.note.c_str());
  } else if (Error e = scene::loadScene(in, s); !e.ok()) {
    return runError("pack", e.message);
  }
  ProgressBar bar("pack");
  params.progress = bar.callback();
  scene::SceneLods lods;
  if (Error e = scene::buildLods(s, params, lods, nullptr, in); !e.ok()) return runError("pack", e.message);
  bar.finish();

  scene::PackWriteOptions wo;
  wo.optimize_order = !args.has("--no-order");
  if (!demo) {
    // where the full materials (textures, ...) are, as seen from the pack's folder
    std::error_code ec;
    const std::filesystem::path pack_dir = std::filesystem::absolute(out, ec).lexically_normal().parent_path();
    const std::filesystem::path rel = std::filesystem::absolute(in, ec).lexically_normal().lexically_relative(pack_dir);
    wo.material_source = rel.empty() ? in : rel.generic_string();
  }
  scene::PackWriteStats stats;
  const auto t_write = std::chrono::steady_clock::now();
  if (Error e = scene::writePack(out, s, lods.chains, lods.chain_spheres, wo, &stats); !e.ok()) return runError("pack", e.message);
  const double write_ms = millisecondsSince(t_write);

  const std::vector<int32_t> objects = scene::objectNodes(s);
  std::vector<size_t> instances(s.meshes.size(), 0);
  for (int32_t n : objects) ++instances[s.nodes[n].mesh];
  std::printf("%-5s %-24s %9s %6s %10s %10s %10s\n", "mesh", "name", "instances", "levels", "tris L0", "tris last",
              "build ms");
  size_t total_levels = 0;
  for (size_t m = 0; m < s.meshes.size(); ++m) {
    const LodChain& c = lods.chains[m];
    total_levels += c.levelCount();
    const std::string name = s.meshes[m].name.size() > 24 ? s.meshes[m].name.substr(0, 21) + "..." : s.meshes[m].name;
    std::printf("%-5zu %-24s %9zu %6zu %10zu %10zu %10.1f\n", m, name.c_str(), instances[m], c.levelCount(),
                c.levels.empty() ? size_t(0) : c.levels.front().mesh.triangleCount(),
                c.levels.empty() ? size_t(0) : c.levels.back().mesh.triangleCount(), lods.build_seconds[m] * 1e3);
  }
  Error load_error;
  const double load_ms = timeLoad(out, 5, load_error);
  if (!load_error.ok()) return runError("pack", "the pack just written does not load: " + load_error.message);
  std::printf("%s: %zu objects, %zu unique meshes, %zu levels\n", in.c_str(), objects.size(), s.meshes.size(), total_levels);
  std::printf("precompute %.1f ms (meshes in parallel), write %.1f ms\n", lods.total_seconds * 1e3, write_ms);
  std::printf("wrote %s: %zu bytes; ACMR (FIFO 16) %.3f -> %.3f\n", out.c_str(), stats.bytes, stats.acmr_before,
              stats.acmr_after);
  std::printf("load (one read + checks, best of 5): %.2f ms\n", load_ms);
  return 0;
}

const CommandRegistration kRegister({"pack", "precompute a scene's LOD chains into a LOD pack (or --check one)",
                                     kUsage.c_str(), &runPack});

}  // namespace

}  // namespace scenelod::tool
