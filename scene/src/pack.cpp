// LOD pack writer and loader. The checksum is CRC-32 (IEEE), computed with the slicing-by-8 table
// method (Kounavis & Berry 2005, "A systematic approach to building high performance software-based
// CRC generators").
#include "scenelod/scene/pack.h"

#include <cstdio>
#include <cstring>
#include <type_traits>
#include <vector>

#include "scenelod/lodcore/atomic_file.h"
#include "scenelod/scene/mesh_order.h"
#include "scenelod/scene/scene.h"

namespace scenelod::scene {

namespace {

struct Crc32Tables {
  uint32_t t[8][256];
  Crc32Tables() {
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? (c >> 1) ^ 0xEDB88320u : c >> 1;
      t[0][i] = c;
    }
    for (uint32_t i = 0; i < 256; ++i)
      for (int s = 1; s < 8; ++s) t[s][i] = (t[s - 1][i] >> 8) ^ t[0][t[s - 1][i] & 0xff];
  }
};

const Crc32Tables& crcTables() {
  static const Crc32Tables tables;
  return tables;
}

// ---- on-disk records (little-endian, fixed sizes checked below) ----
struct FileHeader {
  char magic[8];
  uint32_t version;
  uint32_t header_bytes;
  uint64_t file_bytes;
  uint32_t checksum;  // crc32 of the whole file with this field set to 0
  uint32_t section_count;
  uint64_t section_table_offset;
  uint32_t flags;
  uint32_t reserved[5];
};
static_assert(sizeof(FileHeader) == 64, "pack header is 64 bytes");
constexpr size_t kChecksumOffset = 24;

enum SectionKind : uint32_t {
  kNodes = 1, kChildren = 2, kRoots = 3, kObjects = 4, kChains = 5, kLevels = 6, kNames = 7, kData = 8,
  kLevelAttributes = 9, kMaterials = 10, kLevelMorphs = 11, kLevelGroups = 12,
};
constexpr uint32_t kSectionKindCount = 12;
// sections every pack has; later kinds are optional (a pack written before them has none)
constexpr uint32_t kRequiredSectionKinds = 8;

struct SectionEntry {
  uint32_t kind;
  uint32_t element_bytes;
  uint64_t offset;
  uint64_t count;
  uint64_t reserved;
};
static_assert(sizeof(SectionEntry) == 32, "section entry is 32 bytes");

struct NodeRecord {
  int32_t parent;
  int32_t mesh;
  uint32_t first_child;
  uint32_t child_count;
  uint32_t name;  // offset in the names section
  uint32_t reserved[3];
  float local[16];
};
static_assert(sizeof(NodeRecord) == 96, "node record is 96 bytes");

struct ObjectRecord {
  uint32_t node;
  uint32_t chain;
  float importance;
  uint32_t flags;  // bit 0: must draw
  uint64_t user_data;
};
static_assert(sizeof(ObjectRecord) == 24, "object record is 24 bytes");

struct ChainRecord {
  uint32_t first_level;
  uint32_t level_count;
  uint32_t name;
  uint32_t reserved;
  float sphere[4];
};
static_assert(sizeof(ChainRecord) == 32, "chain record is 32 bytes");

struct LevelRecord {
  float cell_width;
  float max_error;
  uint32_t method;
  uint32_t reserved;
  float bounds[4];
  uint32_t vertex_count, triangle_count, edge_count, point_count;
  // absolute byte offsets of the arrays; 0 = absent
  uint64_t positions, normals, colors, uvs, triangles, edges, thickness, points;
};
static_assert(sizeof(LevelRecord) == 112, "level record is 112 bytes");

// the attributes beyond LevelRecord's, one record per level record (same order); written only when
// some level has one, so packs of meshes without them are the bytes they were before this section
struct LevelAttributesRecord {
  uint32_t extra_uv_set_count;  // texture coordinate sets after set 0
  uint32_t joint_count;         // entries of joint_parents
  uint32_t reserved[2];
  // absolute byte offsets into the data section; 0 = absent
  uint64_t extra_uvs;        // extra_uv_set_count x vertex_count x 2 f32, set after set
  uint64_t tangents;         // vertex_count x 4 f32
  uint64_t joints;           // vertex_count x 4 u16
  uint64_t weights;          // vertex_count x 4 f32
  uint64_t joint_parents;    // joint_count x i32
  uint64_t triangle_groups;  // triangle_count x u32
  uint64_t source_vertex;    // vertex_count x u32, vertices of the chain's level 0
  uint64_t reserved_offset;
};
static_assert(sizeof(LevelAttributesRecord) == 80, "level attributes record is 80 bytes");

// What scenelod reads of a material (MaterialData), and where the full material is: material
// `index` of the glTF file `source`. One record per material, in the scene's order; written only
// when the scene has materials.
struct MaterialRecord {
  uint32_t name;    // offset in the names section
  uint32_t source;  // offset in the names section: the file the material comes from ("" = unknown)
  int32_t index;    // its index in that file's materials
  uint32_t flags;   // bit 0: has a base colour texture
  float base_color[4];
  float average_texel_color[3];
  int32_t base_color_texture;  // texture index in the source file, -1 for none
  uint32_t base_color_texcoord;
  float transform[5];  // KHR_texture_transform: offset x, y, rotation, scale x, y
  int32_t transform_texcoord;
  uint32_t reserved;
};
static_assert(sizeof(MaterialRecord) == 80, "material record is 80 bytes");

// The material of every group of a level, and the groups of its edges and points; one record per
// level record (same order), written when a mesh has materials or groups.
struct LevelGroupsRecord {
  uint32_t group_count;     // entries of group_materials
  uint32_t reserved;
  uint64_t group_materials;  // group_count x i32: material record index, -1 for none
  uint64_t edge_groups;      // edge_count x u32; 0 = every edge in group 0
  uint64_t point_groups;     // point_count x u32; 0 = every point in group 0
};
static_assert(sizeof(LevelGroupsRecord) == 32, "level groups record is 32 bytes");

// the geomorph targets of a level's vertices (LodLevel::morph), one record per level record (same
// order); written only when some level has them, so packs of chains without them are unchanged
struct LevelMorphRecord {
  uint32_t vertex_count;        // the level's vertex count, or 0: no targets
  uint32_t extra_uv_set_count;  // texture coordinate sets after set 0
  uint32_t reserved[2];
  // absolute byte offsets into the data section; 0 = absent (positions present when vertex_count > 0)
  uint64_t positions;  // vertex_count x 3 f32
  uint64_t normals;    // vertex_count x 3 f32
  uint64_t colors;     // vertex_count x 3 f32
  uint64_t uvs;        // vertex_count x 2 f32
  uint64_t extra_uvs;  // extra_uv_set_count x vertex_count x 2 f32, set after set
  uint64_t tangents;   // vertex_count x 4 f32
  uint64_t reserved_offset[2];
};
static_assert(sizeof(LevelMorphRecord) == 80, "level morph record is 80 bytes");

// element sizes by kind; 0 = a kind this build does not read (skipped like unknown kinds)
constexpr uint32_t kElementBytes[kSectionKindCount + 1] = {0, sizeof(NodeRecord), 4, 4, sizeof(ObjectRecord),
                                                           sizeof(ChainRecord), sizeof(LevelRecord), 1, 1,
                                                           sizeof(LevelAttributesRecord), sizeof(MaterialRecord),
                                                           sizeof(LevelMorphRecord), sizeof(LevelGroupsRecord)};

size_t align16(size_t x) { return (x + 15) & ~size_t(15); }

bool littleEndianHost() {
  const uint32_t one = 1;
  uint8_t b;
  std::memcpy(&b, &one, 1);
  return b == 1;
}

class Writer {
 public:
  std::vector<uint8_t> data;  // the data section's contents

