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
    "  materials, textures, images, skins, animations\n"
    "             how many the file has, then per object (node with a mesh): its mesh, each\n"
    "             primitive's material, the vertex attributes it carries (uv sets, tangents,\n"
    "             colours, skin weights), its skin and its LOD levels (MSFT_lod, as scenelod lods\n"
    "             writes them) with their triangle counts\n"
    "\n"
    "  --json       print one JSON object (keys: file, nodes, meshes, objects, vertices, triangles,\n"
    "               edges, points, unique_vertices, unique_triangles, materials, textures, images,\n"
    "               skins, animations, bounds, object_details: [{node, name, mesh, materials,\n"
    "               attributes, skin, level_triangles}])\n"
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

// the vertex attributes a mesh carries, by short name
std::vector<std::string> attributeNames(const Mesh& m) {
  std::vector<std::string> out;
  if (!m.normals.empty()) out.push_back("normals");
  if (!m.uvs.empty()) out.push_back("uv0");
  for (size_t k = 0; k < m.extra_uvs.size(); ++k) out.push_back("uv" + std::to_string(k + 1));
  if (!m.tangents.empty()) out.push_back("tangents");
  if (!m.colors.empty()) out.push_back("colors");
  if (m.skinned()) out.push_back("skin_weights");
  return out;
}

// what the report says of one object (a node with a mesh)
struct ObjectInfo {
  int32_t node = -1;
  int32_t mesh = -1;
  std::vector<int32_t> materials;         // per primitive, -1 = none
  std::vector<std::string> attributes;
  int32_t skin = -1;
  std::vector<size_t> level_triangles;    // level 0 first
};

std::vector<ObjectInfo> describeObjects(const scene::SceneData& s, const std::vector<int32_t>& objects,
                                        const std::vector<LodChain>& chains) {
  std::vector<ObjectInfo> out;
  for (int32_t node : objects) {
    ObjectInfo o;
    o.node = node;
    o.mesh = s.nodes[static_cast<size_t>(node)].mesh;
    o.skin = s.nodes[static_cast<size_t>(node)].skin;
    const scene::MeshData& md = s.meshes[static_cast<size_t>(o.mesh)];
    o.materials = md.primitive_materials;
    o.attributes = attributeNames(md.mesh);
    if (static_cast<size_t>(o.mesh) < chains.size() && !chains[static_cast<size_t>(o.mesh)].empty()) {
      for (const LodLevel& level : chains[static_cast<size_t>(o.mesh)].levels)
        o.level_triangles.push_back(level.mesh.triangleCount());
    } else {
      o.level_triangles.push_back(md.mesh.triangleCount());
    }
    out.push_back(std::move(o));
  }
  return out;
}

template <typename T, typename F>
std::string joined(const std::vector<T>& items, const char* separator, F format) {
  std::string out;
  for (size_t i = 0; i < items.size(); ++i) out += (i ? separator : "") + format(items[i]);
  return out;
}

std::string objectsJson(const scene::SceneData& s, const std::vector<ObjectInfo>& objects) {
  return "[" + joined(objects, ", ", [&](const ObjectInfo& o) {
           return "{\"node\": " + std::to_string(o.node) + ", \"name\": " +
                  jsonString(s.nodes[static_cast<size_t>(o.node)].name) + ", \"mesh\": " + std::to_string(o.mesh) +
                  ", \"materials\": [" + joined(o.materials, ", ", [](int32_t m) { return std::to_string(m); }) +
                  "], \"attributes\": [" + joined(o.attributes, ", ", jsonString) + "], \"skin\": " +
                  std::to_string(o.skin) + ", \"level_triangles\": [" +
                  joined(o.level_triangles, ", ", [](size_t n) { return std::to_string(n); }) + "]}";
         }) + "]";
}

