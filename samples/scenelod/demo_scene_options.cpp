#include "demo_scene_options.h"

namespace scenelod::tool {

const char kDemoSceneOptionsHelp[] =
    "  --bunny PATH        the bunny OBJ (default /usr/share/glmark2/models/bunny.obj; when it cannot\n"
    "                      be read a generated organic blob stands in, and the tool says so)\n"
    "  --gearboxes N       gear sub-assemblies (default 4)\n"
    "  --bunnies N         bunny instances (default 4)\n"
    "  --segments N        tessellation of round parts (default 48, >= 3)";

bool readDemoSceneOptions(Args& args, scene::DemoSceneParams& p, std::string& error) {
  long gearboxes = long(p.gearbox_count), bunnies = long(p.bunny_count), segments = long(p.segments);
  if (!args.getInt("--gearboxes", gearboxes) || !args.getInt("--bunnies", bunnies) ||
      !args.getInt("--segments", segments)) {
    error = args.error();
    return false;
  }
  if (gearboxes < 1 || gearboxes > 1000) error = "--gearboxes must be in 1..1000";
  else if (bunnies < 0 || bunnies > 1000) error = "--bunnies must be in 0..1000";
  else if (segments < 3 || segments > 4096) error = "--segments must be in 3..4096";
  if (!error.empty()) return false;
  p.gearbox_count = size_t(gearboxes);
  p.bunny_count = size_t(bunnies);
  p.segments = size_t(segments);
  if (args.has("--bunny")) p.bunny_path = args.get("--bunny");
  return true;
}

}  // namespace scenelod::tool
