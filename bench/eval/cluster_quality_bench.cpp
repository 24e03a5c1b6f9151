// Quality of vertex clustering against meshoptimizer at matched triangle counts: symmetric Hausdorff
// and RMS surface distance (scenelod::eval, relative to the bounding-box diagonal). Each benchmark
// runs once (the "time" column is the simplification plus the measurement) and reports counters.
// Models: the bunny, plus every OBJ listed in SCENELOD_QUALITY_MODELS (colon-separated; convert glTF
// models with `scenelod convert IN.glb OUT.obj`, which flattens them into world space).
#include <cstdlib>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <meshoptimizer.h>

#include "scenelod/eval/metrics.h"
#include "scenelod/lodcore/chain.h"
#include "scenelod/lodcore/cluster.h"
#include "scenelod/lodcore/obj_io.h"

using namespace scenelod;

namespace {

struct Config {
  const char* name;
  LodMethod method;
  Grading grading;
  Synthesis synthesis;
  CellShape shape;
};

const Config kConfigs[] = {
    {"nearest-quadric", LodMethod::kFloatingNearest, Grading::kLowTan, Synthesis::kQuadric, CellShape::kCube},
    {"nearest-mean", LodMethod::kFloatingNearest, Grading::kLowTan, Synthesis::kMean, CellShape::kCube},
    {"nearest-heaviest", LodMethod::kFloatingNearest, Grading::kLowTan, Synthesis::kHeaviest, CellShape::kCube},
    {"heaviest-quadric", LodMethod::kFloatingHeaviest, Grading::kLowTan, Synthesis::kQuadric, CellShape::kCube},
    {"heaviest-mean", LodMethod::kFloatingHeaviest, Grading::kLowTan, Synthesis::kMean, CellShape::kCube},
    {"heaviest-heaviest", LodMethod::kFloatingHeaviest, Grading::kLowTan, Synthesis::kHeaviest, CellShape::kCube},
    {"nearest-quadric-sphere", LodMethod::kFloatingNearest, Grading::kLowTan, Synthesis::kQuadric, CellShape::kSphere},
    {"nearest-quadric-rossignac", LodMethod::kFloatingNearest, Grading::kRossignac, Synthesis::kQuadric, CellShape::kCube},
    {"uniform-quadric", LodMethod::kUniform, Grading::kLowTan, Synthesis::kQuadric, CellShape::kCube},
    {"uniform-mean", LodMethod::kUniform, Grading::kLowTan, Synthesis::kMean, CellShape::kCube},
};

Mesh trianglesOnly(const Mesh& m) {
  Mesh t = m;
  t.edges.clear();
  t.edge_thickness.clear();
  t.points.clear();
  return t;
}

void report(benchmark::State& state, const Mesh& original, const Mesh& simplified, bool with_lines) {
  eval::DistanceResult tri, all;
  const Mesh t = trianglesOnly(simplified);
  if (!t.triangles.empty()) eval::measureSurfaceDistance(original, t, eval::DistanceParams(), tri);
  state.counters["tris"] = double(simplified.triangleCount());
  state.counters["tri_frac"] = double(simplified.triangleCount()) / double(original.triangleCount());
  state.counters["hausdorff_tri"] = tri.hausdorff;
  state.counters["rms_tri"] = tri.rms;
  if (with_lines && (simplified.edgeCount() || simplified.pointCount())) {
    eval::measureSurfaceDistance(original, simplified, eval::DistanceParams(), all);
    state.counters["hausdorff_all"] = all.hausdorff;
    state.counters["rms_all"] = all.rms;
    state.counters["edges"] = double(simplified.edgeCount());
    state.counters["points"] = double(simplified.pointCount());
  }
}

struct Model {
  std::string name;
  Mesh mesh;
  bool cad;
};

std::vector<Model>& models() {
  static std::vector<Model> list = [] {
    std::vector<Model> out;
    Model bunny{"bunny", {}, false};
    if (readObj(SCENELOD_BUNNY_PATH, bunny.mesh).ok()) out.push_back(std::move(bunny));
    if (const char* env = std::getenv("SCENELOD_QUALITY_MODELS")) {
      std::string s = env;
      size_t b = 0;
      while (b <= s.size()) {
        const size_t e = s.find(':', b) == std::string::npos ? s.size() : s.find(':', b);
        const std::string path = s.substr(b, e - b);
        Model m{path.substr(path.find_last_of('/') + 1), {}, true};
        if (!path.empty() && readObj(path, m.mesh).ok()) out.push_back(std::move(m));
        b = e + 1;
      }
    }
    return out;
  }();
  return list;
}

void registerAll() {
  for (size_t mi = 0; mi < models().size(); ++mi) {
    const Model& model = models()[mi];
    const std::vector<int> percents = model.cad ? std::vector<int>{10, 5, 1} : std::vector<int>{20, 10, 5, 2};
    for (int pct : percents) {
      const size_t target = model.mesh.triangleCount() * size_t(pct) / 100;
      for (const Config& c : kConfigs) {
        benchmark::RegisterBenchmark((model.name + "/" + std::to_string(pct) + "%/" + c.name).c_str(),
                                     [mi, target, c](benchmark::State& state) {
                                       const Model& m = models()[mi];
                                       ClusterParams p;
                                       p.method = c.method;
                                       p.grading = c.grading;
                                       p.synthesis = c.synthesis;
                                       p.cell_shape = c.shape;
                                       Mesh out;
                                       for (auto _ : state) {
                                         findCellWidthForTarget(m.mesh, p, target, p.cell_width, 0.01);
                                         clusterMesh(m.mesh, p, out);
                                       }
                                       report(state, m.mesh, out, m.cad);
                                       state.counters["cell_rel"] = p.cell_width / computeBounds(m.mesh).diagonal();
                                     })
            ->Iterations(1)
            ->Unit(benchmark::kMillisecond);
      }
      for (int sloppy = 1; sloppy >= 0; --sloppy) {
        benchmark::RegisterBenchmark((model.name + "/" + std::to_string(pct) + "%/" +
                                      (sloppy ? "meshopt-sloppy" : "meshopt-simplify")).c_str(),
                                     [mi, target, sloppy](benchmark::State& state) {
                                       const Mesh& m = models()[mi].mesh;
                                       Mesh out;
                                       out.positions = m.positions;
                                       out.triangles.resize(m.triangles.size());
                                       for (auto _ : state) {
                                         size_t n = sloppy
                                             ? meshopt_simplifySloppy(out.triangles.data(), m.triangles.data(),
                                                                      m.triangles.size(), &m.positions[0].x,
                                                                      m.positions.size(), sizeof(glm::vec3),
                                                                      target * 3, 1.0f, nullptr)
                                             : meshopt_simplify(out.triangles.data(), m.triangles.data(),
                                                                m.triangles.size(), &m.positions[0].x, m.positions.size(),
                                                                sizeof(glm::vec3), target * 3, 1.0f, 0, nullptr);
                                         out.triangles.resize(n);
                                       }
                                       report(state, m, out, false);
                                     })
            ->Iterations(1)
            ->Unit(benchmark::kMillisecond);
      }
    }
  }
}

const int kRegistered = (registerAll(), 0);

}  // namespace
