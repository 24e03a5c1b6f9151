// Pack::fromBytes on arbitrary bytes, as given and again with the CRC-32 at byte 24 recomputed (most
// mutations would otherwise stop at the checksum, never reaching the section and index checks: a
// hand-edited pack is re-checksummed just as easily). A pack it accepts is then used the way an
// engine would: every root, node, object, chain sphere, mesh name and level view (with its attribute
// arrays) read, every index followed, and the owned copies made (toSceneData, toChains, toScene).
#include <cstring>
#include <vector>

#include "fuzz_input.h"
#include "scenelod/scene/pack.h"
#include "scenelod/scene/scene.h"

namespace {

using scenelod::scene::Pack;

// sums what a view points at, so that every element is really read (ASan sees each access)
template <class T>
float touch(scenelod::Span<const T> span) {
  float sum = 0.0f;
  for (const T& v : span) sum += static_cast<float>(reinterpret_cast<const unsigned char*>(&v)[0]);
  return sum;
}

float walkLevels(const Pack& pack) {
  float sum = 0.0f;
  for (size_t c = 0; c < pack.chainCount(); ++c) {
    sum += pack.chainSphere(c).radius;
    for (const char* n = pack.meshName(c); n && *n; ++n) sum += static_cast<float>(*n);
    for (size_t l = 0; l < pack.levelCount(c); ++l) {
      scenelod::scene::PackLevelView v = pack.level(c, l);
      sum += v.cell_width + touch(v.positions) + touch(v.normals) + touch(v.colors) + touch(v.uvs);
      sum += touch(v.edge_thickness) + touch(v.extra_uvs) + touch(v.tangents) + touch(v.weights) + touch(v.triangle_groups);
      for (const glm::u16vec4& j : v.joints) sum += j.x < v.joint_parents.size() ? float(v.joint_parents[j.x]) : 1.0f;
      for (uint32_t s : v.source_vertex) sum += float(s % 3);
      size_t n = v.positions.size();
      for (uint32_t i : v.triangles) sum += i < n ? v.positions[i].x : 1.0f;
      for (uint32_t i : v.edges) sum += i < n ? v.positions[i].y : 1.0f;
      for (uint32_t i : v.points) sum += i < n ? v.positions[i].z : 1.0f;
    }
  }
  return sum;
}

float walkNodes(const Pack& pack) {
  float sum = 0.0f;
  for (size_t r = 0; r < pack.rootCount(); ++r) sum += static_cast<float>(pack.root(r) % 7);
  for (size_t i = 0; i < pack.nodeCount(); ++i) {
    scenelod::scene::PackNodeView n = pack.node(i);
    for (int k = 0; k < 16 && n.local; ++k) sum += n.local[k];
    sum += touch(n.children);
    for (const char* c = n.name; c && *c; ++c) sum += static_cast<float>(*c);
  }
  for (size_t i = 0; i < pack.objectCount(); ++i) {
    scenelod::scene::PackObjectView o = pack.object(i);
    sum += o.importance + static_cast<float>(o.node % 3 + o.chain % 5);
  }
  return sum;
}

void useBytes(const uint8_t* data, size_t size) {
  Pack pack;
  if (!Pack::fromBytes(data, size, pack, "fuzz input").ok()) return;
  volatile float sink = walkNodes(pack) + walkLevels(pack);
  (void)sink;
  scenelod::scene::SceneData scene;
  pack.toSceneData(scene);
  std::vector<scenelod::LodChain> chains;
  std::vector<scenelod::Sphere> spheres;
  pack.toChains(chains, spheres);
  scenelod::scene::Scene runtime;
  (void)pack.toScene(runtime);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  useBytes(data, size);
  constexpr size_t kChecksumOffset = 24;
  if (size < kChecksumOffset + 4) return 0;
  std::vector<uint8_t> fixed(data, data + size);
  std::memset(fixed.data() + kChecksumOffset, 0, 4);
  uint32_t crc = scenelod::scene::crc32(fixed.data(), fixed.size());
  std::memcpy(fixed.data() + kChecksumOffset, &crc, 4);
  useBytes(fixed.data(), fixed.size());
  return 0;
}
