#pragma once
// Shared pieces of the clustering pipeline (grading, uniform and floating-cell assignment, synthesis,
// elimination, thick edges, normals): the per-level assignment record and a flat grid hash.
#include <cmath>
#include <cstdint>
#include <vector>

#include <glm/common.hpp>
#include <glm/vec3.hpp>

#include "scenelod/lodcore/cluster.h"

namespace scenelod::detail {

constexpr uint32_t kNone = 0xffffffffu;

// Integer coordinates of a grid cube.
struct GridKey {
  int32_t x, y, z;
  bool operator==(const GridKey& o) const { return x == o.x && y == o.y && z == o.z; }
};

// Open-addressing hash from grid cube to a uint32 value (a cluster id or a list head). Grows by
// doubling at half load. A slot is empty while its value is kNone, so callers store a value other
// than kNone right after at() inserts. Lookup order never affects results: callers break ties by value.
class GridHash {
 public:
  explicit GridHash(size_t expected) {
    size_t cap = 64;
    while (cap < expected * 2) cap <<= 1;
    slots_.assign(cap, Slot{0, 0, 0, kNone});
  }

  // returns the value stored for `k`, or kNone
  uint32_t find(const GridKey& k) const {
    const size_t mask = slots_.size() - 1;
    for (size_t i = hash(k) & mask;; i = (i + 1) & mask) {
      const Slot& s = slots_[i];
      if (s.value == kNone) return kNone;
      if (s.x == k.x && s.y == k.y && s.z == k.z) return s.value;
    }
  }

  // returns a reference to the value of `k`; a new key's value is kNone and must be set at once
  uint32_t& at(const GridKey& k) {
    if ((size_ + 1) * 2 > slots_.size()) grow();
    const size_t mask = slots_.size() - 1;
    for (size_t i = hash(k) & mask;; i = (i + 1) & mask) {
      Slot& s = slots_[i];
      if (s.value == kNone) {
        s.x = k.x, s.y = k.y, s.z = k.z;
        ++size_;
        return s.value;
      }
      if (s.x == k.x && s.y == k.y && s.z == k.z) return s.value;
    }
  }

  size_t size() const { return size_; }

 private:
  struct Slot {  // 16 bytes: key and value in one cache line access
    int32_t x, y, z;
    uint32_t value;
  };
  static size_t hash(const GridKey& k) {
    uint64_t h = uint64_t(uint32_t(k.x)) * 0x9E3779B97F4A7C15ull + uint64_t(uint32_t(k.y)) * 0xC2B2AE3D27D4EB4Full +
                 uint64_t(uint32_t(k.z)) * 0x165667B19E3779F9ull;
    h ^= h >> 32;
    h *= 0xff51afd7ed558ccdull;
    return static_cast<size_t>(h ^ (h >> 29));
  }
  void grow() {
    std::vector<Slot> old;
    old.swap(slots_);
    slots_.assign(old.size() * 2, Slot{0, 0, 0, kNone});
    size_ = 0;
    for (const Slot& s : old)
      if (s.value != kNone) at({s.x, s.y, s.z}) = s.value;
  }

  std::vector<Slot> slots_;
  size_t size_ = 0;
};

// Which cluster each vertex joined, and the cell each cluster is bound to (for clamping). The
// clusterings number clusters in creation order (heaviest first), as `assign` and assignClusters
// return them; a level (clusterLevelParts) renumbers them in the order of their first vertex by
// index before elimination and synthesis (renumberByFirstVertex in cluster_mesh.cpp).
struct Assignment {
  std::vector<uint32_t> cluster_of;  // per vertex; kNone for vertices no primitive references
  std::vector<uint32_t> heaviest;    // per cluster: its heaviest vertex (the floating cell's centre)
  uint32_t cluster_count = 0;
  float cell_width = 0.0f;
  bool uniform = false;
  glm::vec3 grid_origin{0.0f};       // uniform: the bounding-box minimum the grid starts at
  CellShape shape = CellShape::kCube;

  // the box a representative of the cluster whose heaviest vertex lies at `p` is clamped to (a
  // sphere cell clamps in synthesis); taking the position, not the cluster, spares a random read.
  // Inline: synthesis calls it once per cluster.
  void cellBox(const glm::vec3& p, glm::vec3& lo, glm::vec3& hi) const {
    if (uniform) {
      const glm::vec3 q = (p - grid_origin) * (1.0f / cell_width);
      lo = grid_origin + glm::floor(q) * cell_width;
      hi = lo + glm::vec3(cell_width);
    } else {
      lo = p - glm::vec3(0.5f * cell_width);
      hi = p + glm::vec3(0.5f * cell_width);
    }
  }

