// Selection per frame for 10k / 100k / 1M objects with 8 levels each: smooth camera (incremental:
// last frame's levels and price are the warm start) and cold (history reset and a camera jump every
// frame), budget mode with the Lagrangian search or the heap greedy, and distance mode.
#include <benchmark/benchmark.h>

#include "selection/selector_scene.h"

using namespace selection_bench;

namespace {

void run(benchmark::State& state, SelectionMode mode, BudgetAlgorithm alg, bool cold,
         Transitions transitions = Transitions::kNone, float min_drop_px = SelectionParams().min_drop_px) {
  const size_t n = static_cast<size_t>(state.range(0));
  BenchScene& s = scene(n);
  const float budget = budgetFor(s, n);
  resetSelectorHistory(s.ctx);
  SelectionStats st;
  double t = 0.0;
  size_t frames = 0, switches = 0, passes = 0, drawn = 0;
  for (auto _ : state) {
    // smooth: 1/600 of a turn per frame (a 10 s orbit at 60 Hz); cold: a jump and no history
    t += cold ? 2.0 : 6.2831853 / 600.0;
    if (cold) resetSelectorHistory(s.ctx);
    Camera cam = cameraAt(n, t);
    SelectionJob j = job(s, &cam, &st);
    j.params.mode = mode;
    j.params.algorithm = alg;
    j.params.budget_ms = budget;
    j.params.calibrate = false;
    j.params.min_drop_px = min_drop_px;
    if (transitions != Transitions::kNone) withTransitions(j, s, transitions);
    if (!j.run()) state.SkipWithError("run() refused the input");
    benchmark::DoNotOptimize(s.levels.data());
    benchmark::ClobberMemory();
    ++frames;
    switches += st.switch_count;
    passes += st.search_passes;
    drawn += st.drawn_count;
  }
  state.SetItemsProcessed(static_cast<int64_t>(frames * n));
  state.counters["bytes_per_object"] = selectorBytesPerObject(s.ctx);
  state.counters["search_passes"] = frames ? static_cast<double>(passes) / frames : 0.0;
  state.counters["drawn"] = frames ? static_cast<double>(drawn) / frames : 0.0;
  state.counters["switch_frac"] = frames ? static_cast<double>(switches) / frames / n : 0.0;
}

void BM_BudgetLagrangianSmooth(benchmark::State& s) { run(s, SelectionMode::kBudget, BudgetAlgorithm::kLagrangian, false); }
void BM_BudgetLagrangianCold(benchmark::State& s) { run(s, SelectionMode::kBudget, BudgetAlgorithm::kLagrangian, true); }
void BM_BudgetGreedySmooth(benchmark::State& s) { run(s, SelectionMode::kBudget, BudgetAlgorithm::kGreedy, false); }
void BM_BudgetGreedyCold(benchmark::State& s) { run(s, SelectionMode::kBudget, BudgetAlgorithm::kGreedy, true); }
void BM_DistanceSmooth(benchmark::State& s) { run(s, SelectionMode::kDistance, BudgetAlgorithm::kLagrangian, false); }
// without the drop policy (any object may be dropped): the same runs' reference
void BM_BudgetLagrangianSmoothDropAny(benchmark::State& s) {
  run(s, SelectionMode::kBudget, BudgetAlgorithm::kLagrangian, false, Transitions::kNone, 0.0f);
}
void BM_BudgetLagrangianColdDropAny(benchmark::State& s) {
  run(s, SelectionMode::kBudget, BudgetAlgorithm::kLagrangian, true, Transitions::kNone, 0.0f);
}
// with transitions (morph factors and fades, their outputs written): the same runs' extra cost
void BM_BudgetLagrangianSmoothMorph(benchmark::State& s) {
  run(s, SelectionMode::kBudget, BudgetAlgorithm::kLagrangian, false, Transitions::kMorph);
}
void BM_DistanceSmoothMorph(benchmark::State& s) {
  run(s, SelectionMode::kDistance, BudgetAlgorithm::kLagrangian, false, Transitions::kMorph);
}
void BM_DistanceSmoothFade(benchmark::State& s) {
  run(s, SelectionMode::kDistance, BudgetAlgorithm::kLagrangian, false, Transitions::kFade);
}
void BM_BudgetLagrangianSmoothFade(benchmark::State& s) {
  run(s, SelectionMode::kBudget, BudgetAlgorithm::kLagrangian, false, Transitions::kFade);
}

}  // namespace

BENCHMARK(BM_BudgetLagrangianSmooth)->Arg(10000)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BudgetLagrangianCold)->Arg(10000)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BudgetGreedySmooth)->Arg(10000)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BudgetGreedyCold)->Arg(10000)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DistanceSmooth)->Arg(10000)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BudgetLagrangianSmoothDropAny)->Arg(10000)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BudgetLagrangianColdDropAny)->Arg(10000)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BudgetLagrangianSmoothMorph)->Arg(10000)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DistanceSmoothMorph)->Arg(10000)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DistanceSmoothFade)->Arg(10000)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BudgetLagrangianSmoothFade)->Arg(10000)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);
