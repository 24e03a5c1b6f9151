#pragma once
// The demo report's textured part: every level of every mesh drawn with its material (Embree), the
// textured image error per level against level 0, and a picture of a few meshes' levels.
#include <string>
#include <vector>

#include "scenelod/lodcore/status.h"
#include "scenelod/scene/lod_build.h"
#include "scenelod/scene/scene_data.h"

namespace scenelod::tool {

struct TexturedLevelsResult {
  std::string markdown;        // the report section (tables and the picture link)
  std::string summary_line;    // one line for the console
};

// Measures the textured image error of every level of every chain against its level 0 (14 views,
// `resolution` pixels, framed like level 0) and writes `out_dir`/textured_levels.png: the levels of
// a few meshes side by side. Errors: unreadable materials, a failed render or write.
Error writeTexturedLevels(const scene::SceneData& data, const scene::SceneLods& lods, const std::string& out_dir,
                          int resolution, TexturedLevelsResult& out);

}  // namespace scenelod::tool
