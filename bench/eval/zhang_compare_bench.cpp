// Zhang, Shu & Luo 2003 vision-characteristic simplification against meshopt_simplify on the bunny at
// the paper's Table 1 rates (50, 80, 90, 95 % decimation): time (Google Benchmark) and, measured once
// after the timed loop, the symmetric Hausdorff and RMS surface distance (scenelod::eval, relative to
// the bounding-box diagonal). Plus two one-shot reports: pictures of the bunny at 90 and 95 %
// (BM_ZhangPictures) and plots of time against decimation rate and mesh size (BM_ZhangPlots), written
// as PNG into $SCENELOD_BENCH_OUT (default: the current folder).
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <meshoptimizer.h>

#include "scenelod/eval/metrics.h"
#include "scenelod/eval/plot.h"
#include "scenelod/eval/render.h"
#include "scenelod/lodcore/obj_io.h"
#include "scenelod/lodcore/zhang.h"

using namespace scenelod;

namespace {

const Mesh& bunny() {
  static const Mesh m = [] {
    Mesh b;
    if (!readObj(SCENELOD_BUNNY_PATH, b).ok()) b = Mesh{};
    b.face_offsets.clear();
    b.face_corners.clear();
    return b;
  }();
  return m;
}

// 0: Zhang, the paper's CA-interpolated placement; 1: Zhang onto the chosen neighbour;
// 2: Zhang triangle decimation; 3: meshopt_simplify (target error 1, no options)
const char* kMethodNames[] = {"zhang-interpolated", "zhang-neighbour", "zhang-triangle", "meshopt"};

Error simplifyWith(int method, const Mesh& in, size_t target, Mesh& out, ZhangStats* stats = nullptr) {
  if (method == 3) {
    out = Mesh{};
    out.positions = in.positions;
    out.triangles.resize(in.triangles.size());
    const size_t n = meshopt_simplify(out.triangles.data(), in.triangles.data(), in.triangles.size(), &in.positions[0].x,
                                      in.positions.size(), sizeof(glm::vec3), 3 * target, 1.0f, 0, nullptr);
    out.triangles.resize(n);
    return {};
  }
  ZhangParams p;
  p.placement = method == 1 ? ZhangPlacement::kNeighbour : ZhangPlacement::kInterpolated;
  p.mode = method == 2 ? ZhangMode::kTriangleDecimation : ZhangMode::kEdgeCollapse;
  return simplifyZhang(in, target, p, out, stats);
}

size_t targetForRate(const Mesh& m, double rate_percent) {
  return static_cast<size_t>(std::llround(m.triangleCount() * (100.0 - rate_percent) / 100.0));
}

double cpuMs(std::clock_t since) { return 1000.0 * static_cast<double>(std::clock() - since) / CLOCKS_PER_SEC; }

std::string outDir() {
  const char* d = std::getenv("SCENELOD_BENCH_OUT");
  return d && *d ? d : ".";
}

// Arg 0: decimation rate in percent; Arg 1: method (kMethodNames)
void BM_ZhangCompareBunny(benchmark::State& state) {
  const Mesh& in = bunny();
  if (in.triangles.empty()) {
    state.SkipWithError("bunny not found");
    return;
  }
  const int method = static_cast<int>(state.range(1));
  const size_t target = targetForRate(in, static_cast<double>(state.range(0)));
  Mesh out;
  ZhangStats st;
  for (auto _ : state) {
    if (Error e = simplifyWith(method, in, target, out, &st); !e.ok()) state.SkipWithError(e.message.c_str());
    benchmark::DoNotOptimize(out.triangles.data());
  }
  state.SetLabel(kMethodNames[method]);
  eval::DistanceResult d;
  if (Error e = eval::measureSurfaceDistance(in, out, eval::DistanceParams{}, d); !e.ok()) {
    state.SkipWithError(e.message.c_str());
    return;
  }
  state.counters["out_tris"] = static_cast<double>(out.triangleCount());
  state.counters["hausdorff_rel"] = d.hausdorff;
  state.counters["rms_rel"] = d.rms;
  state.counters["forward_max_rel"] = d.forward.max / d.diagonal;
  if (method != 3) {  // the level error the chain records, and the bound its cell width comes from
    state.counters["displacement_rel"] = st.max_displacement / d.diagonal;
    state.counters["surface_bound_rel"] = st.max_surface_distance / d.diagonal;
  }
}

BENCHMARK(BM_ZhangCompareBunny)->ArgsProduct({{50, 80, 90, 95}, {0, 1, 2, 3}})->Unit(benchmark::kMillisecond);

// bunny renders: columns original / zhang-interpolated / zhang-neighbour / meshopt, rows 90 % and 95 %
void BM_ZhangPictures(benchmark::State& state) {
  const Mesh& in = bunny();
  if (in.triangles.empty()) {
    state.SkipWithError("bunny not found");
    return;
  }
  for (auto _ : state) {
    const int tile = 256;
    eval::Image sheet(4 * tile, 2 * tile);
    eval::RenderParams rp;
    rp.width = rp.height = tile;
    rp.view = eval::standardView(4);  // from +z: the bunny's side
    rp.frame = eval::boundingSphere(in);
    rp.smooth = false;  // face normals: the triangulation shows
    for (int row = 0; row < 2; ++row) {
      const size_t target = targetForRate(in, row == 0 ? 90.0 : 95.0);
      for (int col = 0; col < 4; ++col) {
        Mesh m;
        if (col == 0) m = in;
        else if (Error e = simplifyWith(col == 3 ? 3 : col - 1, in, target, m); !e.ok()) state.SkipWithError(e.message.c_str());
        eval::Image img;
        if (Error e = eval::renderMesh(m, rp, img); !e.ok()) {
          state.SkipWithError(e.message.c_str());
          return;
        }
        eval::blit(sheet, img, col * tile, row * tile);
      }
    }
    const std::string path = outDir() + "/zhang_bunny_90_95.png";
    if (Error e = eval::writePng(path, sheet); !e.ok()) state.SkipWithError(e.message.c_str());
    state.SetLabel(path);
  }
}

BENCHMARK(BM_ZhangPictures)->Iterations(1)->Unit(benchmark::kMillisecond);

// a torus with ripples, 2 nu nv triangles
Mesh bumpyTorus(int nu, int nv) {
  Mesh m;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const float u = 6.2831853f * i / nu, v = 6.2831853f * j / nv;
      const float r = 0.35f + 0.03f * std::sin(7 * u) * std::sin(5 * v);
      m.positions.push_back({(1.0f + r * std::cos(v)) * std::cos(u), (1.0f + r * std::cos(v)) * std::sin(u), r * std::sin(v)});
    }
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const uint32_t a = i * nv + j, b = ((i + 1) % nu) * nv + j, c = ((i + 1) % nu) * nv + (j + 1) % nv,
                     d = i * nv + (j + 1) % nv;
      m.triangles.insert(m.triangles.end(), {a, b, c, a, c, d});
    }
  return m;
}

