// The per-frame core alone (scenelod::selector): one chain of three levels, three objects at 5, 50 and
// 500 units in front of the camera, distance mode; prints the chosen levels.
#include <cstdint>
#include <cstdio>
#include <vector>

#include <scenelod/selection/level_table.h>
#include <scenelod/selection/selector.h>

namespace sel = scenelod::selection;

int main() {
  const std::vector<float> widths = {0.0f, 0.02f, 0.5f};
  const std::vector<uint32_t> triangles = {1000, 250, 12}, vertices = {520, 130, 8}, lines = {0, 0, 0};
  sel::LevelTableData table;
  const uint32_t chain = table.addChain(widths, triangles, vertices, lines);

  const std::vector<glm::vec3> centers = {{0, 0, -5}, {0, 0, -50}, {0, 0, -500}};
  const std::vector<float> radii(3, 1.0f), scales(3, 1.0f);
  const std::vector<uint32_t> chains(3, chain);
  std::vector<int8_t> levels(3, -1);

  sel::SelectorConfig config;
  config.max_object_count = centers.size();
  sel::SelectorContext* context = sel::createSelectorContext(config);
  sel::Camera camera;
  camera.eye = {0, 0, 0};
  camera.target = {0, 0, -1};
  sel::SelectionJob job;
  job.camera = &camera;
  job.params.mode = sel::SelectionMode::kDistance;
  job.levels = table.view();
  job.centers = centers;
  job.radii = radii;
  job.max_scales = scales;
  job.chains = chains;
  job.levels_out = levels;
  job.context = context;
  const bool ok = context && job.run();
  sel::destroySelectorContext(context);
  if (!ok) {
    std::fprintf(stderr, "selection failed\n");
    return 1;
  }
  std::printf("levels: %d %d %d\n", levels[0], levels[1], levels[2]);
  return 0;
}
