#pragma once
// The Markdown report of a replay run (summary, budget adherence, level histogram, switches), with
// PNG plots beside it.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "scenelod/lodcore/status.h"
#include "scenelod/selection/replay.h"
#include "scenelod/selection/replay_runner.h"

namespace scenelod::tool {

// What a report needs of one run, gathered frame by frame in bounded memory, so that a run of a
// million frames is reported without keeping its log: the running summary, the frame series (every
// frame up to kMaxPoints, then every 2nd, 4th, ... frame) and the switches per whole second.
class ReplayRunDigest {
 public:
  static constexpr size_t kMaxPoints = 4096;
  struct Point {
    uint64_t frame = 0;
    double time_s = 0.0, predicted_ms = 0.0, measured_ms = 0.0, budget_ms = 0.0;
    bool has_measured = false, has_budget = false;
    uint32_t switches = 0;
  };

  void add(const selection::ReplayLogFrame& frame);

  selection::ReplaySummaryBuilder summary;
  std::vector<Point> points;  // every `stride`-th frame
  size_t stride = 1;
  std::map<long, double> switches_per_second;  // whole-second bins, the first frame left out
  bool has_budget = false;
  double budget_ms = 0.0;

 private:
  size_t seen_ = 0;
};

// The digest of a whole log.
ReplayRunDigest digestOf(const std::vector<selection::ReplayLogFrame>& log);

struct ReplayReportInput {
  std::string replay_path;
  std::string scene_path;
  std::string command;  // the command line that produced the run
  const selection::ReplayHeader* header = nullptr;
  size_t frame_count = 0;
  // one or more runs of the same replay (e.g. distance mode and budget mode)
  std::vector<std::string> run_names;
  std::vector<const ReplayRunDigest*> runs;
  std::string extra_sections;  // Markdown appended at the end (e.g. replay --popping's "## Popping")
};

// Writes `md_path` and PNG plots named after it (<stem>_cost.png, <stem>_levels.png,
// <stem>_switches.png). Fills `summary_lines` with three lines that sum the report up.
Error writeReplayReport(const std::string& md_path, const ReplayReportInput& input, std::vector<std::string>& summary_lines);

}  // namespace scenelod::tool
