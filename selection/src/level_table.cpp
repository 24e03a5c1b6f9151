// Flattening LOD chains into the level table read by selection.
#include "scenelod/selection/level_table.h"

#include <algorithm>

namespace scenelod::selection {

// A level morphs into the next only when the next draws triangles alone: a morph moves the level's
// vertices onto the next level's, but cannot grow the thick edges or points the next level draws
// where this one had triangles, so such a switch would still pop; it fades instead.
uint32_t LevelTableData::addChain(const LodChain& chain) {
  for (size_t k = 0; k < chain.levels.size(); ++k) {
    const LodLevel& l = chain.levels[k];
    const bool next_has_lines = k + 1 < chain.levels.size() &&
                                chain.levels[k + 1].mesh.edgeCount() + chain.levels[k + 1].mesh.pointCount() != 0;
    cell_width.push_back(l.cell_width);
    triangle_count.push_back(static_cast<uint32_t>(l.mesh.triangleCount()));
    vertex_count.push_back(static_cast<uint32_t>(l.mesh.vertexCount()));
    line_point_count.push_back(static_cast<uint32_t>(l.mesh.edgeCount() + l.mesh.pointCount()));
    has_morph.push_back(l.morph.empty() || next_has_lines ? 0 : 1);
  }
  chain_level_offset.push_back(static_cast<uint32_t>(cell_width.size()));
  return static_cast<uint32_t>(chain_level_offset.size() - 2);
}

uint32_t LevelTableData::addChain(Span<const float> w, Span<const uint32_t> t, Span<const uint32_t> v,
                                  Span<const uint32_t> lp) {
  for (size_t i = 0; i < w.size(); ++i) {
    cell_width.push_back(w[i]);
    triangle_count.push_back(i < t.size() ? t[i] : 0);
    vertex_count.push_back(i < v.size() ? v[i] : 0);
    line_point_count.push_back(i < lp.size() ? lp[i] : 0);
    has_morph.push_back(0);
  }
  chain_level_offset.push_back(static_cast<uint32_t>(cell_width.size()));
  return static_cast<uint32_t>(chain_level_offset.size() - 2);
}

size_t LevelTableData::maxLevelsPerChain() const {
  size_t m = 0;
  for (size_t c = 0; c + 1 < chain_level_offset.size(); ++c)
    m = std::max<size_t>(m, chain_level_offset[c + 1] - chain_level_offset[c]);
  return m;
}

LevelTable LevelTableData::view() const {
  LevelTable t;
  t.chain_level_offset = Span<const uint32_t>(chain_level_offset.data(), chain_level_offset.size());
  t.cell_width = Span<const float>(cell_width.data(), cell_width.size());
  t.triangle_count = Span<const uint32_t>(triangle_count.data(), triangle_count.size());
  t.vertex_count = Span<const uint32_t>(vertex_count.data(), vertex_count.size());
  t.line_point_count = Span<const uint32_t>(line_point_count.data(), line_point_count.size());
  t.has_morph = Span<const uint8_t>(has_morph.data(), has_morph.size());
  return t;
}

}  // namespace scenelod::selection