  // starts a level over `vertex_count` vertices, none assigned yet
  void reset(size_t vertex_count, float width, bool is_uniform, CellShape cell_shape) {
    cluster_of.assign(vertex_count, kNone);
    heaviest.clear();
    cluster_count = 0;
    cell_width = width;
    uniform = is_uniform;
    shape = cell_shape;
  }
};

// For each 8-bit lane mask, the indices of its set lanes in order, one byte each: the permutation
// that packs the selected lanes of an 8-lane vector to the front (the AVX2 compactions of the
// floating-cell heads and of the elimination's classes; 2 KB, built at compile time)
struct LaneCompaction {
  uint64_t lanes[256];
  constexpr LaneCompaction() : lanes() {
    for (uint32_t mask = 0; mask < 256; ++mask) {
      uint64_t packed = 0;
      int n = 0;
      for (uint32_t lane = 0; lane < 8; ++lane)
        if (mask & (1u << lane)) packed |= uint64_t(lane) << (8 * n++);
      lanes[mask] = packed;
    }
  }
};
inline constexpr LaneCompaction kLaneCompaction;

// floor to int32 without a libm call (inputs are checked to stay within +-2^30)
inline int32_t floorToInt(float x) {
  const int32_t i = static_cast<int32_t>(x);
  return i - static_cast<int32_t>(x < static_cast<float>(i));
}

// Largest cell-grid coordinate we accept along an axis (keeps GridKey in int32 with headroom).
constexpr double kMaxGridCoordinate = 1073741824.0;  // 2^30

// Checks that `cell_width` is finite, > 0 and not too small for the bounds.
// The referenced positions in weight order: PreparedMesh::sorted_positions where it is kept, else
// read through the order. A chain drops the sorted copy of a small mesh (kSortedCopyMinBytes), whose
// positions a level's random reads find in cache: on the bunny it was 0.42 MB of its chain's peak,
// which comes while the last levels assign. Read so by the uniform grid and the floating cells'
// flat grids of side w/2 (a test per vertex, always taken the same way); the grid of side w in
// blocks and the hash, the paths of large meshes, stream the copy.
struct PositionsByWeight {
  explicit PositionsByWeight(const PreparedMesh& p)
      : sorted(p.sorted_positions.empty() ? nullptr : p.sorted_positions.data()),
        positions(p.mesh->positions.data()),
        order(p.order.data()) {}
  glm::vec3 operator[](size_t i) const { return sorted ? sorted[i] : positions[order[i]]; }
  const glm::vec3* sorted;
  const glm::vec3* positions;
  const uint32_t* order;
};
constexpr size_t kSortedCopyMinBytes = size_t(1) << 19;
// The sorted copy itself, for the loops that stream it (meshes above that size): p.sorted_positions,
// or, where it was dropped, a copy made into `local` (only on paths a small mesh rarely takes)
inline const glm::vec3* sortedPositions(const PreparedMesh& p, std::vector<glm::vec3>& local) {
  if (!p.sorted_positions.empty() || p.order.empty()) return p.sorted_positions.data();
  local.resize(p.order.size());
  for (size_t i = 0; i < p.order.size(); ++i) local[i] = p.mesh->positions[p.order[i]];
  return local.data();
}

Error checkCellWidth(const PreparedMesh& p, float cell_width);

// uniform_cluster.cpp: Rossignac & Borrel grid over the bounding box.
void assignUniform(const PreparedMesh& p, float cell_width, Assignment& out);
// floating_cell_cluster.cpp: Low & Tan §3.2 and §4.
void assignFloating(const PreparedMesh& p, float cell_width, CellShape shape, bool nearest, Assignment& out);

// synthesis.cpp: one representative per cluster, plus the cluster's area-weighted colour and normal.
struct Representatives {
  std::vector<glm::vec3> positions;  // per cluster
  std::vector<glm::vec3> colors;     // per cluster, empty when the input has none
  std::vector<glm::vec3> normals;    // per cluster: area-weighted input face normal (for edges, points)
};
void synthesize(const PreparedMesh& p, const Assignment& a, Synthesis synthesis, Representatives& out);

// synthesis.cpp: whether synthesize, buildOutputMesh and the grading run their AVX2 variants (the
// same source compiled for AVX2 without FMA, so the same bits): where the CPU has AVX2, unless the
// test hook useAvx2Paths (test_hooks.h) turned them off.
bool avx2Paths();

// x86: the attribute of the AVX2 variants (elsewhere they compile as plain copies, never chosen)
#if defined(__x86_64__) || defined(__i386__)
#define SCENELOD_AVX2_TARGET __attribute__((target("avx2")))
#else
#define SCENELOD_AVX2_TARGET
#endif
// a body shared by a baseline function and its AVX2 variant, compiled into each
#define SCENELOD_ALWAYS_INLINE inline __attribute__((always_inline))
// whether this CPU runs the AVX2 variants (AVX2 and POPCNT, which every AVX2 CPU has; the
// floating-cell grid's compaction counts bits); false where they are not built
inline bool cpuHasAvx2() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("popcnt");
#else
  return false;
#endif
}

