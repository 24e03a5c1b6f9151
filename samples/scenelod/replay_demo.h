#pragma once
// The selection part of the demo: record a fly-through over a scene, replay it in distance mode and
// under a budget, write the report with its plots.
#include <string>
#include <vector>

#include "scenelod/lodcore/status.h"
#include "scenelod/selection/replay_scene.h"

namespace scenelod::tool {

struct SelectionDemoResult {
  std::string report_path;
  std::vector<std::string> summary_lines;  // three lines that sum the report up
};

// Writes into `out_dir` (created if missing): the scene as a level scene (demo_scene.json), the
// recorded replay (demo_flythrough.jsonl, `frames` frames, 4 pixels per cell), the logs of a distance-mode run and of a
// budget run (budget halfway between the synthetic renderer's fixed per-frame cost and the
// distance run's mean measured cost), and demo_report.md with its
// plots. Errors name the file.
Error runSelectionDemo(const selection::ReplayScene& scene, const std::string& out_dir, size_t frames,
                       SelectionDemoResult& result);

}  // namespace scenelod::tool
