// scenelod convert: OBJ <-> GLB, glTF -> GLB, and any scene -> OBJ flattened in world space.
#include <cstdio>
#include <string>
#include <vector>

#include "args.h"
#include "command.h"
#include "progress.h"
#include "scenelod/lodcore/obj_io.h"
#include "scenelod/scene/gltf_io.h"

namespace scenelod::tool {

namespace {

const char kUsage[] =
    "usage: scenelod convert IN OUT\n"
    "       scenelod convert IN -o OUT\n"
    "\n"
    "Converts between scene formats, chosen by the file extensions:\n"
    "  IN  .obj, .gltf or .glb\n"
    "  OUT .glb  the node hierarchy and meshes (an OBJ becomes one node with one mesh); edges are\n"
    "            written as LINES with a _THICKNESS attribute, points as POINTS, colours as COLOR_0\n"
    "      .obj  every object of the scene merged into one mesh in world space (node transforms\n"
    "            applied, one copy per node instance; the hierarchy is lost). OBJ cannot hold edge\n"
    "            thickness: it is written as '#t' comments that scenelod reads back\n"
    "\n"
    "  -o, --out OUT  the output file (instead of the second positional argument)";

int runConvert(const std::vector<std::string>& argv) {
  Args args(argv, {}, {"--out"});
  if (!args.ok()) return usageError("convert", args.error());
  std::vector<std::string> pos = args.positional();
  if (args.has("--out")) pos.push_back(args.get("--out"));
  if (pos.size() != 2) return usageError("convert", "expected IN and OUT (OUT positional or with -o)");
  const std::string& in = pos[0];
  const std::string& out = pos[1];
  const std::string ext = scene::lowerExtension(out);
  if (ext != ".glb" && ext != ".obj")
    return usageError("convert", "cannot write '" + out + "': the output must end in .glb or .obj");

  // coarse stages: the bar appears only when the whole conversion takes more than a second
  ProgressBar bar("convert");
  bar.update(0.0, "reading");
  scene::SceneData s;
  if (Error e = scene::loadScene(in, s); !e.ok()) return runError("convert", e.message);
  scene::bakeMaterialColors(s);  // the GLB writer keeps colours, not textures
  bar.update(0.5, "writing");
  if (ext == ".glb") {
    if (Error e = scene::exportGlb(out, s); !e.ok()) return runError("convert", e.message);
  } else {
    const Mesh flat = scene::flattenScene(s);
    if (Error e = writeObj(out, flat); !e.ok()) return runError("convert", e.message);
  }
  bar.update(1.0, "done");
  bar.finish();
  std::printf("wrote %s\n", out.c_str());
  return 0;
}

const CommandRegistration kRegister({"convert", "convert OBJ <-> GLB (glTF -> GLB; any scene -> OBJ in world space)", kUsage,
                                     &runConvert});

}  // namespace

}  // namespace scenelod::tool
