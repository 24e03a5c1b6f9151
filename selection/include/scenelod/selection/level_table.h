#pragma once
// Offline builder of the flat level table that selection reads (LevelTable in selector.h): one chain
// per unique mesh, one row per level. Plain vectors, filled once when a scene is loaded.
#include <cstdint>
#include <vector>

#include "scenelod/lodcore/lod_chain.h"
#include "scenelod/lodcore/span.h"
#include "scenelod/selection/selector.h"

namespace scenelod::selection {

struct LevelTableData {
  std::vector<uint32_t> chain_level_offset{0};
  std::vector<float> cell_width;
  std::vector<uint32_t> triangle_count;
  std::vector<uint32_t> vertex_count;
  std::vector<uint32_t> line_point_count;
  std::vector<uint8_t> has_morph;  // per row: the level has geomorph targets into the next level
                                   // (LodLevel::morph) and the next level draws triangles only, so
                                   // a transition between them may morph instead of fade (0 for
                                   // rows added from counts alone)

  // Appends a chain's levels (cell width, counts; edges + points as line_point_count) and returns its
  // chain id. Allocates.
  uint32_t addChain(const LodChain& chain);
  // Appends a chain from per-level arrays of equal length (level 0 first). Returns its chain id.
  uint32_t addChain(Span<const float> cell_widths, Span<const uint32_t> triangles, Span<const uint32_t> vertices,
                    Span<const uint32_t> line_points);

  size_t chainCount() const { return chain_level_offset.size() - 1; }
  size_t maxLevelsPerChain() const;
  // Views into this object's vectors; valid until it is modified or destroyed.
  LevelTable view() const;
};

}  // namespace scenelod::selection
