// scenelod demo: the main job end to end on the built-in scene: build it, precompute its chains,
// record a fly-through, replay it in distance mode and under a budget, and write the report.
#include <cstdio>
#include <string>
#include <vector>

#include "args.h"
#include "command.h"
#include "progress.h"
#include "replay_demo.h"
#include "scenelod/scene/demo_scene.h"
#include "scenelod/scene/lod_build.h"
#include "scenelod/selection/replay_scene.h"

namespace scenelod::tool {
namespace {

const char kUsage[] =
    "usage: scenelod demo [-o DIR] [--frames N]\n"
    "\n"
    "Builds the built-in scene (CAD-like parts and bunnies), precomputes every mesh's LOD chain,\n"
    "records a fly-through, replays it in distance mode and under a budget (synthetic renderer),\n"
    "and writes DIR/demo_report.md with its plots (default DIR: scenelod-demo).\n"
    "\n"
    "options:\n"
    "  -o, --out DIR   output folder (default scenelod-demo)\n"
    "  --frames N      frames of the fly-through (default 600)";

int run(const std::vector<std::string>& argv) {
  Args args(argv, {}, {"--out", "--frames"});
  if (!args.ok()) return usageError("demo", args.error());
  if (!args.positional().empty()) return usageError("demo", "unexpected argument '" + args.positional()[0] + "'");
  long frames = 600;
  if (!args.getInt("--frames", frames)) return usageError("demo", args.error());
  if (frames < 31 || frames > 100000) return usageError("demo", "--frames must be in 31..100000");
  const std::string out = args.get("--out", "scenelod-demo");

  scene::SceneData data;
  scene::DemoSceneInfo info;
  if (Error e = scene::makeDemoScene(data, scene::DemoSceneParams(), &info)) return runError("demo", e.message);
  if (!info.note.empty()) std::printf("%s\n", info.note.c_str());
  scene::SceneLods lods;
  {
    ProgressBar bar("precompute");
    scene::LodBuildParams params;
    params.progress = bar.callback();
    if (Error e = scene::buildLods(data, params, lods, nullptr, "demo scene")) return runError("demo", e.message);
  }
  size_t triangles = 0, levels = 0;
  for (const auto& c : lods.chains) {
    levels += c.levelCount();
    if (!c.empty()) triangles += c.levels[0].mesh.triangleCount();
  }
  selection::ReplayScene scene;
  if (Error e = selection::replaySceneFromSceneData(data, lods.chains, "demo scene", scene, &lods.chain_spheres))
    return runError("demo", e.message);
  std::printf("demo scene: %zu objects, %zu unique meshes (%zu triangles), %zu levels, precomputed in %.2f s\n",
              scene.objectCount(), lods.chains.size(), triangles, levels, lods.total_seconds);
  SelectionDemoResult result;
  if (Error e = runSelectionDemo(scene, out, static_cast<size_t>(frames), result)) return runError("demo", e.message);
  std::printf("report: %s\n", result.report_path.c_str());
  for (const auto& l : result.summary_lines) std::printf("  %s\n", l.c_str());
  return 0;
}

const CommandRegistration kRegistration({"demo", "the main job end to end on the built-in scene, with a report", kUsage, run});

}  // namespace
}  // namespace scenelod::tool
