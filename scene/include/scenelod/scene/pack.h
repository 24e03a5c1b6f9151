#pragma once
// LOD packs: a compact binary file holding a scene (nodes, objects, transforms, importance) and the
// LOD chain of every mesh, loaded with one read and no per-vertex parsing: every array is stored as
// the runtime uses it, 16-byte aligned, little-endian. The byte layout and the versioning policy are
// in docs/SCENE.md.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>
#include <glm/ext/vector_uint4_sized.hpp>

#include "scenelod/lodcore/lod_chain.h"
#include "scenelod/lodcore/span.h"
#include "scenelod/lodcore/status.h"
#include "scenelod/scene/scene_data.h"

namespace scenelod::scene {

class Scene;

constexpr char kPackMagic[8] = {'S', 'L', 'O', 'D', 'P', 'A', 'C', 'K'};
constexpr uint32_t kPackVersion = 1;

// CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320) of `size` bytes, continuing from `crc`
// (0 to start). Cost: O(size), slicing-by-8, no allocation.
uint32_t crc32(const void* data, size_t size, uint32_t crc = 0);

struct PackWriteOptions {
  size_t max_levels = 0;           // keep at most this many levels per chain (0 = all; level 0 always)
  bool optimize_order = true;      // reorder every level with optimizeMeshOrder (vertex cache + fetch)
  // per-object data in objectNodes() order; empty = importance 1, not must-draw, user data = node index
  std::vector<float> importance;
  std::vector<uint8_t> must_draw;
  std::vector<uint64_t> user_data;
  // the file the scene's materials come from (stored with each material; `scenelod pack` writes the
  // input's path relative to the pack's folder)
  std::string material_source;
};

struct PackWriteStats {
  size_t bytes = 0;
  double acmr_before = 0.0;  // triangle-weighted mean ACMR (FIFO 16) of all levels as given
  double acmr_after = 0.0;   // the same after reordering (equal to before when not optimising)
};

// Writes `scene` (nodes, roots, names; meshes are the chains' level 0) and `chains` (one per mesh,
// as buildLods makes them; LodLevel::bounds and `chain_spheres` as stored) to `path`.
// Errors: chain count or per-object arrays not matching, an invalid mesh, cannot write. Allocates.
Error writePack(const std::string& path, const SceneData& scene, const std::vector<LodChain>& chains,
                const std::vector<Sphere>& chain_spheres, const PackWriteOptions& options = {},
                PackWriteStats* stats = nullptr);
// The same into memory.
Error writePackBytes(std::vector<uint8_t>& out, const SceneData& scene, const std::vector<LodChain>& chains,
                     const std::vector<Sphere>& chain_spheres, const PackWriteOptions& options = {},
                     PackWriteStats* stats = nullptr, const std::string& what = "pack");

// Views of one level inside a loaded pack (valid while the Pack lives).
struct PackLevelView {
  float cell_width = 0.0f;
  float max_error = 0.0f;
  LodMethod method = LodMethod::kOriginal;
  Sphere bounds;
  Span<const glm::vec3> positions;
  Span<const glm::vec3> normals;  // empty when absent
  Span<const glm::vec3> colors;   // empty when absent
  Span<const glm::vec2> uvs;      // empty when absent
  Span<const uint32_t> triangles;
  Span<const uint32_t> edges;
  Span<const float> edge_thickness;  // empty when absent
  Span<const uint32_t> points;
  // the level attributes section (all empty when absent, as in packs written before it)
  size_t extra_uv_set_count = 0;
  Span<const glm::vec2> extra_uvs;  // texture coordinate sets 1, 2, ...: set s at [(s - 1) x V, s x V)
  Span<const glm::vec4> tangents;
  Span<const glm::u16vec4> joints;
  Span<const glm::vec4> weights;
  Span<const int32_t> joint_parents;     // the skeleton; every joint index is below its size
  Span<const uint32_t> triangle_groups;  // one per triangle; each group one contiguous run when ordered
  Span<const uint32_t> source_vertex;    // LodLevel::source_vertex: vertices of the chain's level 0
  // the level groups section (empty when absent): the material of each triangle group (an index
  // into Pack::material, -1 for none; groups past the end have none), each edge's and point's group
  Span<const int32_t> group_materials;
  Span<const uint32_t> edge_groups;   // empty = all in group 0
  Span<const uint32_t> point_groups;  // empty = all in group 0
};

// A material as the pack holds it: what scenelod reads of it, and where the full material is
// (material `source_index` of the glTF file `source`, whose textures the texture index refers to).
struct PackMaterialView {
  const char* name = "";
  const char* source = "";
  int32_t source_index = -1;
  glm::vec4 base_color{1.0f};
  bool textured = false;
  glm::vec3 average_texel_color{1.0f};
  int32_t base_color_texture = -1;  // in the source file
  uint32_t base_color_texcoord = 0;
  TextureTransform base_color_transform;
};

// One run of consecutive triangles of one group: triangles [first_triangle, first_triangle +
// triangle_count) of a level, drawn with `material` (an index into Pack::material, -1 for none).
struct PackMaterialRange {
  uint32_t first_triangle = 0;
  uint32_t triangle_count = 0;
  uint32_t group = 0;
  int32_t material = -1;
};

// The level's triangles as runs of one group, in triangle order: one run per group present when
// the pack was written with optimize_order (the default sorts triangles by group), possibly more
// otherwise. Allocates.
std::vector<PackMaterialRange> materialRanges(const PackLevelView& level);

// A level's geomorph targets (LodLevel::morph; section 11): all empty when the level has none (the
// last level of a chain, packs written without them).
struct PackLevelMorphView {
  Span<const glm::vec3> positions;
  Span<const glm::vec3> normals;
  Span<const glm::vec3> colors;
  Span<const glm::vec2> uvs;
  size_t extra_uv_set_count = 0;
  Span<const glm::vec2> extra_uvs;  // sets 1, 2, ...: set s at [(s - 1) x V, s x V)
  Span<const glm::vec4> tangents;
};

struct PackNodeView {
  int32_t parent = -1;
  int32_t mesh = -1;
  const float* local = nullptr;  // 16 floats, column-major
  Span<const uint32_t> children;
  const char* name = "";
};

struct PackObjectView {
  uint32_t node = 0;
  uint32_t chain = 0;
  float importance = 1.0f;
  bool must_draw = false;
  uint64_t user_data = 0;
};

// A loaded pack: one buffer holding the file, with views into it.
class Pack {
 public:
  // Reads `path` with one read into one buffer and checks magic, version, size, checksum and that
  // every section and array lies inside the file; with `check_indices` also that every index is in
  // range (one pass over the index arrays, skin joints and source vertices). Errors name the file: kIoError (missing, unreadable),
  // kCorrupt (truncated, bad checksum, bad offsets), kUnsupported (other version). Allocates once.
  static Error load(const std::string& path, Pack& out, bool check_indices = true);
  // The same from bytes already in memory (copied into the pack's buffer); `what` names the source.
  static Error fromBytes(const uint8_t* data, size_t size, Pack& out, const std::string& what, bool check_indices = true);

