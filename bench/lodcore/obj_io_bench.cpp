// Reading and writing the Stanford bunny (Debian glmark2-data) as OBJ.
#include <cstdio>
#include <string>

#include <benchmark/benchmark.h>

#include "scenelod/lodcore/obj_io.h"

namespace {

void BM_ReadObjBunny(benchmark::State& state) {
  scenelod::Mesh mesh;
  for (auto _ : state) {
    const scenelod::Error e = scenelod::readObj(SCENELOD_BUNNY_PATH, mesh);
    if (!e.ok()) {
      state.SkipWithError(e.message.c_str());
      return;
    }
    benchmark::DoNotOptimize(mesh.positions.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * mesh.triangleCount()));
}
BENCHMARK(BM_ReadObjBunny)->Unit(benchmark::kMillisecond);

void BM_WriteObjBunny(benchmark::State& state) {
  scenelod::Mesh mesh;
  if (scenelod::Error e = scenelod::readObj(SCENELOD_BUNNY_PATH, mesh); !e.ok()) {
    state.SkipWithError(e.message.c_str());
    return;
  }
  const std::string out = "/tmp/scenelod_bench_bunny.obj";
  for (auto _ : state) {
    const scenelod::Error e = scenelod::writeObj(out, mesh);
    if (!e.ok()) {
      state.SkipWithError(e.message.c_str());
      return;
    }
  }
  std::remove(out.c_str());
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * mesh.triangleCount()));
}
BENCHMARK(BM_WriteObjBunny)->Unit(benchmark::kMillisecond);

}  // namespace
