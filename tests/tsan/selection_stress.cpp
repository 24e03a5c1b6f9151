// ThreadSanitizer stress of the selector: selection on the main thread while a "render" thread
// reports frame times through reportFrameTime. Built and run by scripts/selection-tsan (not by CMake).
#include <atomic>
#include <cstdio>
#include <thread>
#include <vector>
#include "scenelod/selection/level_table.h"
#include "scenelod/selection/selector.h"
using namespace scenelod; using namespace scenelod::selection;
int main() {
  LevelTableData t;
  float w[4] = {0, 0.01f, 0.02f, 0.04f}; uint32_t tri[4] = {4000, 1000, 250, 60}, v[4] = {2000, 500, 130, 32}, lp[4] = {0, 0, 5, 5};
  t.addChain(Span<const float>(w, 4), Span<const uint32_t>(tri, 4), Span<const uint32_t>(v, 4), Span<const uint32_t>(lp, 4));
  const size_t n = 2000;
  std::vector<glm::vec3> c(n); std::vector<float> r(n, 1.0f), s(n, 1.0f); std::vector<uint32_t> ch(n, 0); std::vector<int8_t> lv(n);
  for (size_t i = 0; i < n; ++i) c[i] = glm::vec3(float(i % 50) * 3 - 75, 0, -float(i / 50) * 3 - 5);
  SelectorConfig cfg; cfg.max_object_count = n; SelectorContext* ctx = createSelectorContext(cfg);
  std::atomic<uint64_t> published{0}; std::atomic<bool> done{false};
  std::thread render([&] { uint64_t seen = 0; while (!done.load(std::memory_order_acquire)) { uint64_t f = published.load(std::memory_order_acquire); if (f != seen) { seen = f; reportFrameTime(ctx, f - 1, 2.0f + 0.01f * float(f % 5)); } } });
  SelectionStats st; size_t frames = 0;
  for (int k = 0; k < 3000; ++k) {
    Camera cam; cam.eye = glm::vec3(0, 2, 10 - 0.01f * k); cam.target = cam.eye + glm::vec3(0, 0, -1);
    SelectionJob j; j.camera = &cam; j.levels = t.view(); j.centers = Span<const glm::vec3>(c.data(), n); j.radii = Span<const float>(r.data(), n);
    j.max_scales = Span<const float>(s.data(), n); j.chains = Span<const uint32_t>(ch.data(), n); j.levels_out = Span<int8_t>(lv.data(), n);
    j.stats = &st; j.context = ctx; j.params.budget_ms = 3.0f;
    if (!j.run()) { std::printf("refused\n"); return 1; }
    published.store(st.frame + 1, std::memory_order_release); ++frames;
  }
  done.store(true); render.join();
  std::printf("frames %zu, per_frame_ms %.4f, per_triangle_ms %.3g\n", frames, selectorCostModel(ctx).per_frame_ms, selectorCostModel(ctx).per_triangle_ms);
  destroySelectorContext(ctx);
}
