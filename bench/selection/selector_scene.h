#pragma once
// The synthetic scene of the selection benchmarks, shared by selector_bench.cpp (Google Benchmark)
// and selector_frames.cpp (a fixed number of frames, for instruction counts under callgrind):
// objects at constant density on a square, 32 chains of 8 levels, a camera orbiting at 15 m.
#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <vector>

#include "scenelod/selection/level_table.h"
#include "scenelod/selection/selector.h"

namespace selection_bench {

using namespace scenelod;
using namespace scenelod::selection;

struct BenchScene {
  LevelTableData table;
  std::vector<glm::vec3> centers;
  std::vector<float> radii, scales, importance;
  std::vector<uint32_t> chains;
  std::vector<int8_t> levels;
  std::vector<int8_t> previous_levels;  // transition outputs (benchmarks with transitions)
  std::vector<float> morph, fade;
  SelectorContext* ctx = nullptr;
  float distance_cost_ms = 0.0f;
  ~BenchScene() { destroySelectorContext(ctx); }
};

// objects on a square of side proportional to sqrt(n) (constant density), 32 chains of 8 levels
inline BenchScene& scene(size_t n) {
  static std::map<size_t, std::unique_ptr<BenchScene>> cache;
  auto& slot = cache[n];
  if (slot) return *slot;
  slot = std::make_unique<BenchScene>();
  BenchScene& s = *slot;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int c = 0; c < 32; ++c) {
    float w[8];
    uint32_t t[8], v[8], lp[8];
    uint32_t tri = 2000 + static_cast<uint32_t>(u(rng) * 40000.0f);
    const float w1 = 0.01f + 0.02f * u(rng);
    for (int k = 0; k < 8; ++k) {
      w[k] = k == 0 ? 0.0f : w1 * std::pow(2.0f, static_cast<float>(k - 1));
      t[k] = tri;
      v[k] = tri / 2;
      lp[k] = k < 2 ? 0 : 20;
      tri = std::max<uint32_t>(8, tri * 2 / 5);
    }
    s.table.addChain(Span<const float>(w, 8), Span<const uint32_t>(t, 8), Span<const uint32_t>(v, 8), Span<const uint32_t>(lp, 8));
  }
  const float side = 10.0f * std::sqrt(static_cast<float>(n));
  for (size_t i = 0; i < n; ++i) {
    s.centers.push_back({(u(rng) - 0.5f) * side, u(rng) * 4.0f, (u(rng) - 0.5f) * side});
    s.radii.push_back(0.5f + 2.0f * u(rng));
    s.scales.push_back(0.5f + u(rng));
    s.importance.push_back(0.5f + u(rng));
    s.chains.push_back(static_cast<uint32_t>(rng() % 32));
  }
  for (auto& m : s.table.has_morph) m = 1;  // read only by frames with transitions
  s.levels.resize(n);
  s.previous_levels.resize(n);
  s.morph.resize(n);
  s.fade.resize(n);
  SelectorConfig cfg;
  cfg.max_object_count = n;
  cfg.max_levels_per_chain = 8;
  s.ctx = createSelectorContext(cfg);
  return s;
}

inline Camera cameraAt(size_t n, double t) {
  const float side = 10.0f * std::sqrt(static_cast<float>(n));
  Camera c;
  const float a = static_cast<float>(t);
  c.eye = glm::vec3(0.3f * side * std::cos(a), 15.0f, 0.3f * side * std::sin(a));
  c.target = glm::vec3(0.0f, 0.0f, 0.0f);
  c.near_plane = 0.1f;
  c.far_plane = 1e6f;
  return c;
}

// The job's transition outputs and mode (morph factors on every level but the last, fades elsewhere).
inline void withTransitions(SelectionJob& j, BenchScene& s, Transitions mode) {
  const size_t n = s.centers.size();
  j.params.transitions = mode;
  j.morph_out = Span<float>(s.morph.data(), n);
  j.previous_levels_out = Span<int8_t>(s.previous_levels.data(), n);
  j.fade_out = Span<float>(s.fade.data(), n);
}

inline SelectionJob job(BenchScene& s, const Camera* cam, SelectionStats* st) {
  SelectionJob j;
  j.camera = cam;
  j.levels = s.table.view();
  const size_t n = s.centers.size();
  j.centers = Span<const glm::vec3>(s.centers.data(), n);
  j.radii = Span<const float>(s.radii.data(), n);
  j.max_scales = Span<const float>(s.scales.data(), n);
  j.chains = Span<const uint32_t>(s.chains.data(), n);
  j.importance = Span<const float>(s.importance.data(), n);
  j.levels_out = Span<int8_t>(s.levels.data(), n);
  j.stats = st;
  j.context = s.ctx;
  return j;
}

// the budget: half of what distance mode would cost from the first camera
inline float budgetFor(BenchScene& s, size_t n) {
  if (s.distance_cost_ms > 0.0f) return 0.5f * s.distance_cost_ms;
  Camera cam = cameraAt(n, 0.0);
  SelectionStats st;
  SelectionJob j = job(s, &cam, &st);
  j.params.mode = SelectionMode::kDistance;
  j.params.calibrate = false;
  j.run();
  s.distance_cost_ms = static_cast<float>(st.predicted_ms);
  resetSelectorHistory(s.ctx);
  return 0.5f * s.distance_cost_ms;
}

}  // namespace selection_bench
