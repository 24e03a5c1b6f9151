// scenelod replay: runs a replay file through the selector and writes the per-frame log and a report.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "args.h"
#include "cluster_options.h"
#include "command.h"
#include "replay_popping.h"
#include "replay_report.h"
#include "scenelod/lodcore/atomic_file.h"
#include "scenelod/selection/replay_visibility.h"
#include "scenelod/selection/replay.h"
#include "scenelod/selection/replay_runner.h"
#include "scenelod/selection/replay_scene.h"

namespace scenelod::tool {
namespace {

using namespace scenelod::selection;

const char kUsage[] =
    "usage: scenelod replay REPLAY -o LOG.jsonl [--report REPORT.md] [options]\n"
    "\n"
    "Runs every frame of a replay (docs/REPLAY.md) through the selector and writes one JSON line per\n"
    "frame: {frame, time_s, budget_ms, predicted_ms, measured_ms, levels, switches, drawn, culled,\n"
    "dropped, flags, triangles}. Frames without measured_ms are measured by a synthetic renderer\n"
    "(known true costs, 5 % Gaussian noise, seeded).\n"
    "\n"
    "options:\n"
    "  -o, --out FILE       the log (JSON lines)\n"
    "  --report FILE.md     a Markdown report with tables and plots beside it\n"
    "  --budget MS          budget mode with this budget, whatever the replay says\n"
    "  --distance           distance mode, whatever the replay says\n"
    "  --algorithm NAME     lagrangian (default) or greedy\n"
    "  --hysteresis H       level-switch margin (default 0.1)\n"
    "  --skip               skip upgrades that do not fit instead of stopping at the first\n"
    "  --no-calibrate       keep the prior cost model\n"
    "  --seed N             seed of the synthetic renderer's noise (default 1)\n"
    "  --noise F            its relative standard deviation (default 0.05)\n"
    "  --visibility         Embree occlusion estimates and pick focus feed the selection (docs/VISIBILITY.md);\n"
    "                       the log adds visible, pick_object, hidden_count, hidden_cost_ms,\n"
    "                       hidden_cost_without_ms, occlusion_saved_ms\n"
    "  --ray-budget N       occlusion samples per frame with --visibility (default 20000)\n"
    "  --transitions MODE   none (default: hard switches), fade (cross-fades) or morph (geomorphs where\n"
    "                       levels have morph data, fades elsewhere); the log adds morph, fade,\n"
    "                       previous_levels and fading; time between frames from time_s\n"
    "  --fade-ms MS         duration of a cross-fade (default 250)\n"
    "  --morph-band F       share of a level's log pixel-size interval the morph takes, (0, 1] (default 0.3)\n"
    "  --fade-budget-share F  budget mode: share of the objects' budget fades may take, [0, 1] (default 0.1)\n"
    "  --min-drop-px PX     budget mode: objects in view with a projected radius of at least PX pixels\n"
    "                       (and not hidden) are never dropped, only coarsened (default 4; 0: any may be)\n"
    "  --popping            render every frame twice with the OpenGL adapter (last frame's levels, morphs\n"
    "                       and fades, then this frame's; same camera) and log \"popping\": the share of\n"
    "                       the covered pixels that differ by more than 16/255 in a channel; the summary\n"
    "                       gives its maximum and 99th percentile. Needs a glTF/GLB/OBJ scene; exit code\n"
    "                       77 where EGL or OpenGL 3.3 cannot start\n"
    "  --popping-supersample K  render --popping's pictures at K x K times the viewport and average each\n"
    "                       K x K block, as antialiasing would (1..4, default 1)\n"
    "  --popping-camera     on the frames --popping draws, also render this frame's levels under last\n"
    "                       frame's camera and log \"camera_popping\": what the camera's own motion changes\n"
    "  --nested, --independent  chains of a glTF/GLB/OBJ scene built here: each level clusters the one\n"
    "                       before (geomorphs end exactly on the next level) or the original (default)";

int run(const std::vector<std::string>& argv) {
  Args args(argv, {"--distance", "--skip", "--no-calibrate", "--visibility", "--popping", "--popping-camera", "--nested",
                   "--independent"},
            {"--out", "--report", "--budget", "--algorithm", "--hysteresis", "--seed", "--noise", "--ray-budget",
             "--transitions", "--fade-ms", "--morph-band", "--fade-budget-share", "--min-drop-px",
             "--popping-supersample"});
  if (!args.ok()) return usageError("replay", args.error());
  if (args.positional().size() != 1) return usageError("replay", "expected one replay file");
  if (!args.has("--out") && !args.has("--report")) return usageError("replay", "nothing to write: give -o LOG and/or --report FILE.md");
  ReplayRunOptions opt;
  double budget = 0.0, hysteresis = 0.1, noise = 0.05;
  long seed = 1, ray_budget = 20000;
  if (!args.getDouble("--budget", budget) || !args.getDouble("--hysteresis", hysteresis) || !args.getInt("--seed", seed) ||
      !args.getDouble("--noise", noise) || !args.getInt("--ray-budget", ray_budget))
    return usageError("replay", args.error());
  if (ray_budget < 0 || ray_budget > 100000000) return usageError("replay", "--ray-budget must be in [0, 1e8]");
  if (args.has("--budget")) {
    if (!(budget > 0.0)) return usageError("replay", "--budget must be > 0");
    opt.override_budget = true;
    opt.budget_ms = budget;
  }
  if (args.has("--distance") && args.has("--budget")) return usageError("replay", "--distance and --budget exclude each other");
  opt.force_distance = args.has("--distance");
  if (!(hysteresis >= 0.0)) return usageError("replay", "--hysteresis must be >= 0");
  if (!(noise >= 0.0 && noise < 1.0)) return usageError("replay", "--noise must be in [0, 1)");
  opt.params.hysteresis = static_cast<float>(hysteresis);
  opt.params.stop_at_first_non_fitting = !args.has("--skip");
  opt.params.calibrate = !args.has("--no-calibrate");
  const std::string alg = args.get("--algorithm", "lagrangian");
  if (alg == "greedy") opt.params.algorithm = BudgetAlgorithm::kGreedy;
  else if (alg != "lagrangian") return usageError("replay", "--algorithm must be lagrangian or greedy");
  double fade_ms = 250.0, morph_band = 0.3, fade_share = 0.1, min_drop_px = 4.0;
  if (!args.getDouble("--fade-ms", fade_ms) || !args.getDouble("--morph-band", morph_band) ||
      !args.getDouble("--fade-budget-share", fade_share) || !args.getDouble("--min-drop-px", min_drop_px))
    return usageError("replay", args.error());
  if (!(min_drop_px >= 0.0) || !std::isfinite(min_drop_px)) return usageError("replay", "--min-drop-px must be >= 0 and finite");
  opt.params.min_drop_px = static_cast<float>(min_drop_px);
  const std::string transitions = args.get("--transitions", "none");
  if (transitions == "fade") opt.params.transitions = Transitions::kFade;
  else if (transitions == "morph") opt.params.transitions = Transitions::kMorph;
  else if (transitions != "none") return usageError("replay", "--transitions must be none, fade or morph");
  if (!(fade_ms >= 0.0) || !std::isfinite(fade_ms)) return usageError("replay", "--fade-ms must be >= 0 and finite");
  if (!(morph_band > 0.0 && morph_band <= 1.0)) return usageError("replay", "--morph-band must be in (0, 1]");
  if (!(fade_share >= 0.0 && fade_share <= 1.0)) return usageError("replay", "--fade-budget-share must be in [0, 1]");
  opt.params.fade_ms = static_cast<float>(fade_ms);
  opt.params.morph_band = static_cast<float>(morph_band);
  opt.params.fade_budget_share = static_cast<float>(fade_share);
  opt.seed = static_cast<uint64_t>(seed);
  opt.noise = noise;

  const std::string path = args.positional()[0];
  // the replay is read, run and logged one frame at a time: memory does not grow with its length
  ReplayReader reader;
  if (Error e = reader.open(path); !e.ok()) return runError("replay", e.message);
  const ReplayHeader header = reader.header();
  const std::string scene_path = resolveReplayScene(path, header.scene);
  ReplayScene scene;
  ChainParams chain;
  std::string nesting_error;
  if (!parseNesting(args, chain, nesting_error)) return usageError("replay", nesting_error);
  const bool chain_options = args.has("--nested") || args.has("--independent");
  if (Error e = chain_options ? loadReplayScene(scene_path, scene, chain) : loadReplayScene(scene_path, scene); !e.ok())
    return runError("replay", e.message);
  ReplayPopping popping;
  long supersample = 1;
  if (!args.getInt("--popping-supersample", supersample)) return usageError("replay", args.error());
  if (supersample < 1 || supersample > 4) return usageError("replay", "--popping-supersample must be 1..4");
  if (args.has("--popping-supersample") && !args.has("--popping")) return usageError("replay", "--popping-supersample needs --popping");
  if (args.has("--popping-camera") && !args.has("--popping")) return usageError("replay", "--popping-camera needs --popping");
  if (args.has("--popping")) {
    bool unavailable = false;
    if (Error e = popping.init(scene, header, scene_path, static_cast<uint32_t>(supersample), &unavailable); !e.ok()) {
      if (!unavailable) return runError("replay", e.message);
      std::fprintf(stderr, "scenelod replay: %s\nscenelod replay: headless OpenGL cannot start on this machine (docs/GL.md); "
                           "exit code 77\n", e.message.c_str());
      return 77;
    }
  }
  ReplayVisibility visibility;
  if (args.has("--visibility")) {
    ReplayVisibilityParams vp;
    vp.occlusion.ray_budget = static_cast<uint32_t>(ray_budget);
    if (Error e = visibility.init(scene, vp); !e.ok()) return runError("replay", scene_path + ": visibility: " + e.message);
    opt.visibility = &visibility;
  }
  AtomicFile log;
  if (args.has("--out"))
    if (Error e = log.open(args.get("--out")); !e.ok()) return runError("replay", e.message);
  ReplayRunDigest digest;
  size_t frames = 0;
  auto next = [&](ReplayFrame& f, Error& e) {
    const bool more = reader.next(f, e);
    if (more && args.has("--popping")) popping.setFrame(f);
    return more;
  };
  auto sink = [&](const ReplayLogFrame& f) {
    double pop = 0.0, camera_pop = -1.0;
    if (args.has("--popping"))
      if (Error e = popping.measure(scene, f, pop, args.has("--popping-camera") ? &camera_pop : nullptr); !e.ok()) return e;
    if (log.stream())
      log.write((args.has("--popping") ? withPopping(replayLogLine(f), pop, camera_pop) : replayLogLine(f)) + "\n");
    digest.add(f);
    ++frames;
    return Error();
  };
  if (Error e = runReplayStream(header, next, scene, opt, sink); !e.ok()) return runError("replay", e.message);
  if (log.stream())
    if (Error e = log.commit(); !e.ok()) return runError("replay", e.message);
  const ReplaySummary s = digest.summary.summary();
  std::printf("%zu frames, %zu objects, mean predicted %.3f ms, mean measured %.3f ms, %.4f switches/object/s, "
              "mean benefit %.6g\n", s.frames, s.objects, s.mean_predicted_ms, s.mean_measured_ms,
              s.switches_per_object_per_second, s.mean_benefit);
  if (s.budget_frames)
    std::printf("budget frames after warm-up within +10 %%: %zu / %zu (%.1f %%)\n", s.within_10_percent, s.budget_frames,
                100.0 * s.within_10_percent / s.budget_frames);
  if (s.visibility_frames)
    std::printf("visibility: %.1f %% of objects hidden on average; occlusion saved %.3f ms of predicted cost per frame "
                "(%.3f ms went to hidden objects without it); %zu picks hit an object\n",
                100.0 * s.mean_hidden_share, s.mean_occlusion_saved_ms, s.mean_hidden_cost_without_ms, s.pick_frames);
  if (args.has("--popping")) {
    const PoppingSummary p = popping.summary();
    std::printf("popping: max %.4f (frame %llu), 99th percentile %.4f, mean %.5f; %zu of %zu frames changed pixels\n", p.max,
                static_cast<unsigned long long>(p.max_frame), p.p99, p.mean, p.popping_frames, p.frames);
  }
  if (args.has("--report")) {
    ReplayReportInput in;
    in.replay_path = path;
    in.scene_path = scene_path;
    std::string cmd = "scenelod replay";
    for (const auto& a : argv) cmd += " " + a;
    in.command = cmd;
    in.header = &header;
    in.frame_count = frames;
    in.run_names = {digest.has_budget ? "budget" : "distance"};
    in.runs = {&digest};
    if (args.has("--popping")) {
      const PoppingSummary p = popping.summary();
      char line[256];
      std::snprintf(line, sizeof(line), "| %zu | %zu | %.4f (frame %llu) | %.4f | %.5f |", p.frames, p.popping_frames, p.max,
                    static_cast<unsigned long long>(p.max_frame), p.p99, p.mean);
      in.extra_sections = "## Popping\n\nShare of the covered pixels that change by more than 16/255 in a channel "
                          "between last frame's and this frame's levels, same camera (first frame left out).\n\n"
                          "| frames | frames with popping | max | 99th percentile | mean |\n|---:|---:|---:|---:|---:|\n" +
                          std::string(line) + "\n";
    }
    std::vector<std::string> lines;
    if (Error e = writeReplayReport(args.get("--report"), in, lines); !e.ok()) return runError("replay", e.message);
    std::printf("report: %s\n", args.get("--report").c_str());
  }
  return 0;
}

const CommandRegistration kRegistration({"replay", "run a replay file through the selector; log and report", kUsage, run});

}  // namespace
}  // namespace scenelod::tool