  template <class T>
  uint64_t array(const std::vector<T>& v, uint64_t data_base) {
    if (v.empty()) return 0;
    const size_t at = align16(data.size());
    data.resize(at + v.size() * sizeof(T), 0);
    std::memcpy(data.data() + at, v.data(), v.size() * sizeof(T));
    return data_base + at;
  }
};

bool hasExtraAttributes(const LodLevel& l) {
  const Mesh& m = l.mesh;
  return !m.extra_uvs.empty() || !m.tangents.empty() || !m.joints.empty() || !m.joint_parents.empty() ||
         !m.triangle_groups.empty() || !l.source_vertex.empty();
}

// what the pack needs beyond validateMesh: every extra texture set one value per vertex (a set is
// stored by position), source_vertex empty or one vertex of level 0 (`original_vertices` of them)
// per vertex
Error checkLevelExtras(const LodLevel& l, size_t original_vertices, const std::string& what) {
  for (size_t s = 0; s < l.mesh.extra_uvs.size(); ++s)
    if (l.mesh.extra_uvs[s].size() != l.mesh.vertexCount())
      return {Status::kInvalidMesh, what + ": texture coordinate set " + std::to_string(s + 1) + " has " +
                                        std::to_string(l.mesh.extra_uvs[s].size()) + " values for " +
                                        std::to_string(l.mesh.vertexCount()) + " vertices"};
  const std::vector<uint32_t>& sv = l.source_vertex;
  if (sv.empty()) return {};
  if (sv.size() != l.mesh.vertexCount())
    return {Status::kInvalidMesh, what + ": " + std::to_string(sv.size()) + " source vertices for " +
                                      std::to_string(l.mesh.vertexCount()) + " vertices"};
  for (size_t v = 0; v < sv.size(); ++v)
    if (sv[v] >= original_vertices)
      return {Status::kInvalidMesh, what + ": vertex " + std::to_string(v) + " has source vertex " + std::to_string(sv[v]) +
                                        " but level 0 has " + std::to_string(original_vertices) + " vertices"};
  return {};
}

// the attribute record of a level (its arrays written to `w`), its source vertices renumbered by
// level 0's reordering `original_remap` (empty: not reordered) and its own `remap`
LevelAttributesRecord writeAttributes(Writer& w, uint64_t data_base, const Mesh& m, const std::vector<uint32_t>& source,
                                      const std::vector<uint32_t>& remap, const std::vector<uint32_t>& original_remap) {
  LevelAttributesRecord r;
  std::memset(&r, 0, sizeof r);
  r.extra_uv_set_count = static_cast<uint32_t>(m.extra_uvs.size());
  r.joint_count = static_cast<uint32_t>(m.joint_parents.size());
  std::vector<glm::vec2> sets;
  for (const std::vector<glm::vec2>& set : m.extra_uvs) sets.insert(sets.end(), set.begin(), set.end());
  r.extra_uvs = w.array(sets, data_base);
  r.tangents = w.array(m.tangents, data_base);
  r.joints = w.array(m.joints, data_base);
  r.weights = w.array(m.weights, data_base);
  r.joint_parents = w.array(m.joint_parents, data_base);
  r.triangle_groups = w.array(m.triangle_groups, data_base);
  std::vector<uint32_t> sv(source.size());
  for (size_t v = 0; v < source.size(); ++v)
    sv[remap.empty() ? v : remap[v]] = original_remap.empty() ? source[v] : original_remap[source[v]];
  r.source_vertex = w.array(sv, data_base);
  return r;
}

// the morph record of a level (its arrays written to `w`), reordered by the level's `remap` (empty:
// not reordered); a level without targets, or whose targets lie in a level not written, gets none
LevelMorphRecord writeMorph(Writer& w, uint64_t data_base, const LevelMorph& morph, const std::vector<uint32_t>& remap) {
  LevelMorphRecord r;
  std::memset(&r, 0, sizeof r);
  if (morph.empty()) return r;
  auto reordered = [&](const auto& v) {
    std::remove_const_t<std::remove_reference_t<decltype(v)>> out(v.size());
    for (size_t i = 0; i < v.size(); ++i) out[remap.empty() ? i : remap[i]] = v[i];
    return out;
  };
  r.vertex_count = static_cast<uint32_t>(morph.positions.size());
  r.positions = w.array(reordered(morph.positions), data_base);
  r.normals = w.array(reordered(morph.normals), data_base);
  r.colors = w.array(reordered(morph.colors), data_base);
  r.uvs = w.array(reordered(morph.uvs), data_base);
  std::vector<glm::vec2> sets;
  for (const std::vector<glm::vec2>& set : morph.extra_uvs) {
    const std::vector<glm::vec2> one = set.empty() ? std::vector<glm::vec2>(morph.positions.size()) : reordered(set);
    sets.insert(sets.end(), one.begin(), one.end());
  }
  r.extra_uv_set_count = static_cast<uint32_t>(morph.extra_uvs.size());
  r.extra_uvs = w.array(sets, data_base);
  r.tangents = w.array(reordered(morph.tangents), data_base);
  return r;
}

// what the pack needs of a level's targets: every array empty or one per vertex
Error checkLevelMorph(const LodLevel& l, const std::string& what) {
  const LevelMorph& m = l.morph;
  if (m.empty()) return {};
  const size_t n = l.mesh.vertexCount();
  bool ok = m.positions.size() == n;
  for (size_t size : {m.normals.size(), m.colors.size(), m.uvs.size(), m.tangents.size()}) ok = ok && (size == 0 || size == n);
  for (const std::vector<glm::vec2>& set : m.extra_uvs) ok = ok && (set.empty() || set.size() == n);
  if (!ok) return {Status::kInvalidMesh, what + ": its geomorph targets are not one per vertex (" + std::to_string(n) + ")"};
  return {};
}

uint32_t addName(std::vector<char>& names, const std::string& s) {
  const uint32_t at = static_cast<uint32_t>(names.size());
  names.insert(names.end(), s.begin(), s.end());
  names.push_back('\0');
  return at;
}

}  // namespace

uint32_t crc32(const void* data, size_t size, uint32_t crc) {
  const Crc32Tables& t = crcTables();
  const uint8_t* p = static_cast<const uint8_t*>(data);
  crc = ~crc;
  while (size >= 8) {
    uint32_t a, b;
    std::memcpy(&a, p, 4);
    std::memcpy(&b, p + 4, 4);
    a ^= crc;
    crc = t.t[7][a & 0xff] ^ t.t[6][(a >> 8) & 0xff] ^ t.t[5][(a >> 16) & 0xff] ^ t.t[4][a >> 24] ^
          t.t[3][b & 0xff] ^ t.t[2][(b >> 8) & 0xff] ^ t.t[1][(b >> 16) & 0xff] ^ t.t[0][b >> 24];
    p += 8;
    size -= 8;
  }
  while (size--) crc = (crc >> 8) ^ t.t[0][(crc ^ *p++) & 0xff];
  return ~crc;
}

