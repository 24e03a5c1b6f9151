// scenelod info: what a scene file holds, counted as drawn (one copy per node instance).
#include <cinttypes>
#include <cstdio>
#include <string>
#include <vector>

#include "args.h"
#include "command.h"
#include "scenelod/lodcore/atomic_file.h"
#include "scenelod/scene/gltf_io.h"

namespace scenelod::tool {

namespace {

const char kUsage[] =
    "usage: scenelod info FILE [--json] [-o|--out OUT]\n"
    "\n"
    "Reads FILE (.obj, .gltf or .glb) and prints what it holds:\n"
    "  nodes      every node of the file\n"
    "  meshes     every mesh (all primitives of a glTF mesh are one mesh)\n"
    "  objects    nodes with a mesh reachable from the default scene's roots\n"
    "  vertices, triangles, edges, points\n"
    "             counted as drawn: one copy per object (node instance); triangles are every index\n"
    "             triple, degenerate ones included; strips and fans count as their triangles\n"
    "  unique_*   the same counted once per mesh\n"
    "  bounds     world-space box of the drawn vertices\n"
    "  materials  number of materials\n"
    "\n"
    "  --json       print one JSON object (keys: file, nodes, meshes, objects, vertices, triangles,\n"
    "               edges, points, unique_vertices, unique_triangles, materials, bounds)\n"
    "  -o, --out F  write the report to F instead of standard output";

std::string jsonString(const std::string& s) {
  std::string out = "\"";
  for (unsigned char c : s) {
    if (c == '"' || c == '\\') out += '\\', out += static_cast<char>(c);
    else if (c < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof(buf), "\\u%04x", c);
      out += buf;
    } else out += static_cast<char>(c);
  }
  return out + "\"";
}

int runInfo(const std::vector<std::string>& argv) {
  Args args(argv, {"--json"}, {"--out"});
  if (!args.ok()) return usageError("info", args.error());
  if (args.positional().size() != 1) return usageError("info", "expected exactly one FILE");
  const std::string path = args.positional()[0];

  scene::SceneData s;
  if (Error e = scene::loadScene(path, s); !e.ok()) return runError("info", e.message);

  const std::vector<int32_t> objects = scene::objectNodes(s);
  const std::vector<glm::mat4> world = scene::worldTransforms(s);
  uint64_t vertices = 0, triangles = 0, edges = 0, points = 0, unique_vertices = 0, unique_triangles = 0;
  for (const scene::MeshData& m : s.meshes) {
    unique_vertices += m.mesh.vertexCount();
    unique_triangles += m.mesh.triangleCount();
  }
  Aabb box;
  bool first = true;
  for (int32_t node : objects) {
    const Mesh& m = s.meshes[static_cast<size_t>(s.nodes[static_cast<size_t>(node)].mesh)].mesh;
    vertices += m.vertexCount();
    triangles += m.triangleCount();
    edges += m.edgeCount();
    points += m.pointCount();
    const glm::mat4& w = world[static_cast<size_t>(node)];
    for (const glm::vec3& p : m.positions) {
      const glm::vec3 q(w * glm::vec4(p, 1.0f));
      if (first) box.min = box.max = q, first = false;
      box.min = glm::min(box.min, q);
      box.max = glm::max(box.max, q);
    }
  }

  std::string text;
  char buf[512];
  if (args.has("--json")) {
    std::snprintf(buf, sizeof(buf),
                  "{\"file\": %s, \"nodes\": %zu, \"meshes\": %zu, \"objects\": %zu, \"vertices\": %" PRIu64
                  ", \"triangles\": %" PRIu64 ", \"edges\": %" PRIu64 ", \"points\": %" PRIu64
                  ", \"unique_vertices\": %" PRIu64 ", \"unique_triangles\": %" PRIu64 ", \"materials\": %zu, ",
                  jsonString(path).c_str(), s.nodes.size(), s.meshes.size(), objects.size(), vertices, triangles, edges, points,
                  unique_vertices, unique_triangles, s.materials.size());
    text += buf;
    std::snprintf(buf, sizeof(buf), "\"bounds\": {\"min\": [%.9g, %.9g, %.9g], \"max\": [%.9g, %.9g, %.9g], \"diagonal\": %.9g}}\n",
                  box.min.x, box.min.y, box.min.z, box.max.x, box.max.y, box.max.z, box.diagonal());
    text += buf;
  } else {
    std::snprintf(buf, sizeof(buf),
                  "file:       %s\nnodes:      %zu\nmeshes:     %zu\nobjects:    %zu\n"
                  "vertices:   %" PRIu64 " drawn (%" PRIu64 " unique)\ntriangles:  %" PRIu64 " drawn (%" PRIu64 " unique)\n"
                  "edges:      %" PRIu64 "\npoints:     %" PRIu64 "\nmaterials:  %zu\n",
                  path.c_str(), s.nodes.size(), s.meshes.size(), objects.size(), vertices, unique_vertices, triangles,
                  unique_triangles, edges, points, s.materials.size());
    text += buf;
    std::snprintf(buf, sizeof(buf), "bounds:     min (%g, %g, %g) max (%g, %g, %g) diagonal %g\n", box.min.x, box.min.y,
                  box.min.z, box.max.x, box.max.y, box.max.z, box.diagonal());
    text += buf;
  }
  if (args.has("--out")) {
    const std::string out = args.get("--out");
    if (Error e = writeFileAtomic(out, text.data(), text.size()); !e.ok()) return runError("info", e.message);
  } else {
    std::fputs(text.c_str(), stdout);
  }
  return 0;
}

const CommandRegistration kRegister({"info", "print what a scene file holds (counts as drawn, bounds)", kUsage, &runInfo});

}  // namespace

}  // namespace scenelod::tool