std::string objectsText(const scene::SceneData& s, const std::vector<ObjectInfo>& objects) {
  auto quoted = [](const std::string& name) { return name.empty() ? std::string() : " '" + name + "'"; };
  std::string out;
  for (size_t i = 0; i < objects.size(); ++i) {
    const ObjectInfo& o = objects[i];
    out += "object " + std::to_string(i) + ": node " + std::to_string(o.node) + quoted(s.nodes[static_cast<size_t>(o.node)].name) +
           ", mesh " + std::to_string(o.mesh) + quoted(s.meshes[static_cast<size_t>(o.mesh)].name) + "\n";
    out += "  materials:  " + joined(o.materials, ", ", [&](int32_t m) {
             return m < 0 ? std::string("none") : std::to_string(m) + quoted(s.materials[static_cast<size_t>(m)].name);
           }) + "\n";
    out += "  attributes: " + (o.attributes.empty() ? std::string("positions only") : joined(o.attributes, " ", [](const std::string& a) { return a; })) + "\n";
    out += "  skin:       " + (o.skin < 0 ? std::string("none") : std::to_string(o.skin) + quoted(s.skins[static_cast<size_t>(o.skin)].name) + " (" +
                                 std::to_string(s.skins[static_cast<size_t>(o.skin)].joints.size()) + " joints)") + "\n";
    out += "  levels:     " + std::to_string(o.level_triangles.size()) + " (" +
           joined(o.level_triangles, ", ", [](size_t n) { return std::to_string(n); }) + " triangles)\n";
  }
  return out;
}

int runInfo(const std::vector<std::string>& argv) {
  Args args(argv, {"--json"}, {"--out"});
  if (!args.ok()) return usageError("info", args.error());
  if (args.positional().size() != 1) return usageError("info", "expected exactly one FILE");
  const std::string path = args.positional()[0];

  // glTF files are read with their MSFT_lod levels, which come back as each mesh's chain
  scene::SceneData s;
  std::vector<LodChain> chains;
  const std::string ext = scene::lowerExtension(path);
  const Error load_error =
      ext == ".gltf" || ext == ".glb" ? scene::importGltfLods(path, s, chains) : scene::loadScene(path, s);
  if (!load_error.ok()) return runError("info", load_error.message);

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

  const std::vector<ObjectInfo> details = describeObjects(s, objects, chains);
  std::string text;
  char buf[512];
  if (args.has("--json")) {
    std::snprintf(buf, sizeof(buf),
                  "{\"file\": %s, \"nodes\": %zu, \"meshes\": %zu, \"objects\": %zu, \"vertices\": %" PRIu64
                  ", \"triangles\": %" PRIu64 ", \"edges\": %" PRIu64 ", \"points\": %" PRIu64
                  ", \"unique_vertices\": %" PRIu64 ", \"unique_triangles\": %" PRIu64 ", \"materials\": %zu, "
                  "\"textures\": %zu, \"images\": %zu, \"skins\": %zu, \"animations\": %zu, ",
                  jsonString(path).c_str(), s.nodes.size(), s.meshes.size(), objects.size(), vertices, triangles, edges, points,
                  unique_vertices, unique_triangles, s.materials.size(), s.textures.size(), s.images.size(), s.skins.size(),
                  s.animations.size());
    text += buf;
    std::snprintf(buf, sizeof(buf), "\"bounds\": {\"min\": [%.9g, %.9g, %.9g], \"max\": [%.9g, %.9g, %.9g], \"diagonal\": %.9g}, ",
                  box.min.x, box.min.y, box.min.z, box.max.x, box.max.y, box.max.z, box.diagonal());
    text += buf;
    text += "\"object_details\": " + objectsJson(s, details) + "}\n";
  } else {
    std::snprintf(buf, sizeof(buf),
                  "file:       %s\nnodes:      %zu\nmeshes:     %zu\nobjects:    %zu\n"
                  "vertices:   %" PRIu64 " drawn (%" PRIu64 " unique)\ntriangles:  %" PRIu64 " drawn (%" PRIu64 " unique)\n"
                  "edges:      %" PRIu64 "\npoints:     %" PRIu64 "\nmaterials:  %zu\ntextures:   %zu (%zu images)\n"
                  "skins:      %zu\nanimations: %zu\n",
                  path.c_str(), s.nodes.size(), s.meshes.size(), objects.size(), vertices, unique_vertices, triangles,
                  unique_triangles, edges, points, s.materials.size(), s.textures.size(), s.images.size(), s.skins.size(),
                  s.animations.size());
    text += buf;
    std::snprintf(buf, sizeof(buf), "bounds:     min (%g, %g, %g) max (%g, %g, %g) diagonal %g\n", box.min.x, box.min.y,
                  box.min.z, box.max.x, box.max.y, box.max.z, box.diagonal());
    text += buf;
    text += objectsText(s, details);
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
