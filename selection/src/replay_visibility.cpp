// Visibility in replays: occlusion estimates and the pick focus of Funkhouser & Séquin 1993 fed into
// each frame's selection, and a shadow selection without visibility to measure what occlusion saved.
#include "scenelod/selection/replay_visibility.h"

#include <cmath>

#include "scenelod/selection/replay_runner.h"

namespace scenelod::selection {
namespace {

Mesh cubeMesh(glm::vec3 lo, glm::vec3 hi) {
  Mesh m;
  for (int i = 0; i < 8; ++i)
    m.positions.push_back({(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z});
  const uint32_t f[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : f) m.triangles.insert(m.triangles.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
  return m;
}

struct ShadowDeleter {
  void operator()(SelectorContext* c) const { destroySelectorContext(c); }
};

}  // namespace

struct ReplayVisibility::State {
  ReplayVisibilityParams params;
  RayScene rays;
  OcclusionEstimator occlusion;
  std::vector<LodChain> stand_ins;
  std::unique_ptr<SelectorContext, ShadowDeleter> shadow;
  size_t objects = 0;
  FocusParams focus_params;
  int32_t pick_object = -1;
  // per object
  std::vector<glm::mat4> world, next_world;
  std::vector<float> visible, focus, cost, shadow_cost;
  std::vector<int8_t> shadow_levels;
};

ReplayVisibility::ReplayVisibility() : state_(new State) {}
ReplayVisibility::~ReplayVisibility() = default;

Error ReplayVisibility::init(const ReplayScene& scene, const ReplayVisibilityParams& params) {
  state_.reset(new State);
  State& s = *state_;
  s.params = params;
  s.objects = scene.objectCount();
  const size_t chain_count = scene.table.chainCount();
  std::vector<const LodChain*> chains(chain_count, nullptr);
  if (scene.chains.size() == chain_count) {
    for (size_t c = 0; c < chain_count; ++c) chains[c] = &scene.chains[c];
  } else {
    // no geometry: each chain is the cube inscribed in its bounding sphere, at every level
    s.stand_ins.resize(chain_count);
    for (size_t c = 0; c < chain_count; ++c) {
      const Sphere b = c < scene.chain_bounds.size() ? scene.chain_bounds[c] : Sphere{};
      const float h = std::max(b.radius, 1e-6f) / std::sqrt(3.0f);
      const size_t levels = scene.table.chain_level_offset[c + 1] - scene.table.chain_level_offset[c];
      for (size_t l = 0; l < std::max<size_t>(levels, 1); ++l) {
        LodLevel level;
        level.mesh = cubeMesh(b.center - glm::vec3(h), b.center + glm::vec3(h));
        s.stand_ins[c].levels.push_back(std::move(level));
      }
      chains[c] = &s.stand_ins[c];
    }
  }
  if (Error e = s.rays.init(Span<const LodChain* const>(chains.data(), chains.size()), params.ray_scene); !e.ok()) return e;
  computeObjectWorlds(scene, s.world);
  const std::vector<int32_t> levels(s.objects, 0);
  if (Error e = s.rays.setObjects(s.world, scene.object_chain, levels); !e.ok()) return e;
  s.rays.commit();
  if (Error e = s.occlusion.init(std::max<size_t>(s.objects, 1), params.occlusion); !e.ok()) return e;
  SelectorConfig cfg;
  cfg.max_object_count = std::max<size_t>(s.objects, 1);
  cfg.max_levels_per_chain = std::max<size_t>(scene.table.maxLevelsPerChain(), 1);
  s.shadow.reset(createSelectorContext(cfg));
  if (!s.shadow) return Error(Status::kOutOfMemory, scene.name + ": cannot create the shadow selector context");
  s.visible.assign(s.objects, 1.0f);
  s.focus.assign(s.objects, 1.0f);
  s.cost.assign(s.objects, 0.0f);
  s.shadow_cost.assign(s.objects, 0.0f);
  s.shadow_levels.assign(s.objects, -1);
  return {};
}

Error ReplayVisibility::beforeSelect(const ReplayScene& scene, const Camera& camera, const ReplayFrame& frame,
                                     SelectionJob& job) {
  State& s = *state_;
  if (scene.objectCount() != s.objects)
    return Error(Status::kInvalidArgument, "visibility was set up for " + std::to_string(s.objects) +
                                               " objects, the scene has " + std::to_string(scene.objectCount()));
  computeObjectWorlds(scene, s.next_world);
  for (size_t i = 0; i < s.objects; ++i)
    if (s.next_world[i] != s.world[i]) s.rays.setTransform(static_cast<uint32_t>(i), s.next_world[i]);
  s.world.swap(s.next_world);
  s.rays.commit();
  s.occlusion.update(s.rays, camera, Span<float>(s.visible.data(), s.visible.size()));
  s.pick_object = -1;
  if (frame.has_pick) {
    // the focus stays on the latest pick until the next one
    const PickHit hit = s.rays.pick(camera, glm::vec2(frame.pick_px[0], frame.pick_px[1]));
    s.pick_object = hit.object;
    if (hit.object >= 0)
      s.focus_params = focusFromPick(s.rays, hit, s.params.focus_radius_scale, s.params.focus_gain);
  }
  computeFocusFactors(s.rays.worldSpheres(), s.focus_params, Span<float>(s.focus.data(), s.focus.size()));
  job.visible_fraction = Span<const float>(s.visible.data(), s.objects);
  if (s.focus_params.enabled) job.focus = Span<const float>(s.focus.data(), s.objects);
  job.cost_ms_out = Span<float>(s.cost.data(), s.objects);
  return {};
}

void ReplayVisibility::afterSelect(const SelectionJob& job, ReplayLogFrame& out) {
  State& s = *state_;
  // the same selection without occlusion: same parameters, focus and cost model
  SelectionJob blind = job;
  blind.visible_fraction = {};
  blind.context = s.shadow.get();
  blind.levels_out = Span<int8_t>(s.shadow_levels.data(), s.objects);
  blind.cost_ms_out = Span<float>(s.shadow_cost.data(), s.objects);
  blind.stats = nullptr;
  blind.params.calibrate = false;
  setSelectorCostModel(s.shadow.get(), selectorCostModel(job.context));
  const bool shadow_ok = blind.run();

  out.has_visibility = true;
  out.visible = s.visible;
  out.pick_object = s.pick_object;
  out.hidden_count = 0;
  out.hidden_cost_ms = out.hidden_cost_without_ms = 0.0;
  for (size_t i = 0; i < s.objects; ++i) {
    if (s.visible[i] >= s.params.hidden_below) continue;
    ++out.hidden_count;
    out.hidden_cost_ms += s.cost[i];
    if (shadow_ok) out.hidden_cost_without_ms += s.shadow_cost[i];
  }
  out.occlusion_saved_ms = out.hidden_cost_without_ms - out.hidden_cost_ms;
  // the levels drawn this frame are what the next pick sees
  for (size_t i = 0; i < s.objects; ++i) s.rays.setDrawnLevel(static_cast<uint32_t>(i), job.levels_out[i]);
}

}  // namespace scenelod::selection
