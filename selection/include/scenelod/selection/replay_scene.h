#pragma once
// What a replay needs from a scene: nodes with local transforms (moves replace them), objects
// (a node and a chain), each chain's level table rows and object-space bounding sphere. Built from
// a glTF/GLB scene with its chains, from a level-scene JSON file (docs/REPLAY.md), or from a
// built-in synthetic scene ("builtin:NAME"), so tests and golden replays need no meshes.
// Offline code: allocates, returns Error naming the source and the problem.
#include <cstdint>
#include <string>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "scenelod/lodcore/chain.h"
#include "scenelod/lodcore/lod_chain.h"
#include "scenelod/lodcore/status.h"
#include "scenelod/selection/level_table.h"
#include "scenelod/selection/replay.h"

namespace scenelod::scene {
struct SceneData;
}

namespace scenelod::selection {

struct ReplayScene {
  std::string name;
  LevelTableData table;                  // one chain per unique mesh
  std::vector<Sphere> chain_bounds;      // object-space sphere containing every level, per chain
  std::vector<std::string> chain_names;  // per chain (may be empty strings)
  std::vector<int32_t> node_parent;      // per node, -1 for a root
  std::vector<glm::mat4> node_local;     // per node
  std::vector<int32_t> object_node;      // per object: its node
  std::vector<uint32_t> object_chain;    // per object: its chain
  std::vector<float> importance;         // per object
  std::vector<uint8_t> must_draw;        // per object
  std::vector<LodChain> chains;          // per chain, the meshes when the source had them (glTF/GLB/
                                         // OBJ); empty for level-scene files and built-in scenes

  size_t objectCount() const { return object_node.size(); }
};

// Checks sizes agree, indices are in range, parents form no cycle, numbers are finite, level rows
// are valid for selection (widths non-decreasing within a chain). `what` names the source.
Error validateReplayScene(const ReplayScene& scene, const std::string& what);

// World transform of every object: its node's local transform under its ancestors' (a root's is its
// local one), computed parents before children. Cost: O(nodes + objects); allocates.
void computeObjectWorlds(const ReplayScene& scene, std::vector<glm::mat4>& worlds);

// World bounding sphere and largest axis scale of every object (the chain's sphere under the node's
// world transform; the radius is scaled by the largest column length, conservative under
// non-uniform scale). Cost: O(nodes + objects); allocates the outputs.
void computeWorldSpheres(const ReplayScene& scene, std::vector<glm::vec3>& centers, std::vector<float>& radii,
                         std::vector<float>& max_scales);

// Replaces the local transforms of moved objects' nodes. Errors: an object index out of range.
Error applyMoves(ReplayScene& scene, const std::vector<ReplayMove>& moves, const std::string& what);

// Built-in synthetic scenes, made in code from a fixed seed:
//   "builtin:small"  40 objects, 4 chains of 6 levels, one parent node carrying 4 objects;
//   "builtin:city"   a 24 x 24 grid of buildings (576 objects, 6 chains of 8 levels), 2 must-draw
//                    instruments near the origin;
//   "builtin:field"  2 000 objects scattered over a plane, 10 chains of 8 levels.
// Errors: an unknown name (the message lists the known ones).
Error makeBuiltinScene(const std::string& name, ReplayScene& out);

// The scene of `scene_data` (objects numbered as objectNodes) with one chain per mesh; `chains`
// holds one chain per mesh of scene_data. Errors: a chain count that differs from the mesh count,
// a chain with more than 64 levels. `chain_spheres` (one per chain, e.g. SceneLods::chain_spheres)
// replaces the sphere derived from the levels' bounds when given.
Error replaySceneFromSceneData(const scene::SceneData& scene_data, const std::vector<LodChain>& chains,
                               const std::string& what, ReplayScene& out,
                               const std::vector<Sphere>* chain_spheres = nullptr);

// Level-scene JSON files (docs/REPLAY.md): chains (sphere, levels as [cell width, triangles,
// vertices, edges + points]), nodes (parent, translation, rotation, scale) and objects.
Error loadLevelScene(const std::string& path, ReplayScene& out);
Error writeLevelScene(const std::string& path, const ReplayScene& scene);

// A LOD pack (scene/pack.h): its nodes, objects (importance, must-draw) and chains' level rows.
Error loadPackScene(const std::string& path, ReplayScene& out);

// Loads any scene a replay may name: "builtin:NAME", a level-scene .json, a LOD pack (.slodpack or .pack), or a
// .gltf/.glb/.obj file (MSFT_lod levels when the file has them, otherwise every mesh's chain built
// with default parameters by scene::buildLods). Errors name the file.
Error loadReplayScene(const std::string& path, ReplayScene& out);

// The same with the chain parameters of the meshes whose chains are built here (e.g. nested chains,
// ChainParams::nested). Errors as above, and a scene whose levels come from the file (builtin:NAME,
// level-scene, pack, a glTF with MSFT_lod levels): `chain` would not apply.
Error loadReplayScene(const std::string& path, ReplayScene& out, const ChainParams& chain);

}  // namespace scenelod::selection
