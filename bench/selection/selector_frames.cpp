// A fixed number of selection frames on the benchmark scene (selector_scene.h), for deterministic
// instruction and branch-misprediction counts under callgrind (scripts/selection-callgrind); the
// timing benchmarks are in selector_bench.cpp. It also prints a fingerprint (FNV-1a over every
// frame's levels and statistics, and with transitions their three outputs), so a change meant to
// keep the selector's output can be checked bit for bit: run it before and after and diff the lines.
// Usage: selector_frames OBJECTS FRAMES MODE, MODE one of
//   smooth   budget, Lagrangian, camera turning 1/600 of the orbit per frame, history kept
//   cold     budget, Lagrangian, camera jump and history reset every frame
//   greedy   budget, heap greedy, smooth camera
//   distance distance mode, smooth camera
// each optionally followed by +fade or +morph: the same frames with transitions (outputs written);
// SELECTION_MIN_DROP_PX=X in the environment sets SelectionParams::min_drop_px (default 4)
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <cstdint>
#include <string>

#include "selection/selector_scene.h"

using namespace selection_bench;

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: %s OBJECTS FRAMES smooth|cold|greedy|distance\n", argv[0]);
    return 2;
  }
  const size_t n = std::strtoul(argv[1], nullptr, 10);
  const int frames = std::atoi(argv[2]);
  std::string mode_arg = argv[3];
  Transitions transitions = Transitions::kNone;
  const size_t plus = mode_arg.find('+');
  if (plus != std::string::npos) {
    const std::string t = mode_arg.substr(plus + 1);
    if (t == "fade") transitions = Transitions::kFade;
    else if (t == "morph") transitions = Transitions::kMorph;
    else return std::fprintf(stderr, "bad transitions '%s'\n", t.c_str()), 2;
    mode_arg.resize(plus);
  }
  const char* mode = mode_arg.c_str();
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
  uint64_t hash = 1469598103934665603ull;
  auto mixBytes = [&hash](const void* p, size_t bytes) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (size_t i = 0; i < bytes; ++i) hash = (hash ^ b[i]) * 1099511628211ull;
  };
  for (int f = 0; f < frames; ++f) {
    t += cold ? 2.0 : 6.2831853 / 600.0;
    if (cold) resetSelectorHistory(s.ctx);
    Camera cam = cameraAt(n, t);
    SelectionJob j = job(s, &cam, &st);
    j.params.mode = distance ? SelectionMode::kDistance : SelectionMode::kBudget;
    j.params.algorithm = greedy ? BudgetAlgorithm::kGreedy : BudgetAlgorithm::kLagrangian;
    j.params.budget_ms = budget;
    j.params.calibrate = false;
    if (const char* e = std::getenv("SELECTION_MIN_DROP_PX")) j.params.min_drop_px = std::strtof(e, nullptr);
    if (transitions != Transitions::kNone) withTransitions(j, s, transitions);
    if (!j.run()) return 1;
    drawn += st.drawn_count;
    mixBytes(s.levels.data(), s.levels.size());
    const double sums[] = {st.predicted_ms, st.mandatory_ms, st.total_benefit, st.lambda};
    const uint32_t counts[] = {st.drawn_count, st.culled_count,  st.dropped_count,
                               st.switch_count, st.search_passes, st.flags};
    mixBytes(sums, sizeof sums);
    mixBytes(counts, sizeof counts);
    mixBytes(&st.features, sizeof st.features);
    if (transitions != Transitions::kNone) {
      mixBytes(s.morph.data(), s.morph.size() * sizeof(float));
      mixBytes(s.previous_levels.data(), s.previous_levels.size());
      mixBytes(s.fade.data(), s.fade.size() * sizeof(float));
      const double fades[] = {st.fade_cost_ms, static_cast<double>(st.fading_count)};
      mixBytes(fades, sizeof fades);
    }
  }
  std::printf("%d frames, %.1f drawn per frame, fingerprint %016llx\n", frames,
              static_cast<double>(drawn) / frames, static_cast<unsigned long long>(hash));
  return 0;
}