Error writePackBytes(std::vector<uint8_t>& out, const SceneData& scene, const std::vector<LodChain>& chains,
                     const std::vector<Sphere>& chain_spheres, const PackWriteOptions& opt, PackWriteStats* stats,
                     const std::string& what) {
  if (!littleEndianHost()) return {Status::kUnsupported, what + ": packs are little-endian; this host is not"};
  if (chains.size() != scene.meshes.size() || chain_spheres.size() != chains.size())
    return {Status::kInvalidArgument, what + ": " + std::to_string(chains.size()) + " chains and " +
                                          std::to_string(chain_spheres.size()) + " chain spheres for " +
                                          std::to_string(scene.meshes.size()) + " meshes"};
  if (Error e = validateSceneData(scene, what); !e.ok()) return e;
  const std::vector<int32_t> object_nodes = objectNodes(scene);
  const size_t object_count = object_nodes.size();
  if ((!opt.importance.empty() && opt.importance.size() != object_count) ||
      (!opt.must_draw.empty() && opt.must_draw.size() != object_count) ||
      (!opt.user_data.empty() && opt.user_data.size() != object_count))
    return {Status::kInvalidArgument, what + ": per-object arrays must have " + std::to_string(object_count) + " entries"};

  std::vector<NodeRecord> nodes(scene.nodes.size());
  std::vector<uint32_t> children, roots(scene.roots.begin(), scene.roots.end());
  std::vector<char> names;
  for (size_t i = 0; i < scene.nodes.size(); ++i) {
    const NodeData& n = scene.nodes[i];
    NodeRecord& r = nodes[i];
    std::memset(&r, 0, sizeof r);
    r.parent = n.parent;
    r.mesh = n.mesh;
    r.first_child = static_cast<uint32_t>(children.size());
    r.child_count = static_cast<uint32_t>(n.children.size());
    for (int32_t c : n.children) children.push_back(static_cast<uint32_t>(c));
    r.name = addName(names, n.name);
    std::memcpy(r.local, &n.local[0][0], sizeof r.local);
  }
  std::vector<ObjectRecord> objects(object_count);
  for (size_t k = 0; k < object_count; ++k) {
    ObjectRecord& o = objects[k];
    std::memset(&o, 0, sizeof o);
    o.node = static_cast<uint32_t>(object_nodes[k]);
    o.chain = static_cast<uint32_t>(scene.nodes[object_nodes[k]].mesh);
    o.importance = opt.importance.empty() ? 1.0f : opt.importance[k];
    o.flags = !opt.must_draw.empty() && opt.must_draw[k] ? 1u : 0u;
    o.user_data = opt.user_data.empty() ? uint64_t(object_nodes[k]) : opt.user_data[k];
  }

  // fixed layout up to the data section
  bool attributes = false, groups = !scene.materials.empty();
  for (const LodChain& chain : chains)
    for (const LodLevel& l : chain.levels) {
      attributes = attributes || hasExtraAttributes(l);
      groups = groups || !l.mesh.edge_groups.empty() || !l.mesh.point_groups.empty();
    }
  for (const MeshData& m : scene.meshes) groups = groups || !m.primitive_materials.empty();  // in range: validateSceneData
  const bool materials = !scene.materials.empty();
  bool morphs = false;
  for (const LodChain& chain : chains) {
    const size_t kept = opt.max_levels == 0 ? chain.levels.size() : std::min(chain.levels.size(), opt.max_levels);
    for (size_t l = 0; l + 1 < kept; ++l) morphs = morphs || !chain.levels[l].morph.empty();
  }
  const uint32_t section_count =
      kRequiredSectionKinds + uint32_t(attributes) + uint32_t(materials) + uint32_t(morphs) + uint32_t(groups);
  std::vector<MaterialRecord> material_records(scene.materials.size());
  const uint32_t source_name = materials ? addName(names, opt.material_source) : 0;
  for (size_t i = 0; i < scene.materials.size(); ++i) {
    const MaterialData& md = scene.materials[i];
    MaterialRecord& r = material_records[i];
    std::memset(&r, 0, sizeof r);
    r.name = addName(names, md.name);
    r.source = source_name;
    r.index = static_cast<int32_t>(i);
    r.flags = md.textured ? 1u : 0u;
    std::memcpy(r.base_color, &md.base_color[0], sizeof r.base_color);
    std::memcpy(r.average_texel_color, &md.average_texel_color[0], sizeof r.average_texel_color);
    r.base_color_texture = md.base_color_texture;
    r.base_color_texcoord = md.base_color_texcoord;
    const TextureTransform& t = md.base_color_transform;
    const float tf[5] = {t.offset.x, t.offset.y, t.rotation, t.scale.x, t.scale.y};
    std::memcpy(r.transform, tf, sizeof tf);
    r.transform_texcoord = t.texcoord;
  }
  std::vector<ChainRecord> chain_records(chains.size());
  std::vector<LevelRecord> levels;
  for (size_t c = 0; c < chains.size(); ++c) {
    const size_t kept = opt.max_levels == 0 ? chains[c].levels.size() : std::min(chains[c].levels.size(), opt.max_levels);
    ChainRecord& cr = chain_records[c];
    std::memset(&cr, 0, sizeof cr);
    cr.first_level = static_cast<uint32_t>(levels.size());
    cr.level_count = static_cast<uint32_t>(kept);
    cr.name = addName(names, scene.meshes[c].name);
    cr.sphere[0] = chain_spheres[c].center.x;
    cr.sphere[1] = chain_spheres[c].center.y;
    cr.sphere[2] = chain_spheres[c].center.z;
    cr.sphere[3] = chain_spheres[c].radius;
    levels.resize(levels.size() + kept);
  }
  size_t at = align16(sizeof(FileHeader));
  const size_t table_at = at;
  at = align16(at + section_count * sizeof(SectionEntry));
  struct Placed { uint32_t kind; size_t offset, count; };
  std::vector<Placed> placed;
  auto place = [&](uint32_t kind, size_t count) {
    placed.push_back({kind, at, count});
    at = align16(at + count * kElementBytes[kind]);
  };
  place(kNodes, nodes.size());
  place(kChildren, children.size());
  place(kRoots, roots.size());
  place(kObjects, objects.size());
  place(kChains, chain_records.size());
  place(kLevels, levels.size());
  place(kNames, names.size());
  std::vector<LevelAttributesRecord> level_attributes(attributes ? levels.size() : 0);
  if (attributes) place(kLevelAttributes, level_attributes.size());
  if (materials) place(kMaterials, material_records.size());
  std::vector<LevelMorphRecord> level_morphs(morphs ? levels.size() : 0);
  if (morphs) place(kLevelMorphs, level_morphs.size());
  std::vector<LevelGroupsRecord> level_groups(groups ? levels.size() : 0);
  if (groups) place(kLevelGroups, level_groups.size());
  const size_t data_base = at;

  Writer w;
  double acmr_before = 0.0, acmr_after = 0.0, weight = 0.0;
  std::vector<uint32_t> remap, original_remap;
  for (size_t c = 0; c < chains.size(); ++c) {
    const std::vector<int32_t>& group_materials = scene.meshes[c].primitive_materials;
    const uint64_t group_materials_at = groups ? w.array(group_materials, data_base) : 0;
    for (uint32_t l = 0; l < chain_records[c].level_count; ++l) {
      const LodLevel& src = chains[c].levels[l];
      const std::string level_name = what + " chain " + std::to_string(c) + " level " + std::to_string(l);
      if (Error e = validateMesh(src.mesh, level_name); !e.ok()) return e;
      if (Error e = checkLevelExtras(src, chains[c].levels[0].mesh.vertexCount(), level_name); !e.ok()) return e;
      if (Error e = checkLevelMorph(src, level_name); !e.ok()) return e;
      Mesh m = src.mesh;
      const double tris = double(m.triangleCount());
      if (tris > 0) acmr_before += tris * computeAcmr(Span<const uint32_t>(m.triangles.data(), m.triangles.size()), m.vertexCount());
      remap.clear();
      if (opt.optimize_order) optimizeMeshOrder(m, &remap);
      if (l == 0) original_remap = remap;
      if (tris > 0) {
        acmr_after += tris * computeAcmr(Span<const uint32_t>(m.triangles.data(), m.triangles.size()), m.vertexCount());
        weight += tris;
      }
      LevelRecord& r = levels[chain_records[c].first_level + l];
      std::memset(&r, 0, sizeof r);
      r.cell_width = src.cell_width;
      r.max_error = src.max_error;
      r.method = static_cast<uint32_t>(src.method);
      r.bounds[0] = src.bounds.center.x;
      r.bounds[1] = src.bounds.center.y;
      r.bounds[2] = src.bounds.center.z;
      r.bounds[3] = src.bounds.radius;
      r.vertex_count = static_cast<uint32_t>(m.vertexCount());
      r.triangle_count = static_cast<uint32_t>(m.triangleCount());
      r.edge_count = static_cast<uint32_t>(m.edgeCount());
      r.point_count = static_cast<uint32_t>(m.pointCount());
      r.positions = w.array(m.positions, data_base);
      r.normals = w.array(m.normals, data_base);
      r.colors = w.array(m.colors, data_base);
      r.uvs = w.array(m.uvs, data_base);
      r.triangles = w.array(m.triangles, data_base);
      r.edges = w.array(m.edges, data_base);
      r.thickness = w.array(m.edge_thickness, data_base);
      r.points = w.array(m.points, data_base);
      if (attributes)
        level_attributes[chain_records[c].first_level + l] = writeAttributes(w, data_base, m, src.source_vertex, remap, original_remap);
      if (morphs && l + 1 < chain_records[c].level_count)
        level_morphs[chain_records[c].first_level + l] = writeMorph(w, data_base, src.morph, remap);
      if (groups) {
        LevelGroupsRecord& g = level_groups[chain_records[c].first_level + l];
        std::memset(&g, 0, sizeof g);
        g.group_count = static_cast<uint32_t>(group_materials.size());
        g.group_materials = group_materials_at;
        g.edge_groups = w.array(m.edge_groups, data_base);
        g.point_groups = w.array(m.point_groups, data_base);
      }
    }
  }
  place(kData, w.data.size());
  const size_t file_bytes = at;

  out.assign(file_bytes, 0);
  FileHeader h;
  std::memset(&h, 0, sizeof h);
  std::memcpy(h.magic, kPackMagic, 8);
  h.version = kPackVersion;
  h.header_bytes = sizeof(FileHeader);
  h.file_bytes = file_bytes;
  h.section_count = section_count;
  h.section_table_offset = table_at;
  std::memcpy(out.data(), &h, sizeof h);
  for (size_t s = 0; s < placed.size(); ++s) {
    SectionEntry e{placed[s].kind, kElementBytes[placed[s].kind], placed[s].offset, placed[s].count, 0};
    std::memcpy(out.data() + table_at + s * sizeof(SectionEntry), &e, sizeof e);
  }
  // each section's contents at its place (a kind not written is not in `placed`)
  auto put = [&](uint32_t kind, const void* src, size_t bytes) {
    for (const Placed& p : placed)
      if (p.kind == kind && bytes) std::memcpy(out.data() + p.offset, src, bytes);
  };
  put(kNodes, nodes.data(), nodes.size() * sizeof(NodeRecord));
  put(kChildren, children.data(), children.size() * 4);
  put(kRoots, roots.data(), roots.size() * 4);
  put(kObjects, objects.data(), objects.size() * sizeof(ObjectRecord));
  put(kChains, chain_records.data(), chain_records.size() * sizeof(ChainRecord));
  put(kLevels, levels.data(), levels.size() * sizeof(LevelRecord));
  put(kNames, names.data(), names.size());
  put(kLevelAttributes, level_attributes.data(), level_attributes.size() * sizeof(LevelAttributesRecord));
  put(kMaterials, material_records.data(), material_records.size() * sizeof(MaterialRecord));
  put(kLevelMorphs, level_morphs.data(), level_morphs.size() * sizeof(LevelMorphRecord));
  put(kLevelGroups, level_groups.data(), level_groups.size() * sizeof(LevelGroupsRecord));
  put(kData, w.data.data(), w.data.size());
  const uint32_t crc = crc32(out.data(), out.size());
  std::memcpy(out.data() + kChecksumOffset, &crc, 4);
  if (stats) {
    stats->bytes = file_bytes;
    stats->acmr_before = weight > 0 ? acmr_before / weight : 0.0;
    stats->acmr_after = weight > 0 ? acmr_after / weight : 0.0;
  }
  return {};
}

