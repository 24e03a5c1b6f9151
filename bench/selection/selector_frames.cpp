// A fixed number of selection frames on the benchmark scene (selector_scene.h), for deterministic
// instruction and branch-misprediction counts under callgrind (scripts/selection-callgrind); the
// timing benchmarks are in selector_bench.cpp.
// Usage: selector_frames OBJECTS FRAMES MODE, MODE one of
//   smooth   budget, Lagrangian, camera turning 1/600 of the orbit per frame, history kept
//   cold     budget, Lagrangian, camera jump and history reset every frame
//   greedy   budget, heap greedy, smooth camera
//   distance distance mode, smooth camera
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "selection/selector_scene.h"

using namespace selection_bench;

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: %s OBJECTS FRAMES smooth|cold|greedy|distance\n", argv[0]);
    return 2;
  }
  const size_t n = std::strtoul(argv[1], nullptr, 10);
  const int frames = std::atoi(argv[2]);
  const char* mode = argv[3];
  const bool cold = std::strcmp(mode, "cold") == 0, greedy = std::strcmp(mode, "greedy") == 0,
             distance = std::strcmp(mode, "distance") == 0;
  if (n == 0 || frames <= 0 || !(cold || greedy || distance || std::strcmp(mode, "smooth") == 0)) {
    std::fprintf(stderr, "bad arguments\n");
    return 2;
  }
  BenchScene& s = scene(n);
  const float budget = budgetFor(s, n);  // one distance-mode run()
  resetSelectorHistory(s.ctx);
  SelectionStats st;
  double t = 0.0;
  size_t drawn = 0;
  for (int f = 0; f < frames; ++f) {
    t += cold ? 2.0 : 6.2831853 / 600.0;
    if (cold) resetSelectorHistory(s.ctx);
    Camera cam = cameraAt(n, t);
    SelectionJob j = job(s, &cam, &st);
    j.params.mode = distance ? SelectionMode::kDistance : SelectionMode::kBudget;
    j.params.algorithm = greedy ? BudgetAlgorithm::kGreedy : BudgetAlgorithm::kLagrangian;
    j.params.budget_ms = budget;
    j.params.calibrate = false;
    if (!j.run()) return 1;
    drawn += st.drawn_count;
  }
  std::printf("%d frames, %.1f drawn per frame\n", frames, static_cast<double>(drawn) / frames);
  return 0;
}
