// Vertex cache ordering: our Forsyth optimiser vs meshopt_optimizeVertexCache, on the bunny and the
// shared glTF models. Reports ACMR (FIFO 16, computeAcmr) before and after as counters, and the
// optimiser's time per triangle. Models missing on disk are skipped.
#include <benchmark/benchmark.h>
#include <meshoptimizer.h>

#include <memory>
#include <string>
#include <vector>

#include "scenelod/lodcore/obj_io.h"
#include "scenelod/scene/gltf_io.h"
#include "scenelod/scene/mesh_order.h"

using namespace scenelod;
using namespace scenelod::scene;

namespace {

std::string sharedModels() {
  const std::string here = __FILE__;  // .../bench/scene/mesh_order_bench.cpp
  return here.substr(0, here.rfind("/bench/")) + "/../shared/models";
}

struct Model {
  std::string name;
  std::vector<Mesh> meshes;  // unique meshes with triangles
};

const char* const kModels[][2] = {{"bunny", ""},
                                  {"2CylinderEngine", "2CylinderEngine.glb"}, {"BrainStem", "BrainStem.glb"},
                                  {"DamagedHelmet", "DamagedHelmet.glb"},     {"Duck", "Duck.glb"},
                                  {"Fox", "Fox.glb"},                         {"SheenChair", "SheenChair.gltf"},
                                  {"SheenCloth", "SheenCloth.gltf"},          {"VC", "VC.glb"}};

// loaded on first use, so filtering other benchmarks costs nothing; null when the file is missing
const Model* model(size_t i) {
  static std::unique_ptr<Model> cache[sizeof kModels / sizeof kModels[0]];
  static bool tried[sizeof kModels / sizeof kModels[0]] = {};
  if (tried[i]) return cache[i].get();
  tried[i] = true;
  auto m = std::make_unique<Model>();
  m->name = kModels[i][0];
  if (i == 0) {
    Mesh mesh;
    if (!readObj(SCENELOD_BUNNY_PATH, mesh).ok()) return nullptr;
    m->meshes.push_back(mesh);
  } else {
    SceneData s;
    if (!loadScene(sharedModels() + "/" + kModels[i][0] + "/" + kModels[i][1], s).ok()) return nullptr;
    for (auto& md : s.meshes)
      if (md.mesh.triangleCount() > 0) m->meshes.push_back(md.mesh);
  }
  cache[i] = std::move(m);
  return cache[i].get();
}

double weightedAcmr(const std::vector<std::vector<uint32_t>>& idx, const Model& model) {
  double sum = 0.0, tris = 0.0;
  for (size_t i = 0; i < idx.size(); ++i) {
    const double t = double(idx[i].size() / 3);
    sum += t * computeAcmr(Span<const uint32_t>(idx[i].data(), idx[i].size()), model.meshes[i].vertexCount());
    tris += t;
  }
  return tris > 0 ? sum / tris : 0.0;
}

void run(benchmark::State& state, size_t index, bool ours) {
  const Model* mp = model(index);
  if (!mp) { state.SkipWithError("model file missing"); return; }
  const Model& model = *mp;
  std::vector<std::vector<uint32_t>> out(model.meshes.size());
  std::vector<std::vector<uint32_t>> in(model.meshes.size());
  size_t tris = 0;
  for (size_t i = 0; i < model.meshes.size(); ++i) {
    in[i] = model.meshes[i].triangles;
    out[i].resize(in[i].size());
    tris += in[i].size() / 3;
  }
  for (auto _ : state) {
    for (size_t i = 0; i < in.size(); ++i) {
      if (ours)
        optimizeVertexCache(Span<uint32_t>(out[i].data(), out[i].size()), Span<const uint32_t>(in[i].data(), in[i].size()),
                            model.meshes[i].vertexCount());
      else
        meshopt_optimizeVertexCache(out[i].data(), in[i].data(), in[i].size(), model.meshes[i].vertexCount());
    }
    benchmark::ClobberMemory();
  }
  state.counters["acmr_before"] = weightedAcmr(in, model);
  state.counters["acmr_after"] = weightedAcmr(out, model);
  state.counters["triangles"] = double(tris);
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(tris));
}

const bool kRegistered = [] {
  for (size_t i = 0; i < sizeof kModels / sizeof kModels[0]; ++i) {
    const std::string name = kModels[i][0];
    benchmark::RegisterBenchmark(("BM_VertexCache_scenelod/" + name).c_str(), [i](benchmark::State& s) { run(s, i, true); })
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("BM_VertexCache_meshopt/" + name).c_str(), [i](benchmark::State& s) { run(s, i, false); })
        ->Unit(benchmark::kMillisecond);
  }
  return true;
}();

}  // namespace