Error writePack(const std::string& path, const SceneData& scene, const std::vector<LodChain>& chains,
                const std::vector<Sphere>& chain_spheres, const PackWriteOptions& options, PackWriteStats* stats) {
  std::vector<uint8_t> bytes;
  if (Error e = writePackBytes(bytes, scene, chains, chain_spheres, options, stats, path); !e.ok()) return e;
  return writeFileAtomic(path, bytes.data(), bytes.size());
}

// ---- loading ----

Error Pack::load(const std::string& path, Pack& out, bool check_indices) {
  out = Pack{};
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return {Status::kIoError, path + ": cannot open: " + std::strerror(errno)};
  if (std::fseek(f, 0, SEEK_END) != 0) { std::fclose(f); return {Status::kIoError, path + ": cannot seek"}; }
  const long size = std::ftell(f);
  std::rewind(f);
  if (size < 0) { std::fclose(f); return {Status::kIoError, path + ": cannot tell the file size"}; }
  out.bytes_.resize(static_cast<size_t>(size));
  const size_t got = size > 0 ? std::fread(out.bytes_.data(), 1, out.bytes_.size(), f) : 0;
  std::fclose(f);
  if (got != out.bytes_.size()) return {Status::kIoError, path + ": read " + std::to_string(got) + " of " + std::to_string(size) + " bytes"};
  return out.parse(path, check_indices);
}

Error Pack::fromBytes(const uint8_t* data, size_t size, Pack& out, const std::string& what, bool check_indices) {
  out = Pack{};
  out.bytes_.assign(data, data + size);
  return out.parse(what, check_indices);
}

