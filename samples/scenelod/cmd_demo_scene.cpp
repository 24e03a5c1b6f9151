// scenelod demo-scene: writes the built-in default scene (CAD parts and bunny instances) as a GLB.
#include <cstdio>
#include <string>
#include <vector>

#include "args.h"
#include "command.h"
#include "scenelod/scene/demo_scene.h"
#include "scenelod/scene/gltf_io.h"

namespace scenelod::tool {

namespace {

const char kUsage[] =
    "usage: scenelod demo-scene -o FILE.glb [options]\n"
    "\n"
    "Writes the built-in default scene: a CAD-like assembly of simple polyhedra (gears, shafts, bolts,\n"
    "brackets, pipes, prisms, a base plate, thin fins and rods that collapse into thick edges) and\n"
    "instances of the Stanford bunny, with meshes shared between instances. Deterministic.\n"
    "\n"
    "  -o, --out FILE.glb  the output file\n"
    "  --bunny PATH        the bunny OBJ (default /usr/share/glmark2/models/bunny.obj; when it cannot\n"
    "                      be read a generated organic blob stands in, and the tool says so)\n"
    "  --gearboxes N       gear sub-assemblies (default 4)\n"
    "  --bunnies N         bunny instances (default 4)\n"
    "  --segments N        tessellation of round parts (default 48, >= 3)";

int runDemoScene(const std::vector<std::string>& argv) {
  Args args(argv, {}, {"--out", "--bunny", "--gearboxes", "--bunnies", "--segments"});
  scene::DemoSceneParams p;
  long gearboxes = long(p.gearbox_count), bunnies = long(p.bunny_count), segments = long(p.segments);
  args.getInt("--gearboxes", gearboxes);
  args.getInt("--bunnies", bunnies);
  args.getInt("--segments", segments);
  if (!args.ok()) return usageError("demo-scene", args.error());
  if (!args.positional().empty()) return usageError("demo-scene", "unexpected argument '" + args.positional()[0] + "'");
  const std::string out = args.get("--out");
  if (out.empty()) return usageError("demo-scene", "missing -o FILE.glb");
  if (out.size() < 4 || out.substr(out.size() - 4) != ".glb") return usageError("demo-scene", "the output must end in .glb");
  if (gearboxes < 1 || gearboxes > 1000) return usageError("demo-scene", "--gearboxes must be in 1..1000");
  if (bunnies < 0 || bunnies > 1000) return usageError("demo-scene", "--bunnies must be in 0..1000");
  if (segments < 3 || segments > 4096) return usageError("demo-scene", "--segments must be in 3..4096");
  p.gearbox_count = size_t(gearboxes);
  p.bunny_count = size_t(bunnies);
  p.segments = size_t(segments);
  if (args.has("--bunny")) p.bunny_path = args.get("--bunny");

  scene::SceneData s;
  scene::DemoSceneInfo info;
  if (Error e = scene::makeDemoScene(s, p, &info)) return runError("demo-scene", e.message);
  std::fprintf(stderr, "%s\n", info.note.c_str());
  if (Error e = scene::exportGlb(out, s)) return runError("demo-scene", e.message);
  size_t tris = 0;
  const std::vector<int32_t> objects = scene::objectNodes(s);
  for (int32_t n : objects) tris += s.meshes[s.nodes[n].mesh].mesh.triangleCount();
  std::printf("wrote %s: %zu nodes, %zu objects, %zu unique meshes, %zu triangles drawn\n", out.c_str(), s.nodes.size(),
              objects.size(), s.meshes.size(), tris);
  return 0;
}

const CommandRegistration kRegister({"demo-scene", "write the built-in demo scene (CAD parts + bunnies) as GLB", kUsage,
                                     &runDemoScene});

}  // namespace

}  // namespace scenelod::tool
