// Bounding-sphere tightness and speed: Ritter vs the minimal sphere (Welzl move-to-front), on the
// bunny and on every unique mesh of the shared glTF models. Counters: summed radii of each method
// over the model's meshes and the ratio minimal / Ritter (< 1: the minimal sphere is tighter).
#include <benchmark/benchmark.h>

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

const std::vector<Model>& models() {
  static const std::vector<Model> all = [] {
    std::vector<Model> out;
    Mesh m;
    if (!readObj(SCENELOD_BUNNY_PATH, m)) out.push_back({"bunny", {m.positions}});
    const char* names[][2] = {{"2CylinderEngine", "2CylinderEngine.glb"}, {"BrainStem", "BrainStem.glb"},
                              {"DamagedHelmet", "DamagedHelmet.glb"},     {"Duck", "Duck.glb"},
                              {"Fox", "Fox.glb"},                         {"SheenChair", "SheenChair.gltf"},
                              {"SheenCloth", "SheenCloth.gltf"},          {"VC", "VC.glb"}};
    for (auto& n : names) {
      SceneData s;
      if (loadScene(sharedModels() + "/" + n[0] + "/" + n[1], s)) continue;
      Model model{n[0], {}};
      for (auto& md : s.meshes)
        if (!md.mesh.positions.empty()) model.meshes.push_back(md.mesh.positions);
      out.push_back(model);
    }
    return out;
  }();
  return all;
}

void run(benchmark::State& state, const Model& model, bool minimal) {
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
  for (const Model& m : models()) {
    benchmark::RegisterBenchmark(("BM_Sphere_ritter/" + m.name).c_str(), [&m](benchmark::State& s) { run(s, m, false); })
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("BM_Sphere_minimal/" + m.name).c_str(), [&m](benchmark::State& s) { run(s, m, true); })
        ->Unit(benchmark::kMillisecond);
  }
  return true;
}();

}  // namespace