  size_t nodeCount() const;
  size_t rootCount() const;
  size_t objectCount() const;
  size_t chainCount() const;
  size_t levelCount(size_t chain) const;
  uint32_t root(size_t i) const;
  PackNodeView node(size_t i) const;
  PackObjectView object(size_t i) const;
  Sphere chainSphere(size_t chain) const;
  const char* meshName(size_t chain) const;
  PackLevelView level(size_t chain, size_t level) const;
  size_t materialCount() const;  // 0 for packs written without materials
  PackMaterialView material(size_t i) const;
  PackLevelMorphView levelMorph(size_t chain, size_t level) const;
  size_t byteSize() const { return bytes_.size(); }
  const uint8_t* bytes() const { return bytes_.data(); }  // the whole file

  // Copies out owned data: the scene (meshes = level 0 of each chain with their group materials;
  // materials as the pack holds them, without texture references: the textures stay in the
  // source file) and the chains. Allocates.
  void toSceneData(SceneData& out) const;
  void toChains(std::vector<LodChain>& chains, std::vector<Sphere>& chain_spheres) const;
  // Builds a runtime scene: nodes as in toSceneData, the pack's objects with their importance,
  // must-draw flags and user data, and the chains' spheres. Allocates.
  Error toScene(Scene& out) const;

 private:
  Error parse(const std::string& what, bool check_indices);
  std::vector<uint8_t> bytes_;
  // byte offsets of the sections, filled by parse()
  size_t nodes_ = 0, node_count_ = 0, children_ = 0, children_count_ = 0, roots_ = 0, root_count_ = 0;
  size_t objects_ = 0, object_count_ = 0, chains_ = 0, chain_count_ = 0, levels_ = 0, level_count_ = 0;
  size_t names_ = 0, names_size_ = 0;
  size_t attributes_ = 0;  // the level attributes section, 0 when absent
  size_t materials_ = 0, material_count_ = 0;  // the materials section, 0 when absent
  size_t groups_ = 0;                           // the level groups section, 0 when absent
  size_t morphs_ = 0;      // the level geomorph section, 0 when absent
};

}  // namespace scenelod::scene