namespace {

// [offset, offset + count x element_bytes) lies inside `size` bytes, in arithmetic that cannot wrap
// (a hostile offset near 2^64 plus a small count must not pass for a small offset)
bool inside(uint64_t offset, uint64_t count, uint64_t element_bytes, uint64_t size) {
  return offset <= size && (element_bytes == 0 || count <= (size - offset) / element_bytes);
}

// every record of the pack is read through here: out of range reads give a zeroed record, never
// bytes past the end (parse() refuses such packs before any accessor runs)
template <class T>
T read(const std::vector<uint8_t>& b, uint64_t offset) {
  static_assert(std::is_trivially_copyable<T>::value, "records are plain data");
  T t{};
  if (inside(offset, 1, sizeof t, b.size())) std::memcpy(&t, b.data() + offset, sizeof t);
  return t;
}

// A level record r's attribute record a: arrays inside the data section and consistent with the
// level's counts, joint parents a forest; with check_indices, joints below the joint count and
// source vertices below level 0's vertex count. Returns the problem after the record's name.
Error checkAttributes(const std::vector<uint8_t>& bytes, const LevelAttributesRecord& a, const LevelRecord& r,
                      uint32_t original_vertices, size_t data_begin, size_t data_end, bool check_indices) {
  auto arrayOk = [&](uint64_t at, uint64_t n, uint64_t elem) {
    return at == 0 || (at % 4 == 0 && at >= data_begin && at <= data_end && n <= (data_end - at) / elem);
  };
  const uint64_t v = r.vertex_count;
  // first, so that a set count of 0 never divides below
  if ((a.extra_uv_set_count == 0) != (a.extra_uvs == 0) || (a.joints == 0) != (a.weights == 0) ||
      (a.joint_count == 0) != (a.joint_parents == 0))
    return {Status::kCorrupt, " has texture coordinate sets, skin joints and weights or joint parents without their arrays"};
  if (!arrayOk(a.extra_uvs, v, 8ull * a.extra_uv_set_count) || !arrayOk(a.tangents, v, 16) || !arrayOk(a.joints, v, 8) ||
      !arrayOk(a.weights, v, 16) || !arrayOk(a.joint_parents, a.joint_count, 4) ||
      !arrayOk(a.triangle_groups, r.triangle_count, 4) || !arrayOk(a.source_vertex, v, 4))
    return {Status::kCorrupt, " has an attribute array outside the data section"};
  const int32_t* parents = reinterpret_cast<const int32_t*>(bytes.data() + a.joint_parents);
  for (uint32_t j = 0; j < a.joint_count; ++j)
    if (parents[j] < -1 || parents[j] >= int64_t(a.joint_count)) return {Status::kCorrupt, " has a joint parent out of range"};
  if (a.joint_count > 0 && firstParentCycle(Span<const int32_t>(parents, a.joint_count)) < a.joint_count)
    return {Status::kCorrupt, " has joint parents that form a cycle"};
  if (!check_indices) return {};
  const glm::u16vec4* joints = reinterpret_cast<const glm::u16vec4*>(bytes.data() + a.joints);
  if (a.joints != 0 && a.joint_count > 0)
    for (uint64_t i = 0; i < v; ++i)
      for (int c = 0; c < 4; ++c)
        if (joints[i][c] >= a.joint_count) return {Status::kCorrupt, " has a skin joint out of range"};
  const uint32_t* source = reinterpret_cast<const uint32_t*>(bytes.data() + a.source_vertex);
  if (a.source_vertex != 0)
    for (uint64_t i = 0; i < v; ++i)
      if (source[i] >= original_vertices) return {Status::kCorrupt, " has a source vertex out of range"};
  return {};
}

// A level record r's morph record m: no targets, or one per vertex of the level with every array
// inside the data section. Returns the problem after the record's name.
Error checkMorph(const LevelMorphRecord& m, const LevelRecord& r, size_t data_begin, size_t data_end) {
  auto arrayOk = [&](uint64_t at, uint64_t n, uint64_t elem) {
    return at == 0 || (at % 4 == 0 && at >= data_begin && at <= data_end && n <= (data_end - at) / elem);
  };
  if (m.vertex_count == 0) {
    if (m.positions || m.normals || m.colors || m.uvs || m.extra_uvs || m.tangents)
      return {Status::kCorrupt, " has geomorph arrays for 0 vertices"};
    return {};
  }
  if (m.vertex_count != r.vertex_count)
    return {Status::kCorrupt, " has geomorph targets for " + std::to_string(m.vertex_count) + " vertices, the level has " +
                                  std::to_string(r.vertex_count)};
  const uint64_t v = m.vertex_count;
  if (m.positions == 0 || (m.extra_uv_set_count == 0) != (m.extra_uvs == 0))
    return {Status::kCorrupt, " has geomorph targets without positions, or texture coordinate sets without their array"};
  if (!arrayOk(m.positions, v, 12) || !arrayOk(m.normals, v, 12) || !arrayOk(m.colors, v, 12) || !arrayOk(m.uvs, v, 8) ||
      !arrayOk(m.extra_uvs, v, 8ull * m.extra_uv_set_count) || !arrayOk(m.tangents, v, 16))
    return {Status::kCorrupt, " has a geomorph array outside the data section"};
  return {};
}

}  // namespace

