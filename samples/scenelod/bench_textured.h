#pragma once
// `scenelod bench --textured`: the textured image error of scenelod's levels against meshoptimizer's
// at matched triangle counts, each drawn with the model's materials (issue #37's target table).
#include <string>
#include <vector>

#include "scenelod/eval/metrics.h"
#include "scenelod/eval/render.h"
#include "scenelod/lodcore/status.h"

namespace scenelod::tool {

struct TexturedSettings {
  std::vector<double> targets_pct{20, 10};
  size_t samples = 100000;  // area samples per surface for the Hausdorff distance
  int resolution = 256;     // pixels across each of the 14 views
};

struct TexturedRun {
  std::string method;       // scenelod, scenelod-nouv, sloppy, meshopt
  double target_pct = 0.0;
  size_t target = 0;        // triangles asked for
  size_t triangles = 0, edges = 0, points = 0;
  eval::DistanceResult dist;
  eval::ImageErrorResult image;
  std::string note;         // set when there is nothing to measure (empty result)
};

struct TexturedModel {
  std::string name, path;
  size_t triangles = 0, vertices = 0;  // after welding equal vertices
  size_t materials = 0, textured_materials = 0;
  bool has_uvs = false;
  std::vector<TexturedRun> runs;
};

// Loads `path` (flattened to world space, vertices with equal position and attributes welded) and,
// for every target, measures against it:
//   scenelod       floating-cell clustering at the cell width findCellWidthForTarget finds
//   scenelod-nouv  the same level with its texture coordinates dropped (drawn with each texture's mean)
//   sloppy         meshopt_simplifySloppy, target_error 1
//   meshopt        meshopt_simplify, target_error 1, no options
// meshoptimizer runs per triangle group (material), each group asked for its share of the target,
// and every output vertex keeps its own attributes (uvs, normals, colours). Errors: unreadable
// model, failed simplification or measurement, naming the model and method.
Error benchTexturedModel(const std::string& path, const TexturedSettings& s, TexturedModel& out);

// The report: one table per model plus a summary of the targets' ratios (Markdown), and the same
// numbers as JSON.
std::string texturedMarkdown(const std::vector<TexturedModel>& models, const TexturedSettings& s,
                             const std::string& command, const std::string& date);
std::string texturedJson(const std::vector<TexturedModel>& models, const TexturedSettings& s,
                         const std::string& command, const std::string& date);

}  // namespace scenelod::tool
