// LOD packs: loading a pack (one read + checks) vs recomputing the chains (buildLods), for the demo
// scene and the shared glTF models. Packs are written once to $TMPDIR before the timed loops.
// Counters: objects, unique meshes, levels (sum over chains), pack bytes.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "scenelod/scene/demo_scene.h"
#include "scenelod/scene/gltf_io.h"
#include "scenelod/scene/lod_build.h"
#include "scenelod/scene/pack.h"

using namespace scenelod;
using namespace scenelod::scene;

namespace {

std::string sharedModels() {
  const std::string here = __FILE__;
  return here.substr(0, here.rfind("/bench/")) + "/../shared/models";
}

struct Model {
  std::string name;
  SceneData scene;
  std::string pack_path;
  size_t levels = 0, pack_bytes = 0;
};

LodBuildParams buildParams() {
  LodBuildParams p;
  p.chain.level_count = 8;
  return p;
}

const char* const kModels[][2] = {{"demo", ""},
                                  {"2CylinderEngine", "2CylinderEngine.glb"}, {"BrainStem", "BrainStem.glb"},
                                  {"DamagedHelmet", "DamagedHelmet.glb"},     {"Duck", "Duck.glb"},
                                  {"Fox", "Fox.glb"},                         {"SheenChair", "SheenChair.gltf"},
                                  {"SheenCloth", "SheenCloth.gltf"},          {"VC", "VC.glb"}};

// built on first use (outside the timed loops), so filtering other benchmarks costs nothing
const Model* model(size_t i, std::string& error) {
  static std::unique_ptr<Model> cache[sizeof kModels / sizeof kModels[0]];
  if (cache[i]) return cache[i].get();
  auto m = std::make_unique<Model>();
  m->name = kModels[i][0];
  if (i == 0) {
    if (Error e = makeDemoScene(m->scene); !e.ok()) { error = e.message; return nullptr; }
  } else if (Error e = loadScene(sharedModels() + "/" + kModels[i][0] + "/" + kModels[i][1], m->scene); !e.ok()) {
    error = e.message;
    return nullptr;
  }
  SceneLods lods;
  if (Error e = buildLods(m->scene, buildParams(), lods); !e.ok()) { error = e.message; return nullptr; }
  for (const LodChain& c : lods.chains) m->levels += c.levelCount();
  const char* tmp = std::getenv("TMPDIR");
  m->pack_path = std::string(tmp ? tmp : "/tmp") + "/scenelod_bench_" + m->name + ".slodpack";
  PackWriteStats stats;
  if (Error e = writePack(m->pack_path, m->scene, lods.chains, lods.chain_spheres, {}, &stats); !e.ok()) {
    error = e.message;
    return nullptr;
  }
  m->pack_bytes = stats.bytes;
  cache[i] = std::move(m);
  return cache[i].get();
}

void counters(benchmark::State& state, const Model& m) {
  state.counters["objects"] = double(objectNodes(m.scene).size());
  state.counters["meshes"] = double(m.scene.meshes.size());
  state.counters["levels"] = double(m.levels);
  state.counters["pack_bytes"] = double(m.pack_bytes);
}

void loadPack(benchmark::State& state, size_t i, bool check_indices) {
  std::string error;
  const Model* mp = model(i, error);
  if (!mp) { state.SkipWithError(error.c_str()); return; }
  const Model& m = *mp;
  for (auto _ : state) {
    Pack p;
    if (Error e = Pack::load(m.pack_path, p, check_indices); !e.ok()) {
      state.SkipWithError(e.message.c_str());
      break;
    }
    benchmark::DoNotOptimize(p.level(0, 0).positions.data);
  }
  counters(state, m);
}

void recompute(benchmark::State& state, size_t i) {
  std::string error;
  const Model* mp = model(i, error);
  if (!mp) { state.SkipWithError(error.c_str()); return; }
  const Model& m = *mp;
  for (auto _ : state) {
    SceneLods lods;
    if (Error e = buildLods(m.scene, buildParams(), lods); !e.ok()) {
      state.SkipWithError(e.message.c_str());
      break;
    }
    benchmark::DoNotOptimize(lods.chains.data());
  }
  counters(state, m);
}

const bool kRegistered = [] {
  for (size_t i = 0; i < sizeof kModels / sizeof kModels[0]; ++i) {
    const std::string name = kModels[i][0];
    benchmark::RegisterBenchmark(("BM_PackLoad/" + name).c_str(), [i](benchmark::State& s) { loadPack(s, i, true); })
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("BM_PackLoadNoIndexCheck/" + name).c_str(),
                                 [i](benchmark::State& s) { loadPack(s, i, false); })
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("BM_BuildLods/" + name).c_str(), [i](benchmark::State& s) { recompute(s, i); })
        ->Unit(benchmark::kMillisecond)->UseRealTime();
  }
  return true;
}();

}  // namespace
