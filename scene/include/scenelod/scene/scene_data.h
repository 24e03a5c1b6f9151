#pragma once
// The raw, mutable description of a scene as it comes from a file or from an engine: nodes with
// local transforms, meshes, materials. Importers fill it, exporters read it, and the runtime scene
// graph (scene.h) is built from it. Plain vectors, easy to fill by hand in tests and tools.
#include <cstdint>
#include <string>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "scenelod/lodcore/mesh.h"
#include "scenelod/lodcore/status.h"

namespace scenelod::scene {

struct MaterialData {
  std::string name;
  glm::vec4 base_color{1.0f};             // linear RGBA factor
  bool textured = false;                  // has a base colour texture
  glm::vec3 average_texel_color{1.0f};    // linear RGB mean of the base colour texture (SCROOGE §7.3)
};

struct MeshData {
  std::string name;
  // every primitive of the glTF mesh merged into one Mesh; per-vertex colours hold the linear
  // base colour (factor x COLOR_0 x average texel), so a simplifier can average them by area
  Mesh mesh;
  std::vector<int32_t> primitive_materials;  // material of each source primitive, in order (-1 = none)
};

struct NodeData {
  std::string name;
  int32_t parent = -1;                // -1 for a root
  std::vector<int32_t> children;      // in file order
  glm::mat4 local{1.0f};              // local transform (TRS composed, or the node's matrix)
  int32_t mesh = -1;                  // index into SceneData::meshes, -1 for none
};

struct SceneData {
  std::vector<NodeData> nodes;
  std::vector<int32_t> roots;         // the default scene's root nodes, in order
  std::vector<MeshData> meshes;
  std::vector<MaterialData> materials;
};

// Checks parent/child links agree, there are no cycles, every node is reachable at most once from the
// roots, mesh and material indices are in range, and every mesh is valid (validateMesh). `what`
// names the source in messages.
Error validateSceneData(const SceneData& scene, const std::string& what);

// The objects of a scene: nodes that have a mesh, numbered depth-first in pre-order from the roots,
// children in order. This numbering is the object numbering of replay files and of `scenelod info`.
std::vector<int32_t> objectNodes(const SceneData& scene);

// World transform of every node (identity parent for roots); nodes not reachable from the roots get
// their chain of parents applied all the same.
std::vector<glm::mat4> worldTransforms(const SceneData& scene);

}  // namespace scenelod::scene
