// SCROOGE (Reddy 1996) quality on the shared models and the bunny at sub-volumes of 1/64, 1/8 and 1
// of the bounding volume (§8), next to floating-cell clustering (Low & Tan, ClusterParams defaults) at
// the same cell size (the longest sub-volume edge): the timed loop is the reduction; after it, the symmetric Hausdorff
// and RMS surface distances (relative to the bbox diagonal, eval/metrics.h) and the image error over
// the 14 standard views (eval/render.h) are reported as counters. BM_ScroogePictureGrid renders every
// model and level into one PNG when $SCENELOD_SCROOGE_GRID names the file to write.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>
#include <string>

#include "lodcore/scrooge_models.h"
#include "scenelod/eval/image.h"
#include "scenelod/eval/metrics.h"
#include "scenelod/eval/render.h"
#include "scenelod/eval/text.h"
#include "scenelod/lodcore/cluster.h"
#include "scenelod/lodcore/scrooge.h"

namespace {

using namespace scenelod;

const char* fractionName(int divisions) { return divisions == 4 ? "1/64" : divisions == 2 ? "1/8" : "1"; }

Error reduce(const Mesh& mesh, int divisions, Mesh& out, ScroogeStats* st) {
  ScroogeParams p;
  p.subvolume_size = scroogeSubvolumeForDivisions(computeBounds(mesh), divisions);
  return scroogeMesh(mesh, p, out, st);
}

// floating-cell clustering with the cell width of the sub-volume's longest edge
Error clusterAtSubvolume(const Mesh& mesh, int divisions, Mesh& out) {
  const glm::vec3 s = scroogeSubvolumeForDivisions(computeBounds(mesh), divisions);
  ClusterParams cp;
  cp.cell_width = std::max({s.x, s.y, s.z});
  return clusterMesh(mesh, cp, out);
}

void runQuality(benchmark::State& state, const std::string& name, int divisions, bool cluster) {
  std::string error;
  const Mesh* m = bench::loadModel(name, error);
  if (!m) {
    state.SkipWithError(("cannot read " + name + ": " + error).c_str());
    for (auto _ : state) {}
    return;
  }
  Mesh out;
  ScroogeStats st;
  for (auto _ : state) {
    if (Error e = cluster ? clusterAtSubvolume(*m, divisions, out) : reduce(*m, divisions, out, &st); !e.ok()) {
      state.SkipWithError(e.message.c_str());
      return;
    }
  }
  if (cluster) st.output_polygons = st.output_triangles = out.triangleCount();
  eval::DistanceResult d;
  if (Error e = eval::measureSurfaceDistance(*m, out, eval::DistanceParams{}, d); !e.ok()) {
    state.SkipWithError(e.message.c_str());
    return;
  }
  eval::ImageErrorResult img;
  if (Error e = eval::measureImageError(*m, out, eval::ImageErrorParams{}, img); !e.ok()) {
    state.SkipWithError(e.message.c_str());
    return;
  }
  state.counters["in_tris"] = double(m->triangleCount());
  state.counters["polys"] = double(st.output_polygons);
  state.counters["tris"] = double(st.output_triangles);
  state.counters["hausdorff_rel"] = d.hausdorff;
  state.counters["rms_rel"] = d.rms;
  state.counters["silhouette"] = img.silhouette;
  state.counters["normal_deg"] = img.normal_deg;
}

void BM_ScroogePictureGrid(benchmark::State& state) {
  const char* path = std::getenv("SCENELOD_SCROOGE_GRID");
  if (!path) {
    state.SkipWithError("set SCENELOD_SCROOGE_GRID to the PNG to write");
    for (auto _ : state) {}
    return;
  }
  const int cell = 160, label = 12;
  const std::vector<std::string>& names = bench::scroogeModelNames();
  const std::vector<std::string> columns = {"original",     "scrooge 1/64", "scrooge 1/8", "scrooge 1",
                                            "cluster 1/64", "cluster 1/8",  "cluster 1"};
  for (auto _ : state) {
    eval::Image grid(int(columns.size()) * cell, int(names.size()) * (cell + label) + label);
    for (size_t c = 0; c < columns.size(); ++c)
      eval::drawText(grid, int(c) * cell + 4, 2, columns[c], eval::Rgb8{0, 0, 0});
    for (size_t r = 0; r < names.size(); ++r) {
      std::string error;
      const Mesh* m = bench::loadModel(names[r], error);
      if (!m) continue;
      eval::RenderParams rp;
      rp.width = rp.height = cell;
      rp.frame = eval::boundingSphere(*m);  // one scale per row
      const int y = label + int(r) * (cell + label);
      for (size_t c = 0; c < columns.size(); ++c) {
        Mesh level;
        ScroogeStats st;
        const Mesh* shown = m;
        if (c > 0) {
          const int divisions = (c - 1) % 3 == 0 ? 4 : (c - 1) % 3 == 1 ? 2 : 1;
          if (Error e = c <= 3 ? reduce(*m, divisions, level, &st) : clusterAtSubvolume(*m, divisions, level); !e.ok()) continue;
          shown = &level;
        }
        eval::Image img;
        if (Error e = eval::renderMesh(*shown, rp, img); !e.ok()) continue;
        eval::blit(grid, img, int(c) * cell, y + label);
        eval::drawText(grid, int(c) * cell + 4, y + 2,
                       names[r] + " " + std::to_string(shown->triangleCount()) + " tris", eval::Rgb8{0, 0, 0});
      }
    }
    if (Error e = eval::writePng(path, grid); !e.ok()) state.SkipWithError(e.message.c_str());
  }
}
BENCHMARK(BM_ScroogePictureGrid)->Unit(benchmark::kMillisecond)->Iterations(1);

struct RegisterModels {
  RegisterModels() {
    for (const std::string& name : bench::scroogeModelNames())
      for (int divisions : {4, 2, 1})
      for (bool cluster : {false, true})
        benchmark::RegisterBenchmark(
            ((cluster ? "BM_ClusterQuality/" : "BM_ScroogeQuality/") + name + "/" + fractionName(divisions)).c_str(),
            [name, divisions, cluster](benchmark::State& state) { runQuality(state, name, divisions, cluster); })
            ->Unit(benchmark::kMillisecond)
            ->Iterations(1);
  }
} register_models;

}  // namespace