// elimination.cpp: cluster-level primitives after removing degenerate, duplicate and covered ones.
struct Eliminated {
  std::vector<uint32_t> triangles;  // cluster ids, 3 per triangle
  std::vector<uint32_t> edges;      // cluster ids, 2 per edge
  std::vector<float> edge_thickness;
  std::vector<uint32_t> points;     // cluster ids
  size_t collapsed_triangles = 0;
};
// with compute_thickness false, edge_thickness stays empty (counting only)
void eliminate(const PreparedMesh& p, const Assignment& a, bool keep_edges, bool keep_points,
               bool compute_thickness, Eliminated& out);

// thick_edge.cpp: §3.3.1 thickness D_A + D_B of edges made by collapsing triangles. `edge_of_pair`
// maps the sorted cluster pair (a < b) of each collapsed triangle to its edge index in `e`.
struct CollapsedTriangle {
  uint32_t triangle;
  uint32_t edge;  // index into e.edges / 2
};
void computeThickness(const PreparedMesh& p, const Assignment& a, const std::vector<CollapsedTriangle>& collapsed,
                      Eliminated& e);

// normals.cpp: builds the output mesh from cluster-level primitives, splitting vertices whose
// incident faces meet at more than the crease angle. Consumes e.triangles and e.edge_thickness (their
// storage becomes the output's).
void buildOutputMesh(Eliminated& e, const Representatives& r, float crease_angle_deg, Mesh& out);

// cluster_mesh.cpp: clusterPrepared in two steps, so that a chain can hold a level between them.
// The first (assignment, elimination, synthesis) reads the prepared mesh: its order and sorted
// positions only until the assignment is made, when `assigned` (if given) is called with `context`;
// the second (buildOutputMesh) reads none of it, so it may run after the prepared arrays are freed.
struct LevelParts {
  Eliminated eliminated;
  Representatives representatives;
  // set before clusterLevelParts to keep each cluster's heaviest vertex for finishLevel's source
  // vertices (clusterPrepared with ClusterOutputs); a chain's levels do not
  bool keep_heaviest = false;
  std::vector<uint32_t> heaviest;  // per cluster, when kept
  // set before clusterLevelParts to keep the assignment's cluster of every vertex (for geomorphs)
  bool keep_cluster_of = false;
  std::vector<uint32_t> cluster_of;  // per vertex of the prepared mesh, when kept
};
// With `synthesized` given, synthesis comes before elimination and `synthesized(synthesized_context)`
// is called between them (the prepared mesh's arrays are not read after it, only its mesh).
Error clusterLevelParts(const PreparedMesh& prepared, const ClusterParams& params, LevelParts& parts,
                        ClusterStats* stats, void (*assigned)(void*) = nullptr, void* context = nullptr,
                        void (*synthesized)(void*) = nullptr, void* synthesized_context = nullptr);
// frees parts; `source_vertex` (optional, parts.heaviest kept) gets each output vertex's cluster's
// heaviest vertex, `vertex_cluster` (optional) each output vertex's cluster
void finishLevel(LevelParts& parts, const ClusterParams& params, Mesh& out,
                 std::vector<uint32_t>* source_vertex = nullptr, std::vector<uint32_t>* vertex_cluster = nullptr);
// The same first step from an assignment already made at params.cell_width (by `assign`, e.g. a
// width search's last probe, which a chain keeps as its first level's); consumes `a`.
Error clusterLevelParts(const PreparedMesh& prepared, const ClusterParams& params, Assignment& a, LevelParts& parts,
                        ClusterStats* stats, void (*synthesized)(void*) = nullptr, void* context = nullptr);
// The assignment step alone: checks the width and the method, then assigns every vertex.
Error assign(const PreparedMesh& prepared, const ClusterParams& params, Assignment& a);
// The first step's renumbering of a level's clusters by first vertex (levels of 32,768 clusters or
// more; the others are left as they are), which clusterLevelParts does to the assignment it is
// given; public to the tools that time the steps apart (bench/tools/level_phases.cpp).
void renumberByFirstVertex(Assignment& a);

}  // namespace scenelod::detail
