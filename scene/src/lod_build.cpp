// Whole-scene LOD precompute: one lodcore chain (Low & Tan 1997 floating-cell clustering by
// default) per unique mesh, meshes in parallel with TBB, then bounding spheres per level.
#include "scenelod/scene/lod_build.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <numeric>

#include <tbb/parallel_for.h>

#include "scenelod/scene/bounding_sphere.h"
#include "scenelod/scene/scene.h"
#include "scenelod/scene/skin_pose.h"

namespace scenelod::scene {
namespace {

// a skinned mesh's chain sphere follows its animations, every level posed with its own weights
Error animatedChainSphere(const SceneData& data, size_t m, SceneLods& out, const std::string& what) {
  std::vector<const Mesh*> levels;
  for (const LodLevel& level : out.chains[m].levels) levels.push_back(&level.mesh);
  return animatedMeshSphere(data, static_cast<int32_t>(m), Span<const Mesh* const>(levels.data(), levels.size()),
                            out.chain_spheres[m], what + " mesh " + std::to_string(m));
}

}  // namespace

Error buildLods(const SceneData& data, const LodBuildParams& params, SceneLods& out, Scene* scene,
                const std::string& what) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  if (Error e = validateSkinning(data, what); !e.ok()) return e;
  const size_t n = data.meshes.size();
  out = SceneLods{};
  out.chains.resize(n);
  out.chain_spheres.resize(n);
  out.build_seconds.assign(n, 0.0);
  std::vector<Error> errors(n);
  const std::vector<uint8_t> skinned = meshesDrawnWithSkin(data);

  // work = primitives, so the bar moves evenly with a mix of large and small meshes
  std::vector<double> work(n);
  double total_work = 0.0;
  for (size_t m = 0; m < n; ++m) {
    const Mesh& mesh = data.meshes[m].mesh;
    work[m] = 1.0 + double(mesh.triangleCount() + mesh.edgeCount() + mesh.pointCount());
    total_work += work[m];
  }
  // biggest meshes first so one huge mesh does not start last
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return work[a] > work[b]; });

  std::mutex progress_mutex;
  double done_work = 0.0;
  params.progress(0.0, "building chains");
  tbb::parallel_for(size_t(0), n, size_t(1), [&](size_t k) {
    const size_t m = order[k];
    const auto t0 = Clock::now();
    ChainParams cp = params.chain;
    cp.progress = ProgressCallback{};
    const MeshData& md = data.meshes[m];
    if (params.first_cell_rel > 0.0f) {
      const float diagonal = computeBounds(md.mesh).diagonal();
      cp.first_cell_width = diagonal > 0.0f ? params.first_cell_rel * diagonal : 0.0f;
    }
    if (Error e = buildChain(md.mesh, cp, out.chains[m]); !e.ok()) {
      errors[m] = Error(e.status, what + " mesh " + std::to_string(m) + (md.name.empty() ? "" : " '" + md.name + "'") +
                                      ": " + e.message);
    } else {
      out.chain_spheres[m] = computeChainBounds(out.chains[m]);
      if (skinned[m]) errors[m] = animatedChainSphere(data, m, out, what);
    }
    out.build_seconds[m] = std::chrono::duration<double>(Clock::now() - t0).count();
    std::lock_guard<std::mutex> lock(progress_mutex);
    done_work += work[m];
    params.progress(done_work / total_work, "building chains");
  });
  for (size_t m = 0; m < n; ++m)
    if (!errors[m].ok()) return errors[m];
  if (scene) {
    scene->setChainCount(n);
    for (size_t m = 0; m < n; ++m)
      if (Error e = scene->setChainSphere(static_cast<uint32_t>(m), out.chain_spheres[m]); !e.ok()) return e;
  }
  out.total_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  params.progress(1.0, "done");
  return {};
}

}  // namespace scenelod::scene