Error Pack::parse(const std::string& what, bool check_indices) {
  auto corrupt = [&](const std::string& m) { return Error(Status::kCorrupt, what + ": " + m); };
  const size_t size = bytes_.size();
  if (size < 8 || std::memcmp(bytes_.data(), kPackMagic, 8) != 0)
    return {Status::kParseError, what + ": not a scenelod pack (no SLODPACK magic at the start)"};
  if (size < sizeof(FileHeader))
    return corrupt("truncated: " + std::to_string(size) + " bytes, a pack header alone has 64");
  const FileHeader h = read<FileHeader>(bytes_, 0);
  if (h.version != kPackVersion)
    return {Status::kUnsupported, what + ": pack version " + std::to_string(h.version) + ", this build reads version " +
                                      std::to_string(kPackVersion) + " only (rebuild the pack with 'scenelod pack')"};
  if (!littleEndianHost()) return {Status::kUnsupported, what + ": packs are little-endian; this host is not"};
  if (h.file_bytes != size)
    return corrupt(h.file_bytes > size ? "truncated: the header says " + std::to_string(h.file_bytes) + " bytes, the file has " + std::to_string(size)
                                       : "the header says " + std::to_string(h.file_bytes) + " bytes but the file has " + std::to_string(size) + " (trailing data)");
  uint32_t crc = crc32(bytes_.data(), kChecksumOffset);
  const uint32_t zero = 0;
  crc = crc32(&zero, 4, crc);
  crc = crc32(bytes_.data() + kChecksumOffset + 4, size - kChecksumOffset - 4, crc);
  if (crc != h.checksum) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "checksum mismatch (stored %08x, computed %08x): the file is corrupt", h.checksum, crc);
    return corrupt(buf);
  }
  // from here on the bytes are what the writer wrote, unless made by hand: keep checking bounds
  if (h.header_bytes != sizeof(FileHeader) || h.section_table_offset % 16 != 0 || h.section_count > 64 ||
      !inside(h.section_table_offset, h.section_count, sizeof(SectionEntry), size))
    return corrupt("section table out of bounds");
  size_t offset[kSectionKindCount + 1] = {}, count[kSectionKindCount + 1] = {};
  bool seen[kSectionKindCount + 1] = {};
  for (uint32_t s = 0; s < h.section_count; ++s) {
    const SectionEntry e = read<SectionEntry>(bytes_, h.section_table_offset + s * sizeof(SectionEntry));
    // unknown sections are skipped (minor additions)
    if (e.kind == 0 || e.kind > kSectionKindCount || kElementBytes[e.kind] == 0) continue;
    if (e.element_bytes != kElementBytes[e.kind])
      return corrupt("section " + std::to_string(e.kind) + " has " + std::to_string(e.element_bytes) + "-byte elements, expected " +
                     std::to_string(kElementBytes[e.kind]));
    if (e.offset % 4 != 0 || !inside(e.offset, e.count, e.element_bytes, size))
      return corrupt("section " + std::to_string(e.kind) + " lies outside the file");
    offset[e.kind] = e.offset;
    count[e.kind] = e.count;
    seen[e.kind] = true;
  }
  for (uint32_t k = 1; k <= kRequiredSectionKinds; ++k)
    if (!seen[k]) return corrupt("section " + std::to_string(k) + " is missing");
  nodes_ = offset[kNodes]; node_count_ = count[kNodes];
  children_ = offset[kChildren]; children_count_ = count[kChildren];
  roots_ = offset[kRoots]; root_count_ = count[kRoots];
  objects_ = offset[kObjects]; object_count_ = count[kObjects];
  chains_ = offset[kChains]; chain_count_ = count[kChains];
  levels_ = offset[kLevels]; level_count_ = count[kLevels];
  names_ = offset[kNames]; names_size_ = count[kNames];
  attributes_ = seen[kLevelAttributes] ? offset[kLevelAttributes] : 0;
  if (seen[kLevelAttributes] && count[kLevelAttributes] != level_count_)
    return corrupt("section 9 has " + std::to_string(count[kLevelAttributes]) + " level attribute records for " +
                   std::to_string(level_count_) + " level records");
  morphs_ = seen[kLevelMorphs] ? offset[kLevelMorphs] : 0;
  if (seen[kLevelMorphs] && count[kLevelMorphs] != level_count_)
    return corrupt("section 11 (geomorphs) has " + std::to_string(count[kLevelMorphs]) + " level morph records for " +
                   std::to_string(level_count_) + " level records");
  materials_ = seen[kMaterials] ? offset[kMaterials] : 0;
  material_count_ = seen[kMaterials] ? count[kMaterials] : 0;
  groups_ = seen[kLevelGroups] ? offset[kLevelGroups] : 0;
  if (seen[kLevelGroups] && count[kLevelGroups] != level_count_)
    return corrupt("section 12 has " + std::to_string(count[kLevelGroups]) + " level group records for " +
                   std::to_string(level_count_) + " level records");
  if (names_size_ > 0 && bytes_[names_ + names_size_ - 1] != 0) return corrupt("names section is not terminated");
  auto nameOk = [&](uint32_t n) { return names_size_ > 0 && n < names_size_; };
  for (size_t i = 0; i < material_count_; ++i) {
    const MaterialRecord r = read<MaterialRecord>(bytes_, materials_ + i * sizeof(MaterialRecord));
    if (!nameOk(r.name) || !nameOk(r.source)) return corrupt("material " + std::to_string(i) + " has a name out of range");
  }
  std::vector<int32_t> parents(node_count_);
  for (size_t i = 0; i < node_count_; ++i) {
    const NodeRecord r = read<NodeRecord>(bytes_, nodes_ + i * sizeof(NodeRecord));
    if (r.parent < -1 || r.parent >= int64_t(node_count_) || r.mesh < -1 || r.mesh >= int64_t(chain_count_) ||
        uint64_t(r.first_child) + r.child_count > children_count_ || !nameOk(r.name))
      return corrupt("node " + std::to_string(i) + " has an index out of range");
    parents[i] = r.parent;
  }
  if (firstParentCycle(Span<const int32_t>(parents.data(), parents.size())) < parents.size())
    return corrupt("the node parents form a cycle");
  for (size_t i = 0; i < children_count_; ++i)
    if (read<uint32_t>(bytes_, children_ + 4 * i) >= node_count_) return corrupt("child list entry out of range");
  for (size_t i = 0; i < root_count_; ++i)
    if (read<uint32_t>(bytes_, roots_ + 4 * i) >= node_count_) return corrupt("root out of range");
  for (size_t i = 0; i < object_count_; ++i) {
    const ObjectRecord o = read<ObjectRecord>(bytes_, objects_ + i * sizeof(ObjectRecord));
    if (o.node >= node_count_ || o.chain >= chain_count_) return corrupt("object " + std::to_string(i) + " has an index out of range");
  }
  // per level record: the vertex count of its chain's level 0 (what source vertices index)
  std::vector<uint32_t> original_vertices(level_count_, 0);
  for (size_t c = 0; c < chain_count_; ++c) {
    const ChainRecord r = read<ChainRecord>(bytes_, chains_ + c * sizeof(ChainRecord));
    if (uint64_t(r.first_level) + r.level_count > level_count_ || !nameOk(r.name))
      return corrupt("chain " + std::to_string(c) + " has a level range out of bounds");
    if (r.level_count == 0) return corrupt("chain " + std::to_string(c) + " has no levels (level 0 is the original)");
    const uint32_t v0 = read<LevelRecord>(bytes_, levels_ + size_t(r.first_level) * sizeof(LevelRecord)).vertex_count;
    for (uint32_t l = 0; l < r.level_count; ++l) original_vertices[r.first_level + l] = v0;
  }
  const size_t data_begin = offset[kData], data_end = offset[kData] + count[kData];
  auto arrayOk = [&](uint64_t at, uint64_t n, uint64_t elem, bool optional) {
    if (at == 0) return optional || n == 0;
    return at % 4 == 0 && at >= data_begin && at <= data_end && n <= (data_end - at) / elem;
  };
  for (size_t l = 0; l < level_count_; ++l) {
    const LevelRecord r = read<LevelRecord>(bytes_, levels_ + l * sizeof(LevelRecord));
    const std::string where = "level record " + std::to_string(l);
    const uint64_t v = r.vertex_count;
    if (!arrayOk(r.positions, v, 12, false) || !arrayOk(r.normals, v, 12, true) || !arrayOk(r.colors, v, 12, true) ||
        !arrayOk(r.uvs, v, 8, true) || !arrayOk(r.triangles, 3ull * r.triangle_count, 4, false) ||
        !arrayOk(r.edges, 2ull * r.edge_count, 4, false) || !arrayOk(r.thickness, r.edge_count, 4, true) ||
        !arrayOk(r.points, r.point_count, 4, false) || r.method > uint32_t(LodMethod::kScrooge))
      return corrupt(where + " has an array outside the data section");
    if (check_indices) {
      auto indicesOk = [&](uint64_t at, uint64_t n) {
        if (n == 0) return true;
        const uint32_t* p = reinterpret_cast<const uint32_t*>(bytes_.data() + at);
        uint32_t worst = 0;
        for (uint64_t i = 0; i < n; ++i) worst = p[i] > worst ? p[i] : worst;
        return worst < v;
      };
      if (!indicesOk(r.triangles, 3ull * r.triangle_count) || !indicesOk(r.edges, 2ull * r.edge_count) ||
          !indicesOk(r.points, r.point_count))
        return corrupt(where + " has a vertex index out of range");
    }
    if (attributes_ != 0)
      if (Error e = checkAttributes(bytes_, read<LevelAttributesRecord>(bytes_, attributes_ + l * sizeof(LevelAttributesRecord)), r,
                                    original_vertices[l], data_begin, data_end, check_indices);
          !e.ok())
        return corrupt(where + e.message);
    if (morphs_ != 0)
      if (Error e = checkMorph(read<LevelMorphRecord>(bytes_, morphs_ + l * sizeof(LevelMorphRecord)), r, data_begin, data_end);
          !e.ok())
        return corrupt(where + e.message);
    if (groups_ != 0) {
      const LevelGroupsRecord g = read<LevelGroupsRecord>(bytes_, groups_ + l * sizeof(LevelGroupsRecord));
      if (!arrayOk(g.group_materials, g.group_count, 4, false) || !arrayOk(g.edge_groups, r.edge_count, 4, true) ||
          !arrayOk(g.point_groups, r.point_count, 4, true))
        return corrupt(where + " has a group array outside the data section");
      const int32_t* mats = reinterpret_cast<const int32_t*>(bytes_.data() + g.group_materials);
      for (uint32_t i = 0; i < g.group_count; ++i)
        if (mats[i] < -1 || mats[i] >= int64_t(material_count_))
          return corrupt(where + " has group " + std::to_string(i) + " with material " + std::to_string(mats[i]) + " but the pack has " +
                         std::to_string(material_count_) + " materials");
    }
  }
  return {};
}

