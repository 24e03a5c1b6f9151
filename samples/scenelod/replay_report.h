#pragma once
// The Markdown report of a replay run (summary, budget adherence, level histogram, switches), with
// PNG plots beside it.
#include <string>
#include <vector>

#include "scenelod/lodcore/status.h"
#include "scenelod/selection/replay.h"
#include "scenelod/selection/replay_runner.h"

namespace scenelod::tool {

struct ReplayReportInput {
  std::string replay_path;
  std::string scene_path;
  std::string command;  // the command line that produced the run
  const selection::Replay* replay = nullptr;
  // one or more runs of the same replay (e.g. distance mode and budget mode)
  std::vector<std::string> run_names;
  std::vector<const std::vector<selection::ReplayLogFrame>*> runs;
};

// Writes `md_path` and PNG plots named after it (<stem>_cost.png, <stem>_levels.png,
// <stem>_switches.png). Fills `summary_lines` with three lines that sum the report up.
Error writeReplayReport(const std::string& md_path, const ReplayReportInput& input, std::vector<std::string>& summary_lines);

}  // namespace scenelod::tool
