#pragma once
// Synthetic scenes for selection tests: objects on a plane in front of the camera, chains with
// monotone counts and doubling cell widths, filled from a seed.
#include <cstdint>
#include <random>
#include <vector>

#include <glm/vec3.hpp>

#include "scenelod/selection/level_table.h"
#include "scenelod/selection/selector.h"

namespace scenelod::selection::test {

struct SyntheticScene {
  LevelTableData table;
  std::vector<glm::vec3> centers;
  std::vector<float> radii, scales, importance;
  std::vector<uint32_t> chains;
  std::vector<uint8_t> must_draw;
};

// `chain_count` chains of `levels` levels (level 0 width 0, w_k = w1 * 2^(k-1), triangles halving
// with random jitter) and `object_count` objects scattered in a box in front of a camera at the
// origin looking down -z, some behind it when `behind` is set.
inline SyntheticScene makeScene(uint32_t seed, size_t object_count, size_t chain_count, size_t levels,
                                float extent = 100.0f, bool behind = false) {
  SyntheticScene s;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (size_t c = 0; c < chain_count; ++c) {
    std::vector<float> w(levels);
    std::vector<uint32_t> t(levels), v(levels), lp(levels);
    const float w1 = 0.005f + 0.02f * u(rng);
    uint32_t tri = 2000 + static_cast<uint32_t>(u(rng) * 60000.0f);
    for (size_t k = 0; k < levels; ++k) {
      w[k] = k == 0 ? 0.0f : w1 * static_cast<float>(1u << (k - 1));
      t[k] = tri;
      v[k] = tri / 2 + 2;
      lp[k] = k == 0 ? 0 : static_cast<uint32_t>(u(rng) * 50.0f);
      tri = std::max<uint32_t>(4, static_cast<uint32_t>(tri * (0.35f + 0.3f * u(rng))));
    }
    s.table.addChain(Span<const float>(w.data(), w.size()), Span<const uint32_t>(t.data(), t.size()),
                     Span<const uint32_t>(v.data(), v.size()), Span<const uint32_t>(lp.data(), lp.size()));
  }
  for (size_t i = 0; i < object_count; ++i) {
    const float z = behind && u(rng) < 0.2f ? 2.0f + extent * u(rng) : -(2.0f + extent * u(rng));
    s.centers.push_back({(u(rng) - 0.5f) * extent, (u(rng) - 0.5f) * extent * 0.5f, z});
    s.radii.push_back(0.3f + 2.0f * u(rng));
    s.scales.push_back(0.5f + u(rng));
    s.importance.push_back(0.5f + u(rng));
    s.chains.push_back(static_cast<uint32_t>(rng() % chain_count));
    s.must_draw.push_back(0);
  }
  return s;
}

// A camera at `eye` looking down -z.
inline Camera makeCamera(const glm::vec3& eye = glm::vec3(0.0f)) {
  Camera c;
  c.eye = eye;
  c.target = eye + glm::vec3(0.0f, 0.0f, -1.0f);
  c.near_plane = 0.1f;
  c.far_plane = 10000.0f;
  return c;
}

// A job over the scene; outputs go to `levels` (resized here).
inline SelectionJob makeJob(const SyntheticScene& s, SelectorContext* ctx, const Camera* cam, std::vector<int8_t>& levels,
                            SelectionStats* stats) {
  levels.assign(s.centers.size(), 0);
  SelectionJob job;
  job.camera = cam;
  job.levels = s.table.view();
  job.centers = Span<const glm::vec3>(s.centers.data(), s.centers.size());
  job.radii = Span<const float>(s.radii.data(), s.radii.size());
  job.max_scales = Span<const float>(s.scales.data(), s.scales.size());
  job.chains = Span<const uint32_t>(s.chains.data(), s.chains.size());
  job.importance = Span<const float>(s.importance.data(), s.importance.size());
  job.must_draw = Span<const uint8_t>(s.must_draw.data(), s.must_draw.size());
  job.levels_out = Span<int8_t>(levels.data(), levels.size());
  job.stats = stats;
  job.context = ctx;
  return job;
}

// a selector context destroyed with the test's scope
struct Owned {
  SelectorContext* ctx;
  explicit Owned(SelectorContext* c) : ctx(c) {}
  ~Owned() { destroySelectorContext(ctx); }
  Owned(const Owned&) = delete;
  Owned& operator=(const Owned&) = delete;
};

inline SelectorContext* makeContext(size_t objects, size_t bracket = 4096) {
  SelectorConfig cfg;
  cfg.max_object_count = objects;
  cfg.bracket_capacity = bracket;
  return createSelectorContext(cfg);
}

}  // namespace scenelod::selection::test