size_t Pack::nodeCount() const { return node_count_; }
size_t Pack::rootCount() const { return root_count_; }
size_t Pack::objectCount() const { return object_count_; }
size_t Pack::chainCount() const { return chain_count_; }
uint32_t Pack::root(size_t i) const { return read<uint32_t>(bytes_, roots_ + 4 * i); }

size_t Pack::levelCount(size_t chain) const {
  return read<ChainRecord>(bytes_, chains_ + chain * sizeof(ChainRecord)).level_count;
}

PackNodeView Pack::node(size_t i) const {
  const size_t at = nodes_ + i * sizeof(NodeRecord);
  const NodeRecord r = read<NodeRecord>(bytes_, at);
  PackNodeView v;
  v.parent = r.parent;
  v.mesh = r.mesh;
  v.local = reinterpret_cast<const float*>(bytes_.data() + at + offsetof(NodeRecord, local));
  v.children = Span<const uint32_t>(reinterpret_cast<const uint32_t*>(bytes_.data() + children_) + r.first_child, r.child_count);
  v.name = reinterpret_cast<const char*>(bytes_.data() + names_ + r.name);
  return v;
}

PackObjectView Pack::object(size_t i) const {
  const ObjectRecord r = read<ObjectRecord>(bytes_, objects_ + i * sizeof(ObjectRecord));
  return PackObjectView{r.node, r.chain, r.importance, (r.flags & 1u) != 0, r.user_data};
}

Sphere Pack::chainSphere(size_t c) const {
  const ChainRecord r = read<ChainRecord>(bytes_, chains_ + c * sizeof(ChainRecord));
  return Sphere{glm::vec3(r.sphere[0], r.sphere[1], r.sphere[2]), r.sphere[3]};
}

const char* Pack::meshName(size_t c) const {
  const ChainRecord r = read<ChainRecord>(bytes_, chains_ + c * sizeof(ChainRecord));
  return reinterpret_cast<const char*>(bytes_.data() + names_ + r.name);
}

PackLevelView Pack::level(size_t chain, size_t level) const {
  const ChainRecord c = read<ChainRecord>(bytes_, chains_ + chain * sizeof(ChainRecord));
  const LevelRecord r = read<LevelRecord>(bytes_, levels_ + (c.first_level + level) * sizeof(LevelRecord));
  PackLevelView v;
  v.cell_width = r.cell_width;
  v.max_error = r.max_error;
  v.method = static_cast<LodMethod>(r.method);
  v.bounds = Sphere{glm::vec3(r.bounds[0], r.bounds[1], r.bounds[2]), r.bounds[3]};
  auto span = [&](auto* type_tag, uint64_t at, size_t n) {
    using T = std::remove_pointer_t<decltype(type_tag)>;
    return at == 0 ? Span<const T>() : Span<const T>(reinterpret_cast<const T*>(bytes_.data() + at), n);
  };
  v.positions = span((glm::vec3*)nullptr, r.positions, r.vertex_count);
  v.normals = span((glm::vec3*)nullptr, r.normals, r.vertex_count);
  v.colors = span((glm::vec3*)nullptr, r.colors, r.vertex_count);
  v.uvs = span((glm::vec2*)nullptr, r.uvs, r.vertex_count);
  v.triangles = span((uint32_t*)nullptr, r.triangles, 3 * size_t(r.triangle_count));
  v.edges = span((uint32_t*)nullptr, r.edges, 2 * size_t(r.edge_count));
  v.edge_thickness = span((float*)nullptr, r.thickness, r.edge_count);
  v.points = span((uint32_t*)nullptr, r.points, r.point_count);
  if (groups_ != 0) {
    const LevelGroupsRecord g = read<LevelGroupsRecord>(bytes_, groups_ + (c.first_level + level) * sizeof(LevelGroupsRecord));
    v.group_materials = span((int32_t*)nullptr, g.group_materials, g.group_count);
    v.edge_groups = span((uint32_t*)nullptr, g.edge_groups, r.edge_count);
    v.point_groups = span((uint32_t*)nullptr, g.point_groups, r.point_count);
  }
  if (attributes_ == 0) return v;
  const LevelAttributesRecord a =
      read<LevelAttributesRecord>(bytes_, attributes_ + (c.first_level + level) * sizeof(LevelAttributesRecord));
  v.extra_uv_set_count = a.extra_uvs == 0 ? 0 : a.extra_uv_set_count;
  v.extra_uvs = span((glm::vec2*)nullptr, a.extra_uvs, v.extra_uv_set_count * r.vertex_count);
  v.tangents = span((glm::vec4*)nullptr, a.tangents, r.vertex_count);
  v.joints = span((glm::u16vec4*)nullptr, a.joints, r.vertex_count);
  v.weights = span((glm::vec4*)nullptr, a.weights, r.vertex_count);
  v.joint_parents = span((int32_t*)nullptr, a.joint_parents, a.joint_count);
  v.triangle_groups = span((uint32_t*)nullptr, a.triangle_groups, r.triangle_count);
  v.source_vertex = span((uint32_t*)nullptr, a.source_vertex, r.vertex_count);
  return v;
}

PackLevelMorphView Pack::levelMorph(size_t chain, size_t level) const {
  PackLevelMorphView v;
  if (morphs_ == 0) return v;
  const ChainRecord c = read<ChainRecord>(bytes_, chains_ + chain * sizeof(ChainRecord));
  const LevelMorphRecord m = read<LevelMorphRecord>(bytes_, morphs_ + (c.first_level + level) * sizeof(LevelMorphRecord));
  if (m.vertex_count == 0) return v;
  const size_t n = m.vertex_count;
  auto span = [&](auto* type_tag, uint64_t at, size_t count) {
    using T = std::remove_pointer_t<decltype(type_tag)>;
    return at == 0 ? Span<const T>() : Span<const T>(reinterpret_cast<const T*>(bytes_.data() + at), count);
  };
  v.positions = span((glm::vec3*)nullptr, m.positions, n);
  v.normals = span((glm::vec3*)nullptr, m.normals, n);
  v.colors = span((glm::vec3*)nullptr, m.colors, n);
  v.uvs = span((glm::vec2*)nullptr, m.uvs, n);
  v.extra_uv_set_count = m.extra_uvs == 0 ? 0 : m.extra_uv_set_count;
  v.extra_uvs = span((glm::vec2*)nullptr, m.extra_uvs, v.extra_uv_set_count * n);
  v.tangents = span((glm::vec4*)nullptr, m.tangents, n);
  return v;
}

