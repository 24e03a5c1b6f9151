#pragma once
// Hand edits of LOD pack bytes for the pack tests (the header layout in docs/SCENE.md): re-signing
// edited bytes so that only the edit is wrong, and finding a section in the section table.
#include <cstdint>
#include <cstring>
#include <vector>

#include "scenelod/scene/pack.h"

namespace scenelod::test {

// the file size and checksum of hand-edited bytes made valid again
inline void resign(std::vector<uint8_t>& bytes) {
  const uint64_t size = bytes.size();
  std::memcpy(bytes.data() + 16, &size, 8);  // file_bytes
  std::memset(bytes.data() + 24, 0, 4);
  const uint32_t crc = scene::crc32(bytes.data(), bytes.size());
  std::memcpy(bytes.data() + 24, &crc, 4);
}

// the byte offset of section `kind`'s table entry (kind, element bytes, offset, count, reserved),
// 0 when the pack has no such section
inline size_t sectionEntry(const std::vector<uint8_t>& bytes, uint32_t kind) {
  uint32_t count;
  uint64_t table;
  std::memcpy(&count, bytes.data() + 28, 4);
  std::memcpy(&table, bytes.data() + 32, 8);
  for (uint32_t s = 0; s < count; ++s) {
    uint32_t k;
    std::memcpy(&k, bytes.data() + table + 32 * s, 4);
    if (k == kind) return static_cast<size_t>(table + 32 * s);
  }
  return 0;
}

// the byte offset of the first record of section `kind` (1 nodes, 5 chains), 0 when absent
inline size_t sectionOffset(const std::vector<uint8_t>& bytes, uint32_t kind) {
  const size_t entry = sectionEntry(bytes, kind);
  if (entry == 0) return 0;
  uint64_t offset;
  std::memcpy(&offset, bytes.data() + entry + 8, 8);
  return static_cast<size_t>(offset);
}

}  // namespace scenelod::test
