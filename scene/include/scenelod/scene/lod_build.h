#pragma once
// Whole-scene precompute: the LOD chain of every unique mesh of a scene, built in parallel.
#include <cstddef>
#include <vector>

#include "scenelod/lodcore/chain.h"
#include "scenelod/lodcore/lod_chain.h"
#include "scenelod/lodcore/progress.h"
#include "scenelod/lodcore/status.h"
#include "scenelod/scene/scene_data.h"

namespace scenelod::scene {

class Scene;

struct LodBuildParams {
  ChainParams chain;         // for every mesh; chain.progress is ignored (use `progress`)
  float first_cell_rel = 0;  // > 0: each mesh's w_1 = this x its bounding-box diagonal (overrides
                             // chain.first_cell_width)
  ProgressCallback progress; // whole-scene progress, weighted by triangle count; never concurrent
};

struct SceneLods {
  std::vector<LodChain> chains;       // one per SceneData mesh: chain id = mesh index
  std::vector<Sphere> chain_spheres;  // object space, contains every level of the chain
  std::vector<double> build_seconds;  // wall time of each chain's build (threads overlap)
  double total_seconds = 0.0;         // wall time of the whole precompute
};

// Builds the chain of every mesh of `data` with lodcore's buildChain, meshes in parallel (TBB, each
// chain itself parallel over levels), then every level's bounding sphere (LodLevel::bounds, the
// minimal sphere of the level) and the chain's sphere containing all levels (for a mesh drawn with
// a skin, all levels in every pose of the animations: animatedMeshSphere). When `scene` is not
// null its chain spheres are set from the result (its chain count becomes the mesh count).
// The chains do not depend on the thread count. Errors: validateSkinning's; the first failing mesh
// (lowest index), its message naming `what`, the mesh index and name. Allocates; blocks until done.
Error buildLods(const SceneData& data, const LodBuildParams& params, SceneLods& out, Scene* scene = nullptr,
                const std::string& what = "scene");

}  // namespace scenelod::scene
