#pragma once
// glTF 2.0 (.gltf and .glb) import and export through tinygltf, and loading any supported scene file.
#include <string>
#include <vector>

#include "scenelod/lodcore/lod_chain.h"
#include "scenelod/lodcore/status.h"
#include "scenelod/scene/scene_data.h"

namespace scenelod::scene {

// Reads a .gltf or .glb file: every node with its local transform, the default scene's roots, meshes
// (all primitives of a mesh merged into one Mesh), materials. Errors name the file and the problem.
Error importGltf(const std::string& path, SceneData& out);

// Reads OBJ (one root node holding one mesh), .gltf or .glb, chosen by extension.
Error loadScene(const std::string& path, SceneData& out);

// Writes a GLB with the node hierarchy and meshes; edges become LINES with a _THICKNESS attribute,
// points become POINTS. When `chains` is given (one per mesh, or null entries), each mesh node is
// written with the MSFT_lod extension pointing at nodes of the coarser levels.
Error exportGlb(const std::string& path, const SceneData& scene,
                const std::vector<const LodChain*>* chains = nullptr);

// Merges every object of the scene into one world-space mesh (positions and normals transformed),
// as used to simplify or measure a whole model.
Mesh flattenScene(const SceneData& scene);

}  // namespace scenelod::scene
