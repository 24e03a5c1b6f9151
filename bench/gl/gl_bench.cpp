// The OpenGL adapter's level transitions (docs/GL.md, "Level transitions"): what the geomorph in
// the vertex shader and the dithered cross-fade cost per frame. A grid of Stanford bunnies (one
// chain, default clustering parameters, morph targets on) is drawn by scenelod::gl into a 640x360
// offscreen target, every object at one level:
//   Disabled  chains uploaded without morph data, no morph span (the vertex size of plain levels)
//   Factor0   morph targets uploaded, every factor 0
//   Factor05  every factor 0.5
//   Fade05    no morph; every object fading at 0.5 from the next coarser level (drawn twice,
//             complementary dither masks)
// Arguments: objects per side, level. Times are wall time per drawFrame (it ends with glFinish;
// llvmpipe's rasteriser threads do the work). Skips (an error in the output) where EGL cannot start.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include <benchmark/benchmark.h>

#include <glm/gtc/matrix_transform.hpp>

#include "scenelod/gl/renderer.h"
#include "scenelod/lodcore/chain.h"
#include "scenelod/lodcore/obj_io.h"

using namespace scenelod;

namespace {

const LodChain& bunnyChain() {
  static LodChain chain = [] {
    Mesh b;
    if (Error e = readObj(SCENELOD_BUNNY_PATH, b); !e.ok()) {
      std::fprintf(stderr, "gl_bench: %s\n", e.message.c_str());
      std::exit(1);
    }
    ChainParams cp;
    cp.level_count = 6;
    LodChain c;
    if (Error e = buildChain(b, cp, c); !e.ok()) {
      std::fprintf(stderr, "gl_bench: %s\n", e.message.c_str());
      std::exit(1);
    }
    return c;
  }();
  return chain;
}

// one renderer for the whole run (an EGL context per benchmark would be wasteful); null when EGL
// cannot start
gl::Renderer* renderer() {
  static gl::Renderer* r = [] {
    auto* g = new gl::Renderer;
    gl::RendererConfig rc;
    rc.width_px = 640;
    rc.height_px = 360;
    if (Error e = g->init(rc); !e.ok()) {
      std::fprintf(stderr, "gl_bench: %s\n", e.message.c_str());
      delete g;
      return static_cast<gl::Renderer*>(nullptr);
    }
    std::fprintf(stderr, "gl_bench: %s\n", g->description().c_str());
    return g;
  }();
  return r;
}

enum class Mode { kDisabled, kFactor0, kFactor05, kFade05 };

void BM_GlTransitions(benchmark::State& state, Mode mode) {
  gl::Renderer* g = renderer();
  if (!g) {
    state.SkipWithError("EGL cannot start");
    return;
  }
  const LodChain& chain = bunnyChain();
  const int side = static_cast<int>(state.range(0));
  const int8_t level = static_cast<int8_t>(state.range(1));
  if (static_cast<size_t>(level) + 1 >= chain.levels.size()) {
    state.SkipWithError("the chain has too few levels");
    return;
  }
  LodChain uploaded = chain;
  if (mode == Mode::kDisabled)
    for (LodLevel& l : uploaded.levels) l.morph = LevelMorph{};
  if (Error e = g->uploadChains({uploaded}); !e.ok()) {
    state.SkipWithError(e.message.c_str());
    return;
  }
  // a side x side grid of bunnies scaled to radius 1, 2.2 apart, filling the view
  const Sphere& b = chain.levels[0].bounds;
  const size_t n = static_cast<size_t>(side) * side;
  std::vector<glm::mat4> world(n);
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) {
      const glm::vec3 at(2.2f * (x - 0.5f * (side - 1)), 2.2f * (y - 0.5f * (side - 1)), 0.0f);
      world[static_cast<size_t>(y) * side + x] =
          glm::scale(glm::translate(glm::mat4(1.0f), at), glm::vec3(1.0f / b.radius)) * glm::translate(glm::mat4(1.0f), -b.center);
    }
  selection::Camera cam;
  cam.viewport_width_px = 640;
  cam.viewport_height_px = 360;
  cam.fov_y_rad = 0.7853982f;
  cam.eye = {0.0f, 0.0f, 1.1f * 1.1f * side / std::tan(0.5f * cam.fov_y_rad) + 1.0f};
  cam.near_plane = 0.1f;
  cam.far_plane = 1000.0f;
  const std::vector<uint32_t> chains(n, 0);
  const std::vector<int8_t> levels(n, level), previous(n, static_cast<int8_t>(level + 1));
  const std::vector<float> factors(n, mode == Mode::kFactor05 ? 0.5f : 0.0f), fades(n, 0.5f);
  gl::FrameInput in;
  in.camera = &cam;
  in.object_world = {world.data(), n};
  in.object_chain = {chains.data(), n};
  in.levels = {levels.data(), n};
  if (mode == Mode::kFactor0 || mode == Mode::kFactor05) in.morph = {factors.data(), n};
  if (mode == Mode::kFade05) {
    in.previous_levels = {previous.data(), n};
    in.fade = {fades.data(), n};
  }
  gl::FrameResult r;
  if (!g->drawFrame(in, &r)) {  // once unmeasured: shader variants compile on first use
    state.SkipWithError("drawFrame refused the input");
    return;
  }
  for (auto _ : state) g->drawFrame(in, &r);
  state.counters["triangles"] = static_cast<double>(r.triangles);
  state.counters["draws"] = r.draw_calls;
  state.counters["gpu_MB"] = static_cast<double>(g->gpuBytes()) / 1e6;
}

void args(benchmark::internal::Benchmark* b) {
  b->Args({4, 0})->Args({8, 2})->Unit(benchmark::kMillisecond)->UseRealTime();
}

}  // namespace

BENCHMARK_CAPTURE(BM_GlTransitions, Disabled, Mode::kDisabled)->Apply(args);
BENCHMARK_CAPTURE(BM_GlTransitions, Factor0, Mode::kFactor0)->Apply(args);
BENCHMARK_CAPTURE(BM_GlTransitions, Factor05, Mode::kFactor05)->Apply(args);
BENCHMARK_CAPTURE(BM_GlTransitions, Fade05, Mode::kFade05)->Apply(args);
