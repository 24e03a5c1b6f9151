// World-sphere update of the runtime scene graph: N objects, every node moved every frame.
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "scenelod/scene/scene.h"

using namespace scenelod;
using namespace scenelod::scene;

namespace {

struct Fixture {
  Scene scene;
  std::vector<NodeHandle> nodes;
  std::vector<glm::mat4> poses[2];
};

// n objects on n nodes: a root per 100 objects (a "vehicle"), each object on a child node, so the
// update pass has real parent-child products; 8 chains
void build(Fixture& f, size_t n) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-100.0f, 100.0f), s(0.5f, 2.0f);
  f.scene.setChainCount(8);
  for (uint32_t c = 0; c < 8; ++c) f.scene.setChainSphere(c, Sphere{{0.1f * c, 0.0f, 0.0f}, 1.0f + c});
  NodeHandle root;
  for (size_t i = 0; i < n; ++i) {
    if (i % 100 == 0) f.scene.addNode({}, glm::translate(glm::mat4(1.0f), glm::vec3(u(rng), 0, u(rng))), root);
    Trs t;
    t.translation = {u(rng) * 0.1f, u(rng) * 0.1f, u(rng) * 0.1f};
    t.rotation = glm::angleAxis(u(rng), glm::normalize(glm::vec3(u(rng), u(rng), u(rng) + 200.0f)));
    t.scale = {s(rng), s(rng), s(rng)};
    NodeHandle h;
    f.scene.addNode(root, composeTrs(t), h);
    f.nodes.push_back(h);
    ObjectHandle o;
    f.scene.addObject(ObjectDesc{h, uint32_t(i % 8)}, o);
    for (int k = 0; k < 2; ++k) {
      t.translation += glm::vec3(0.01f);
      f.poses[k].push_back(composeTrs(t));
    }
  }
  f.scene.update();
}

enum class Moves { kSetLocal, kSetLocals };

// one frame per iteration: every object's node gets a new local transform (one setLocal call per
// node, or one setLocals call for all), then, when asked, one update(): transforms + spheres
void moveFrames(benchmark::State& state, Moves moves, bool update) {
  Fixture f;
  const size_t n = static_cast<size_t>(state.range(0));
  build(f, n);
  int frame = 0;
  const Span<const NodeHandle> nodes(f.nodes.data(), n);
  for (auto _ : state) {
    const auto& pose = f.poses[frame++ & 1];
    if (moves == Moves::kSetLocals) {
      benchmark::DoNotOptimize(f.scene.setLocals(nodes, Span<const glm::mat4>(pose.data(), n)).ok());
    } else {
      for (size_t i = 0; i < n; ++i) f.scene.setLocal(f.nodes[i], pose[i]);
    }
    if (update) benchmark::DoNotOptimize(f.scene.update());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(n));
}

void BM_MoveAllAndUpdate(benchmark::State& state) { moveFrames(state, Moves::kSetLocal, true); }
BENCHMARK(BM_MoveAllAndUpdate)->Arg(1000)->Arg(10000)->Arg(100000)->Unit(benchmark::kMicrosecond);

// the split of the above: update() alone after every node got a new local transform (the
// setLocal loop runs with the timer paused)
void BM_UpdateAfterMoveAll(benchmark::State& state) {
  Fixture f;
  const size_t n = static_cast<size_t>(state.range(0));
  build(f, n);
  int frame = 0;
  for (auto _ : state) {
    state.PauseTiming();
    const auto& pose = f.poses[frame++ & 1];
    for (size_t i = 0; i < n; ++i) f.scene.setLocal(f.nodes[i], pose[i]);
    state.ResumeTiming();
    benchmark::DoNotOptimize(f.scene.update());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(n));
}
BENCHMARK(BM_UpdateAfterMoveAll)->Arg(10000)->Arg(100000)->Unit(benchmark::kMicrosecond);

// and the setLocal calls alone (no update: the nodes just stay dirty)
void BM_SetLocalAll(benchmark::State& state) { moveFrames(state, Moves::kSetLocal, false); }
BENCHMARK(BM_SetLocalAll)->Arg(10000)->Arg(100000)->Unit(benchmark::kMicrosecond);

// the frame through the batch call (the engine hands over its poses as an array), with update()
// and alone
void BM_SetLocalsAndUpdate(benchmark::State& state) { moveFrames(state, Moves::kSetLocals, true); }
BENCHMARK(BM_SetLocalsAndUpdate)->Arg(10000)->Arg(100000)->Unit(benchmark::kMicrosecond);
void BM_SetLocalsAll(benchmark::State& state) { moveFrames(state, Moves::kSetLocals, false); }
BENCHMARK(BM_SetLocalsAll)->Arg(10000)->Arg(100000)->Unit(benchmark::kMicrosecond);

// the sphere part alone: chain spheres change (every object dirty) but no node moved
void BM_WorldSpheresOnly(benchmark::State& state) {
  Fixture f;
  const size_t n = static_cast<size_t>(state.range(0));
  build(f, n);
  for (auto _ : state) {
    f.scene.setChainCount(8);  // marks every object's sphere dirty, O(1)
    benchmark::DoNotOptimize(f.scene.update());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(n));
}
BENCHMARK(BM_WorldSpheresOnly)->Arg(100000)->Unit(benchmark::kMicrosecond);

// nothing moved: the cost of an idle update (flag scans)
void BM_IdleUpdate(benchmark::State& state) {
  Fixture f;
  const size_t n = static_cast<size_t>(state.range(0));
  build(f, n);
  for (auto _ : state) benchmark::DoNotOptimize(f.scene.update());
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(n));
}
BENCHMARK(BM_IdleUpdate)->Arg(100000)->Unit(benchmark::kMicrosecond);

}  // namespace