// one CPU-time measurement per point (std::clock), so the plots show shape, not precision
void BM_ZhangPlots(benchmark::State& state) {
  const Mesh& in = bunny();
  if (in.triangles.empty()) {
    state.SkipWithError("bunny not found");
    return;
  }
  for (auto _ : state) {
    std::vector<eval::PlotSeries> by_rate(3);
    for (int m = 0; m < 3; ++m) {
      by_rate[m].name = kMethodNames[m == 2 ? 3 : m];
      by_rate[m].color = eval::seriesColor(m);
    }
    for (double rate : {10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 90.0, 95.0}) {
      for (int m = 0; m < 3; ++m) {
        Mesh out;
        const std::clock_t t0 = std::clock();
        simplifyWith(m == 2 ? 3 : m, in, targetForRate(in, rate), out);
        by_rate[m].x.push_back(rate);
        by_rate[m].y.push_back(cpuMs(t0));
      }
    }
    eval::PlotParams pp;
    pp.title = "bunny (69,666 triangles): CPU time against decimation rate";
    pp.x_label = "decimation rate (%)";
    pp.y_label = "CPU time (ms)";
    if (Error e = eval::writePlotPng(outDir() + "/zhang_time_vs_rate.png", by_rate, pp); !e.ok()) state.SkipWithError(e.message.c_str());

    std::vector<eval::PlotSeries> by_size(2);
    by_size[0].name = "zhang-interpolated";
    by_size[1].name = "meshopt";
    for (int m = 0; m < 2; ++m) by_size[m].color = eval::seriesColor(m == 0 ? 0 : 2);
    for (double tris : {10000.0, 100000.0, 300000.0, 1000000.0}) {
      const int nv = static_cast<int>(std::sqrt(tris / 4.0));
      const Mesh torus = bumpyTorus(static_cast<int>(tris / (2 * nv)), nv);
      for (int m = 0; m < 2; ++m) {
        Mesh out;
        const std::clock_t t0 = std::clock();
        simplifyWith(m == 0 ? 0 : 3, torus, targetForRate(torus, 90.0), out);
        by_size[m].x.push_back(static_cast<double>(torus.triangleCount()));
        by_size[m].y.push_back(cpuMs(t0));
      }
    }
    pp.title = "bumpy torus to 10 %: CPU time against mesh size";
    pp.x_label = "input triangles";
    pp.log_x = pp.log_y = true;
    if (Error e = eval::writePlotPng(outDir() + "/zhang_time_vs_size.png", by_size, pp); !e.ok()) state.SkipWithError(e.message.c_str());
    for (int m = 0; m < 3; ++m)
      for (size_t i = 0; i < by_rate[m].x.size(); ++i)
        state.counters[std::string(by_rate[m].name) + "@" + std::to_string(static_cast<int>(by_rate[m].x[i])) + "_ms"] =
            by_rate[m].y[i];
    for (int m = 0; m < 2; ++m)
      for (size_t i = 0; i < by_size[m].x.size(); ++i)
        state.counters[by_size[m].name + "@" + std::to_string(static_cast<long>(by_size[m].x[i])) + "tris_ms"] =
            by_size[m].y[i];
  }
}

BENCHMARK(BM_ZhangPlots)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace
