// scenelod demo-scene: writes the built-in default scene (CAD parts and bunny instances) as a GLB.
#include <cstdio>
#include <string>
#include <vector>

#include "args.h"
#include "demo_scene_options.h"
#include "command.h"
#include "scenelod/scene/demo_scene.h"
#include "scenelod/scene/gltf_io.h"

namespace scenelod::tool {

namespace {

const std::string kUsage =
    std::string("usage: scenelod demo-scene -o FILE.glb [options]\n"
    "\n"
    "Writes the built-in default scene: a CAD-like assembly of simple polyhedra (gears, shafts, bolts,\n"
    "brackets, pipes, prisms, a base plate, thin fins and rods that collapse into thick edges) and\n"
    "instances of the Stanford bunny, with meshes shared between instances. Deterministic.\n"
    "\n"
    "  -o, --out FILE.glb  the output file\n") +
    kDemoSceneOptionsHelp;

int runDemoScene(const std::vector<std::string>& argv) {
  std::vector<std::string> options = demoSceneOptionNames();
  options.push_back("--out");
  Args args(argv, {}, options);
  if (!args.ok()) return usageError("demo-scene", args.error());
  if (!args.positional().empty()) return usageError("demo-scene", "unexpected argument '" + args.positional()[0] + "'");
  scene::DemoSceneParams p;
  std::string option_error;
  if (!readDemoSceneOptions(args, p, option_error)) return usageError("demo-scene", option_error);
  const std::string out = args.get("--out");
  if (out.empty()) return usageError("demo-scene", "missing -o FILE.glb");
  if (out.size() < 4 || out.substr(out.size() - 4) != ".glb") return usageError("demo-scene", "the output must end in .glb");

  scene::SceneData s;
  scene::DemoSceneInfo info;
  if (Error e = scene::makeDemoScene(s, p, &info); !e.ok()) return runError("demo-scene", e.message);
  std::fprintf(stderr, "%s\n", info.note.c_str());
  if (Error e = scene::exportGlb(out, s); !e.ok()) return runError("demo-scene", e.message);
  size_t tris = 0;
  const std::vector<int32_t> objects = scene::objectNodes(s);
  for (int32_t n : objects) tris += s.meshes[s.nodes[n].mesh].mesh.triangleCount();
  std::printf("wrote %s: %zu nodes, %zu objects, %zu unique meshes, %zu triangles drawn\n", out.c_str(), s.nodes.size(),
              objects.size(), s.meshes.size(), tris);
  return 0;
}

const CommandRegistration kRegister({"demo-scene", "write the built-in demo scene (CAD parts + bunnies) as GLB", kUsage.c_str(),
                                     &runDemoScene});

}  // namespace

}  // namespace scenelod::tool
