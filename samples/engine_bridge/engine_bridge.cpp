// How a C++ engine uses scenelod: mirror its objects into scene::Scene, precompute chains once,
// then every frame move what moved, update, select under a budget with Embree occlusion feeding the
// benefit, draw the chosen levels and report the measured frame time. docs/INTEGRATION.md walks
// through it. Exits non-zero if a step fails.
#include <cmath>
#include <cstdio>
#include <vector>

#include "scenelod/scene/demo_scene.h"
#include "scenelod/scene/lod_build.h"
#include "scenelod/scene/scene.h"
#include "scenelod/selection/level_table.h"
#include "scenelod/selection/selector.h"
#include "scenelod/selection/visibility.h"

using namespace scenelod;

int main() {
  // 1. the engine's content, here the built-in demo scene (any SceneData: glTF import, or filled by hand)
  scene::SceneData data;
  if (Error e = scene::makeDemoScene(data, scene::DemoSceneParams()); !e.ok()) return std::fprintf(stderr, "%s\n", e.message.c_str()), 1;

  // 2. offline: the runtime scene graph and every unique mesh's chain (in parallel)
  scene::Scene world;
  if (Error e = scene::Scene::fromSceneData(data, world); !e.ok()) return std::fprintf(stderr, "%s\n", e.message.c_str()), 1;
  scene::SceneLods lods;
  if (Error e = scene::buildLods(data, scene::LodBuildParams(), lods, &world); !e.ok())
    return std::fprintf(stderr, "%s\n", e.message.c_str()), 1;
  selection::LevelTableData table;
  for (const LodChain& c : lods.chains) table.addChain(c);  // chain id = mesh index, as the scene uses
  world.update();

  // 3. the per-frame state, sized once
  const size_t n = world.objectCount();
  selection::SelectorConfig cfg;
  cfg.max_object_count = n;
  cfg.max_levels_per_chain = table.maxLevelsPerChain();
  selection::SelectorContext* selector = selection::createSelectorContext(cfg);
  if (!selector) return std::fprintf(stderr, "cannot create the selector\n"), 1;
  std::vector<const LodChain*> chain_ptrs;
  for (const LodChain& c : lods.chains) chain_ptrs.push_back(&c);
  selection::RayScene rays;
  if (Error e = rays.init(Span<const LodChain* const>(chain_ptrs.data(), chain_ptrs.size())); !e.ok())
    return std::fprintf(stderr, "%s\n", e.message.c_str()), 1;
  selection::OcclusionEstimator occlusion;
  if (Error e = occlusion.init(n); !e.ok()) return std::fprintf(stderr, "%s\n", e.message.c_str()), 1;
  std::vector<int8_t> levels(n, -1);
  std::vector<int32_t> drawn(n, 0);
  std::vector<float> visible(n, 1.0f);

  selection::Camera camera;
  camera.viewport_width_px = 1280;
  camera.viewport_height_px = 720;
  size_t total_triangles = 0, frames = 120;
  for (size_t frame = 0; frame < frames; ++frame) {
    // the engine moves things: here the first object spins
    const float a = 0.05f * static_cast<float>(frame);
    scene::ObjectDesc first;
    world.getObject(world.objectAt(0), first);
    scene::Trs trs;
    trs.rotation = glm::angleAxis(a, glm::vec3(0, 1, 0));
    world.setLocal(first.node, trs);
    world.update();

    camera.eye = glm::vec3(60.0f * std::cos(a * 0.2f), 15.0f, 60.0f * std::sin(a * 0.2f));
    camera.target = glm::vec3(0.0f);

    // visibility from last frame's drawn levels
    for (size_t i = 0; i < n; ++i) drawn[i] = levels[i];
    if (Error e = rays.syncFromScene(world, Span<const int32_t>(drawn.data(), n)); !e.ok()) return std::fprintf(stderr, "%s\n", e.message.c_str()), 1;
    rays.commit();
    occlusion.update(rays, camera, Span<float>(visible.data(), n));

    selection::SelectionJob job;
    job.camera = &camera;
    job.params.budget_ms = 8.0f;
    job.levels = table.view();
    job.centers = world.worldCenters();
    job.radii = world.worldRadii();
    job.max_scales = world.maxScales();
    job.chains = world.chainIds();
    job.importance = world.importances();
    job.must_draw = world.mustDraw();
    job.visible_fraction = Span<const float>(visible.data(), n);
    job.levels_out = Span<int8_t>(levels.data(), n);
    selection::SelectionStats stats;
    job.stats = &stats;
    job.context = selector;
    if (!job.run()) return std::fprintf(stderr, "the selector refused frame %zu\n", frame), 1;

    // draw: the engine binds chain c's level levels[i] for object i (here we only count)
    size_t triangles = 0;
    for (size_t i = 0; i < n; ++i)
      if (levels[i] >= 0) triangles += lods.chains[world.chainIds()[i]].levels[levels[i]].mesh.triangleCount();
    total_triangles += triangles;
    // report what the frame really cost (a measured GPU time in a real engine)
    selection::reportFrameTime(selector, stats.frame, static_cast<float>(stats.predicted_ms));
  }
  selection::destroySelectorContext(selector);
  std::printf("engine_bridge: %zu objects, %zu chains, %zu frames, mean %.0f triangles drawn per frame\n", n,
              lods.chains.size(), frames, static_cast<double>(total_triangles) / frames);
  return total_triangles > 0 ? 0 : 1;
}