namespace {
Mesh meshFromLevel(const PackLevelView& v) {
  Mesh m;
  m.positions.assign(v.positions.begin(), v.positions.end());
  m.normals.assign(v.normals.begin(), v.normals.end());
  m.colors.assign(v.colors.begin(), v.colors.end());
  m.uvs.assign(v.uvs.begin(), v.uvs.end());
  m.triangles.assign(v.triangles.begin(), v.triangles.end());
  m.edges.assign(v.edges.begin(), v.edges.end());
  m.edge_thickness.assign(v.edge_thickness.begin(), v.edge_thickness.end());
  m.points.assign(v.points.begin(), v.points.end());
  const size_t n = v.positions.size();
  m.extra_uvs.resize(v.extra_uv_set_count);
  for (size_t s = 0; s < v.extra_uv_set_count; ++s) m.extra_uvs[s].assign(v.extra_uvs.begin() + s * n, v.extra_uvs.begin() + (s + 1) * n);
  m.tangents.assign(v.tangents.begin(), v.tangents.end());
  m.joints.assign(v.joints.begin(), v.joints.end());
  m.weights.assign(v.weights.begin(), v.weights.end());
  m.joint_parents.assign(v.joint_parents.begin(), v.joint_parents.end());
  m.triangle_groups.assign(v.triangle_groups.begin(), v.triangle_groups.end());
  m.edge_groups.assign(v.edge_groups.begin(), v.edge_groups.end());
  m.point_groups.assign(v.point_groups.begin(), v.point_groups.end());
  return m;
}
}  // namespace

size_t Pack::materialCount() const { return material_count_; }

PackMaterialView Pack::material(size_t i) const {
  const MaterialRecord r = read<MaterialRecord>(bytes_, materials_ + i * sizeof(MaterialRecord));
  PackMaterialView v;
  v.name = reinterpret_cast<const char*>(bytes_.data() + names_ + r.name);
  v.source = reinterpret_cast<const char*>(bytes_.data() + names_ + r.source);
  v.source_index = r.index;
  v.textured = (r.flags & 1u) != 0;
  v.base_color = glm::vec4(r.base_color[0], r.base_color[1], r.base_color[2], r.base_color[3]);
  v.average_texel_color = glm::vec3(r.average_texel_color[0], r.average_texel_color[1], r.average_texel_color[2]);
  v.base_color_texture = r.base_color_texture;
  v.base_color_texcoord = r.base_color_texcoord;
  v.base_color_transform.offset = glm::vec2(r.transform[0], r.transform[1]);
  v.base_color_transform.rotation = r.transform[2];
  v.base_color_transform.scale = glm::vec2(r.transform[3], r.transform[4]);
  v.base_color_transform.texcoord = r.transform_texcoord;
  return v;
}

std::vector<PackMaterialRange> materialRanges(const PackLevelView& level) {
  std::vector<PackMaterialRange> ranges;
  const size_t n = level.triangles.size() / 3;
  for (size_t t = 0; t < n; ++t) {
    const uint32_t g = level.triangle_groups.empty() ? 0u : level.triangle_groups[t];
    if (!ranges.empty() && ranges.back().group == g) {
      ++ranges.back().triangle_count;
      continue;
    }
    const int32_t material = g < level.group_materials.size() ? level.group_materials[g] : -1;
    ranges.push_back(PackMaterialRange{static_cast<uint32_t>(t), 1u, g, material});
  }
  return ranges;
}

void Pack::toSceneData(SceneData& out) const {
  out = SceneData{};
  out.nodes.resize(node_count_);
  for (size_t i = 0; i < node_count_; ++i) {
    const PackNodeView v = node(i);
    NodeData& n = out.nodes[i];
    n.name = v.name;
    n.parent = v.parent;
    n.mesh = v.mesh;
    n.children.assign(v.children.begin(), v.children.end());
    std::memcpy(&n.local[0][0], v.local, 16 * sizeof(float));
  }
  for (size_t i = 0; i < root_count_; ++i) out.roots.push_back(static_cast<int32_t>(root(i)));
  out.meshes.resize(chain_count_);
  for (size_t c = 0; c < chain_count_; ++c) {
    out.meshes[c].name = meshName(c);
    if (levelCount(c) == 0) continue;
    const PackLevelView l0 = level(c, 0);
    out.meshes[c].mesh = meshFromLevel(l0);
    out.meshes[c].primitive_materials.assign(l0.group_materials.begin(), l0.group_materials.end());
  }
  // the textures stay in the source file: references to them are dropped here
  out.materials.resize(material_count_);
  for (size_t i = 0; i < material_count_; ++i) {
    const PackMaterialView v = material(i);
    MaterialData& m = out.materials[i];
    m.name = v.name;
    m.base_color = v.base_color;
    m.textured = v.textured;
    m.average_texel_color = v.average_texel_color;
    m.base_color_texcoord = v.base_color_texcoord;
    m.base_color_transform = v.base_color_transform;
  }
}

void Pack::toChains(std::vector<LodChain>& chains, std::vector<Sphere>& spheres) const {
  chains.assign(chain_count_, LodChain{});
  spheres.resize(chain_count_);
  for (size_t c = 0; c < chain_count_; ++c) {
    spheres[c] = chainSphere(c);
    const size_t n = levelCount(c);
    chains[c].levels.resize(n);
    for (size_t l = 0; l < n; ++l) {
      const PackLevelView v = level(c, l);
      LodLevel& dst = chains[c].levels[l];
      dst.mesh = meshFromLevel(v);
      dst.cell_width = v.cell_width;
      dst.max_error = v.max_error;
      dst.method = v.method;
      dst.bounds = v.bounds;
      dst.source_vertex.assign(v.source_vertex.begin(), v.source_vertex.end());
      const PackLevelMorphView mv = levelMorph(c, l);
      LevelMorph& morph = dst.morph;
      morph.positions.assign(mv.positions.begin(), mv.positions.end());
      morph.normals.assign(mv.normals.begin(), mv.normals.end());
      morph.colors.assign(mv.colors.begin(), mv.colors.end());
      morph.uvs.assign(mv.uvs.begin(), mv.uvs.end());
      const size_t vn = mv.positions.size();
      morph.extra_uvs.resize(mv.extra_uv_set_count);
      for (size_t s = 0; s < mv.extra_uv_set_count; ++s)
        morph.extra_uvs[s].assign(mv.extra_uvs.begin() + s * vn, mv.extra_uvs.begin() + (s + 1) * vn);
      morph.tangents.assign(mv.tangents.begin(), mv.tangents.end());
    }
  }
}

Error Pack::toScene(Scene& out) const {
  // nodes through SceneData (no meshes needed: objects come from the pack's object table)
  SceneData d;
  d.nodes.resize(node_count_);
  for (size_t i = 0; i < node_count_; ++i) {
    const PackNodeView v = node(i);
    d.nodes[i].parent = v.parent;
    d.nodes[i].children.assign(v.children.begin(), v.children.end());
    std::memcpy(&d.nodes[i].local[0][0], v.local, 16 * sizeof(float));
  }
  for (size_t i = 0; i < root_count_; ++i) d.roots.push_back(static_cast<int32_t>(root(i)));
  if (Error e = Scene::fromSceneData(d, out, "pack"); !e.ok()) return e;
  out.setChainCount(chain_count_);
  for (size_t c = 0; c < chain_count_; ++c)
    if (Error e = out.setChainSphere(static_cast<uint32_t>(c), chainSphere(c)); !e.ok()) return e;
  for (size_t k = 0; k < object_count_; ++k) {
    const PackObjectView o = object(k);
    ObjectHandle h;
    if (Error e = out.addObject(ObjectDesc{NodeHandle{o.node, 0}, o.chain, o.importance, o.must_draw, o.user_data}, h); !e.ok())
      return e;
  }
  out.update();
  return {};
}

}  // namespace scenelod::scene
