// scenelod record: writes a replay file from a scripted camera path over a scene.
#include <cstdio>
#include <string>
#include <vector>

#include "args.h"
#include "command.h"
#include "scenelod/selection/camera_path.h"
#include "scenelod/selection/replay.h"
#include "scenelod/selection/replay_scene.h"

namespace scenelod::tool {
namespace {

using namespace scenelod::selection;

const char kUsage[] =
    "usage: scenelod record SCENE --path orbit|flythrough|approach --frames N -o REPLAY [options]\n"
    "\n"
    "Writes a replay (docs/REPLAY.md) whose camera follows a scripted path fitted to the scene's\n"
    "bounds. SCENE is a .gltf/.glb/.obj file, a LOD pack (.slodpack), a level-scene .json or\n"
    "builtin:small|city|field. The replay names SCENE relative to the replay's folder.\n"
    "\n"
    "options:\n"
    "  --path NAME          orbit, flythrough or approach (default orbit)\n"
    "  --frames N           frame count (default 300)\n"
    "  --fps F              frames per second of time_s (default 60)\n"
    "  --budget MS          budget in the header (default: none, distance mode)\n"
    "  --viewport W H       default 1280 720\n"
    "  --fov DEG            vertical field of view (default 60)\n"
    "  --pixels-per-cell X  default 1\n"
    "  --from R             approach: start R scene radii from the centre (default 3, > 0.15)\n"
    "  -o, --out FILE       the replay to write";

std::string relativeTo(const std::string& from_file, const std::string& path) {
  if (path.rfind("builtin:", 0) == 0) return path;
  // absolute scene path unless both are relative to the same folder
  const size_t slash = from_file.find_last_of('/');
  const std::string dir = slash == std::string::npos ? std::string() : from_file.substr(0, slash + 1);
  if (!dir.empty() && path.rfind(dir, 0) == 0) return path.substr(dir.size());
  if (dir.empty() && path[0] != '/') return path;
  if (path[0] == '/') return path;
  char buf[4096];
  if (realpath(path.c_str(), buf)) return buf;
  return path;
}

int run(const std::vector<std::string>& argv) {
  std::vector<std::string> a = argv;
  // --viewport takes two values: join them
  for (size_t i = 0; i + 2 < a.size(); ++i)
    if (a[i] == "--viewport") {
      a[i + 1] = a[i + 1] + "x" + a[i + 2];
      a.erase(a.begin() + static_cast<long>(i) + 2);
    }
  Args args(a, {}, {"--out", "--path", "--frames", "--fps", "--budget", "--viewport", "--fov", "--pixels-per-cell", "--from"});
  if (!args.ok()) return usageError("record", args.error());
  if (args.positional().size() != 1) return usageError("record", "expected one scene");
  if (!args.has("--out")) return usageError("record", "missing -o REPLAY");
  CameraPathKind kind;
  if (!parseCameraPathKind(args.get("--path", "orbit"), kind)) return usageError("record", "--path must be orbit, flythrough or approach");
  long frames = 300;
  double fps = 60.0, budget = 0.0, fov = 60.0, ppc = 1.0, from = 3.0;
  if (!args.getInt("--frames", frames) || !args.getDouble("--fps", fps) || !args.getDouble("--budget", budget) ||
      !args.getDouble("--fov", fov) || !args.getDouble("--pixels-per-cell", ppc) || !args.getDouble("--from", from))
    return usageError("record", args.error());
  if (frames < 1 || frames > 10000000) return usageError("record", "--frames must be 1..10000000");
  if (!(fps > 0.0)) return usageError("record", "--fps must be > 0");
  if (args.has("--budget") && !(budget > 0.0)) return usageError("record", "--budget must be > 0");
  if (!(fov > 0.0 && fov < 180.0)) return usageError("record", "--fov must be in (0, 180)");
  if (!(ppc > 0.0)) return usageError("record", "--pixels-per-cell must be > 0");
  if (!(from > 0.15 && from < 1e6)) return usageError("record", "--from must be in (0.15, 1e6) scene radii");
  if (args.has("--from") && kind != CameraPathKind::kApproach) return usageError("record", "--from applies to --path approach");
  Replay replay;
  if (args.has("--viewport")) {
    unsigned w = 0, h = 0;
    char extra;
    if (std::sscanf(args.get("--viewport").c_str(), "%ux%u%c", &w, &h, &extra) != 2 || w < 1 || h < 1 || w > 65536 || h > 65536)
      return usageError("record", "--viewport needs two whole numbers W H");
    replay.header.viewport_width_px = w;
    replay.header.viewport_height_px = h;
  }
  const std::string scene_path = args.positional()[0];
  ReplayScene scene;
  if (Error e = loadReplayScene(scene_path, scene); !e.ok()) return runError("record", e.message);
  const std::string out = args.get("--out");
  replay.header.scene = relativeTo(out, scene_path);
  replay.header.fov_y_deg = fov;
  replay.header.pixels_per_cell = ppc;
  replay.header.has_budget = args.has("--budget");
  replay.header.budget_ms = budget;
  makeCameraPath(sceneBounds(scene), kind, static_cast<size_t>(frames), fps, replay, from);
  if (Error e = writeReplay(out, replay); !e.ok()) return runError("record", e.message);
  std::printf("wrote %s: %ld frames over %s (%zu objects)\n", out.c_str(), frames, scene_path.c_str(), scene.objectCount());
  return 0;
}

const CommandRegistration kRegistration({"record", "write a replay from a scripted camera path", kUsage, run});

}  // namespace
}  // namespace scenelod::tool
