// Bounding-sphere tightness and speed: Ritter vs the minimal sphere (Welzl move-to-front), on the
// bunny and on every unique mesh of the shared glTF models. Counters: summed radii of each method
// over the model's meshes and the ratio minimal / Ritter (< 1: the minimal sphere is tighter).
#include <benchmark/benchmark.h>

#include <memory>
#include <string>
#include <vector>

#include "scenelod/lodcore/obj_io.h"
#include "scenelod/scene/bounding_sphere.h"
#include "scenelod/scene/gltf_io.h"

using namespace scenelod;
using namespace scenelod::scene;

namespace {

std::string sharedModels() {
  const std::string here = __FILE__;
  return here.substr(0, here.rfind("/bench/")) + "/../shared/models";
}

struct Model {
  std::string name;
  std::vector<std::vector<glm::vec3>> meshes;
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
    m->meshes.push_back(mesh.positions);
  } else {
    SceneData s;
    if (!loadScene(sharedModels() + "/" + kModels[i][0] + "/" + kModels[i][1], s).ok()) return nullptr;
    for (auto& md : s.meshes)
      if (!md.mesh.positions.empty()) m->meshes.push_back(md.mesh.positions);
  }
  cache[i] = std::move(m);
  return cache[i].get();
}

void run(benchmark::State& state, size_t index, bool minimal) {
  const Model* mp = model(index);
  if (!mp) { state.SkipWithError("model file missing"); return; }
  const Model& model = *mp;
  double radius_sum = 0.0, other_sum = 0.0;
  size_t points = 0;
  for (auto _ : state) {
    radius_sum = 0.0;
    for (const auto& p : model.meshes) {
      const Span<const glm::vec3> s(p.data(), p.size());
      const Sphere sp = minimal ? minimalSphere(s) : ritterSphere(s);
      radius_sum += sp.radius;
      benchmark::DoNotOptimize(sp);
    }
  }
  for (const auto& p : model.meshes) {
    const Span<const glm::vec3> s(p.data(), p.size());
    other_sum += (minimal ? ritterSphere(s) : minimalSphere(s)).radius;
    points += p.size();
  }
  state.counters["meshes"] = double(model.meshes.size());
  state.counters["radius_sum"] = radius_sum;
  state.counters["minimal_over_ritter"] = minimal ? radius_sum / other_sum : other_sum / radius_sum;
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(points));
}

const bool kRegistered = [] {
  for (size_t i = 0; i < sizeof kModels / sizeof kModels[0]; ++i) {
    const std::string name = kModels[i][0];
    benchmark::RegisterBenchmark(("BM_Sphere_ritter/" + name).c_str(), [i](benchmark::State& s) { run(s, i, false); })
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("BM_Sphere_minimal/" + name).c_str(), [i](benchmark::State& s) { run(s, i, true); })
        ->Unit(benchmark::kMillisecond);
  }
  return true;
}();

}  // namespace
