#pragma once
// Running a replay through the selector: per frame apply moves, update world spheres, select, then
// take the frame's measured time from the file or from a synthetic renderer (known true cost
// coefficients with seeded Gaussian noise) and report it to the selector before the next frame, as
// an engine would. Produces the JSON-lines log of docs/REPLAY.md. Offline code: allocates.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "scenelod/lodcore/status.h"
#include "scenelod/selection/cost_model.h"
#include "scenelod/selection/replay.h"
#include "scenelod/selection/replay_scene.h"
#include "scenelod/selection/selector.h"

namespace scenelod::selection {

// The true costs of the synthetic renderer: deliberately not the selector's prior, so calibration
// has something to learn.
CostCoefficients syntheticTrueCost();

class ReplayVisibility;

struct ReplayRunOptions {
  SelectionParams params;              // mode, budget and pixels_per_cell are taken from the header;
                                       // dt_ms from the frames' time_s (0 for the first frame)
  bool force_distance = false;         // distance mode whatever the header says
  bool override_budget = false;        // budget mode with budget_ms below whatever the header says
  double budget_ms = 16.7;
  bool synthetic_renderer = true;      // measure frames without measured_ms synthetically
  CostCoefficients true_cost = syntheticTrueCost();
  double noise = 0.05;                 // relative standard deviation of the synthetic measurement
  uint64_t seed = 1;
  CostCoefficients initial_cost;       // the selector's prior
  CalibrationParams calibration;       // the selector's calibration (SelectorConfig::calibration)
  ReplayVisibility* visibility = nullptr;  // optional occlusion and pick focus (replay_visibility.h),
                                           // initialised on the same scene
};

struct ReplayLogFrame {
  uint64_t frame = 0;
  double time_s = 0.0;
  bool has_budget = false;
  double budget_ms = 0.0;
  double predicted_ms = 0.0;
  bool has_measured = false;
  double measured_ms = 0.0;
  bool measured_from_file = false;
  std::vector<int8_t> levels;       // with views: the primary group's (selector.h, SelectionJob::views)
  // with transitions (ReplayRunOptions::params.transitions != none; logged as "morph" and "fade"):
  // per object the morph factor, the level fading out and the new level's weight
  bool has_transitions = false;
  std::vector<float> morph, fade;
  std::vector<int8_t> previous_levels;
  uint32_t fading = 0;
  // frames without views: the largest projected radius (pixels) of an object in view left out to
  // fit the budget, 0 when none was (not logged; the summary's)
  double max_dropped_radius_px = 0.0;
  std::vector<std::vector<int8_t>> view_levels;  // frames with views: one per group, in order of
                                                 // first appearance (logged as "view_levels")
  uint32_t switches = 0;
  uint32_t drawn = 0;
  uint32_t culled = 0;
  uint32_t dropped = 0;
  uint32_t flags = 0;
  double benefit = 0.0;
  double triangles = 0.0;
  // with ReplayRunOptions::visibility only (logged as "visible", "pick_object", "hidden_count",
  // "hidden_cost_ms", "hidden_cost_without_ms", "occlusion_saved_ms")
  bool has_visibility = false;
  std::vector<float> visible;          // estimated visible fraction per object
  int32_t pick_object = -1;            // object under the frame's pick point, -1 for none or no pick
  uint32_t hidden_count = 0;           // objects read as hidden
  double hidden_cost_ms = 0.0;         // predicted cost of the chosen levels of hidden objects
  double hidden_cost_without_ms = 0.0; // the same for a selection without visibility
  double occlusion_saved_ms = 0.0;     // hidden_cost_without_ms - hidden_cost_ms
};

// Runs every frame of `replay` on `scene` (moves change the scene). Errors: an invalid scene, a move
// naming a missing object, a frame whose camera is degenerate (eye == target), views together with
// ReplayRunOptions::visibility (occlusion is estimated for one camera), each naming the frame.
// Version-2 replays get a context with room for 8 view groups (about 2 KB per object).
Error runReplay(const Replay& replay, ReplayScene& scene, const ReplayRunOptions& options,
                std::vector<ReplayLogFrame>& log);

// The same run in constant memory: frames come one at a time from `next_frame` (true while there is
// one; a false with its Error set ends the run with that error, e.g. ReplayReader::next), and each
// frame's log goes to `sink` as soon as it is selected (an Error from the sink ends the run).
using ReplayFrameSource = std::function<bool(ReplayFrame& frame, Error& error)>;
using ReplayLogSink = std::function<Error(const ReplayLogFrame& frame)>;
Error runReplayStream(const ReplayHeader& header, const ReplayFrameSource& next_frame, ReplayScene& scene,
                      const ReplayRunOptions& options, const ReplayLogSink& sink);

// One log line (no newline): {"frame", "time_s", "budget_ms", "predicted_ms", "measured_ms",
// "levels", ["view_levels",] ["morph", "fade", "previous_levels", "fading",] "switches", "drawn", "culled", "dropped", "flags", "triangles"}, numbers printed with
// fixed precision so logs compare exactly.
std::string replayLogLine(const ReplayLogFrame& frame);
Error writeReplayLog(const std::string& path, const std::vector<ReplayLogFrame>& log);

struct ReplaySummary {
  size_t frames = 0;
  size_t objects = 0;
  size_t warmup = 30;
  double duration_s = 0.0;
  size_t budget_frames = 0;            // frames after warm-up with a budget and a measurement
  size_t within_10_percent = 0;        // of those, measured <= 1.1 x budget
  size_t over_budget_flagged = 0;
  double mean_predicted_ms = 0.0, mean_measured_ms = 0.0;
  double mean_abs_prediction_error = 0.0;  // |predicted - measured| / measured, after warm-up
  double switches_per_object_per_second = 0.0;
  double mean_triangles = 0.0;
  double mean_benefit = 0.0;          // total benefit of the chosen levels, per frame
  std::vector<size_t> level_histogram; // index 0 = not drawn, k + 1 = level k; over all frames and objects
  size_t visibility_frames = 0;        // frames with visibility estimates
  double mean_hidden_share = 0.0;      // hidden objects / objects, over those frames
  double mean_occlusion_saved_ms = 0.0;
  double mean_hidden_cost_without_ms = 0.0;
  size_t pick_frames = 0;              // frames whose pick hit an object
  size_t drawn_object_frames = 0;      // sum over frames of the objects drawn
  size_t dropped_object_frames = 0;    // ... of the objects in view left out to fit the budget
  double max_dropped_radius_px = 0.0;  // the largest projected radius of a dropped object, any frame
};

ReplaySummary summarizeReplay(const std::vector<ReplayLogFrame>& log, size_t warmup = 30);

// summarizeReplay fed one log frame at a time, in constant memory (a streamed run's summary).
class ReplaySummaryBuilder {
 public:
  explicit ReplaySummaryBuilder(size_t warmup = 30);
  void add(const ReplayLogFrame& frame);
  ReplaySummary summary() const;

 private:
  ReplaySummary s_;
  double first_time_s_ = 0.0;
  double predicted_sum_ = 0.0, triangles_sum_ = 0.0, benefit_sum_ = 0.0;
  double measured_sum_ = 0.0, error_sum_ = 0.0;
  double hidden_share_sum_ = 0.0, saved_sum_ = 0.0, hidden_without_sum_ = 0.0;
  size_t measured_ = 0, switches_ = 0;
};

}  // namespace scenelod::selection
