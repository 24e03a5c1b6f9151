// Floating-cell clustering (Low & Tan 1997 §3.2 and §4). Vertices are visited heaviest first (the
// sort is done once per mesh, PreparedMesh); a vertex inside no existing cell becomes the centre of
// a new cell of width w (a cube of side w or a sphere of diameter w). A vertex inside several cells
// joins the one with the heaviest centre (§3.2) or, in the variant of §3.2.3, the nearest centre.
//
// §4's grid: space is cut into cubes of side w (from the origin, so the grid, like the cells, does not
// depend on the bounding box) and each cell is listed in the cube holding its centre. A cell's centre
// is never inside another cell, so two centres are more than w/2 apart along some axis (cube cells)
// or in distance (sphere cells): a grid cube lists at most 8 cube cells (one per w/2 octant) and at
// most 64 sphere cells (one per w/4 sub-cube, whose diagonal is below w/2). Cells past the third
// of a cube are chained through flat arrays, so a list's length needs no fixed bound. A cell containing a vertex at q (grid
// units) has its centre within 1/2 of q along each axis: only the 2 x 2 x 2 cubes covering
// [q - 1/2, q + 1/2] are searched. When the mesh's box spans few enough grid cubes, the grid is a flat
// array of list heads over that box (one load per cube, no hashing), preferably of cubes of side w/2
// (3 x 3 x 3 of them searched: 2.4 times less volume than 2 x 2 x 2 cubes of side w, so fewer cells
// to test; each lists at most one cube cell), else of cubes of side w whose cells are kept in
// blocks of 4 where these fit too (one copy per cube instead of a walk along a list), else listed;
// otherwise, where a table of the box's bricks of 4 x 4 x 4 cubes and the bricks holding vertices
// (counted first) take at most 21 bytes per expected cell, the blocks under heads in those bricks
// (CellBlocks); otherwise (scattered parts, boxes mostly empty) a hash whose slots hold each grid
// cube's first three cells inline (one cache line per cube), the slots of the next vertices in
// weight order being prefetched. All give the same cells:
// the joining rule breaks ties by id. The flat grids have AVX2 variants (floating_cell_avx2.cpp),
// chosen at run time, that gather the heads by rows and test cells 8 at a time with the same
// operations and order; where cells are rare among the vertices (coarse levels of a small mesh),
// the AVX2 grid of side w/2 keeps per grid cube the cells its vertices test (CandidateCache).
#include <algorithm>
#include <atomic>
#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>
#include <utility>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#if defined(__SSE2__)
#include <emmintrin.h>
#include <xmmintrin.h>
#endif
// the AVX2 paths are built on x86 beside the SSE2 ones (a build without SSE2 keeps the scalar paths)

#include "floating_cell_internal.h"
#include "test_hooks.h"
namespace scenelod::detail {

using namespace floating;

namespace {
// vertices ahead of the current one whose grid slots are prefetched (the search is bound by the
// latency of its random slot reads, vertices being visited in weight order). With the home slot of
// the vertex's own cube prefetched too, the 1 M sphere's 50 % level (17 MB of slots) assigned in
// 105 ms instead of 124 (minima of 32, AMD Zen 3); 8 ahead, or the slot after each home as well,
// did no better
constexpr size_t kPrefetchDistance = 4;
// One grid cube in the hash: its key and the first cells listed in it, inline, so that testing a
// cube costs one cache line. A grid cube lists at most 8 cube cells (64 sphere cells); those past
// the third go to an overflow chain, rare on surfaces (about one cell per occupied cube).
struct alignas(64) CubeSlot {
  int32_t x, y, z;
  uint32_t n;            // cells listed in this cube; 0 marks an empty slot
  float cx[3], cy[3], cz[3];  // centres of the first three
  uint32_t id[3];
};
static_assert(sizeof(CubeSlot) == 64, "one cache line per grid cube");

// Linear in the coordinates, so the hashes of a cube's neighbours are one addition away; the table
// index is taken from the top bits (a Kronecker sequence over the lattice, well spread).
constexpr uint64_t kHashX = 0x9E3779B97F4A7C15ull, kHashY = 0xC2B2AE3D27D4EB4Full, kHashZ = 0x165667B19E3779F9ull;
uint64_t cubeHash(int32_t x, int32_t y, int32_t z) {
  return uint64_t(int64_t(x)) * kHashX + uint64_t(int64_t(y)) * kHashY + uint64_t(int64_t(z)) * kHashZ;
}

// Open-addressing hash from grid cube to its listed cells, of any capacity (the home slot is the
// hash's top 32 bits scaled to the capacity), so that it is sized to the expected cube count rather
// than the next power of two; grows by doubling at 3/4 load.
class CellGrid {
 public:
  explicit CellGrid(size_t expected_cubes) { reset(std::max<size_t>(64, expected_cubes * 4 / 3 + 1)); }
  size_t home(uint64_t h) const { return static_cast<size_t>(((h >> 32) * uint64_t(slots_.size())) >> 32); }
  // false: the cube certainly lists no cell (at least 8 bits per slot, at most 3/32 of them set), so
  // most empty cubes cost one access to this small array instead of probing the slots
  bool mayHold(uint64_t h) const {
    const size_t b = static_cast<size_t>(h >> 8) & filter_mask_;
    return (filter_[b >> 6] >> (b & 63)) & 1u;
  }
  void prefetch(uint64_t h) const {
    if (mayHold(h)) __builtin_prefetch(&slots_[home(h)]);
  }
  // the slot a new cube of hash h would be added at first (its home), held or not
  void prefetchHome(uint64_t h) const { __builtin_prefetch(&slots_[home(h)]); }

  // the slot of cube (x, y, z) or null; call only when mayHold(h)
  const CubeSlot* findHeld(int32_t x, int32_t y, int32_t z, uint64_t h) const {
    const size_t cap = slots_.size();
    for (size_t i = home(h);; i = i + 1 == cap ? 0 : i + 1) {
      const CubeSlot& s = slots_[i];
      if (s.n == 0) return nullptr;
      if (s.x == x && s.y == y && s.z == z) return &s;
    }
  }
  const CubeSlot* find(int32_t x, int32_t y, int32_t z, uint64_t h) const {
    if (!mayHold(h)) return nullptr;
    const size_t cap = slots_.size();
    for (size_t i = home(h);; i = i + 1 == cap ? 0 : i + 1) {
      const CubeSlot& s = slots_[i];
      if (s.n == 0) return nullptr;
      if (s.x == x && s.y == y && s.z == z) return &s;
    }
  }
  uint32_t overflowHead(const CubeSlot* s) const { return overflow_head_[size_t(s - slots_.data())]; }

  // lists cell `id` centred at `c` in cube (x, y, z)
  void add(int32_t x, int32_t y, int32_t z, const glm::vec3& c, uint32_t id) {
    if ((size_ + 1) * 4 > slots_.size() * 3) grow();  // load <= 3/4: the filter keeps misses short
    const uint64_t h = cubeHash(x, y, z);
    const size_t i = slotFor(x, y, z, h);
    CubeSlot& s = slots_[i];
    if (s.n == 0) {
      s.x = x, s.y = y, s.z = z;
      ++size_;
      setFilter(h);
    }
    if (s.n < 3) {
      s.cx[s.n] = c.x, s.cy[s.n] = c.y, s.cz[s.n] = c.z, s.id[s.n] = id;
    } else {
      overflow_centre.push_back(c);
      overflow_id.push_back(id);
      overflow_next.push_back(overflow_head_[i]);
      overflow_head_[i] = static_cast<uint32_t>(overflow_id.size() - 1);
    }
    ++s.n;
  }

  // overflow cells (the fourth and later of a cube), chained per cube
  std::vector<glm::vec3> overflow_centre;
  std::vector<uint32_t> overflow_id, overflow_next;

 private:
  void reset(size_t cap) {
    slots_.assign(cap, CubeSlot{0, 0, 0, 0, {}, {}, {}, {}});
    overflow_head_.assign(cap, kNone);
    size_t bits = 64;
    while (bits < cap * 8) bits <<= 1;
    filter_.assign(bits / 64, 0);
    filter_mask_ = bits - 1;
    size_ = 0;
  }
  // the slot holding cube (x, y, z), or the empty slot where it goes
  size_t slotFor(int32_t x, int32_t y, int32_t z, uint64_t h) const {
    const size_t cap = slots_.size();
    for (size_t i = home(h);; i = i + 1 == cap ? 0 : i + 1) {
      const CubeSlot& s = slots_[i];
      if (s.n == 0 || (s.x == x && s.y == y && s.z == z)) return i;
    }
  }
  void grow() {
    std::vector<CubeSlot> old;
    std::vector<uint32_t> old_head;
    old.swap(slots_);
    old_head.swap(overflow_head_);
    reset(old.size() * 2);
    for (size_t k = 0; k < old.size(); ++k) {
      if (old[k].n == 0) continue;
      const uint64_t h = cubeHash(old[k].x, old[k].y, old[k].z);
      const size_t i = slotFor(old[k].x, old[k].y, old[k].z, h);
      slots_[i] = old[k];
      overflow_head_[i] = old_head[k];
      setFilter(h);
      ++size_;
    }
  }
  void setFilter(uint64_t h) {
    const size_t b = static_cast<size_t>(h >> 8) & filter_mask_;
    filter_[b >> 6] |= uint64_t(1) << (b & 63);
  }

  std::vector<CubeSlot> slots_;
  std::vector<uint32_t> overflow_head_;  // per slot: first overflow cell, kNone
  std::vector<uint64_t> filter_;         // bits set for the hashes of occupied cubes
  size_t filter_mask_ = 63;
  size_t size_ = 0;
};

// The AVX2 variants (floating_cell_avx2.cpp), chosen at run time where the CPU has AVX2
#if defined(SCENELOD_FLOATING_AVX2)
constexpr bool kAvx2Built = true;
#else
constexpr bool kAvx2Built = false;
#endif
// cleared by setFloatingAvx2ForTest, so that a test can compare the paths on one CPU
std::atomic<bool> g_avx2_allowed{true}, g_cache_allowed{true};
// the bricked grid of side w in blocks: -1 the default, 0 never (the hash instead), k > 0 with a
// limit of k bricks in place of kBrickBytesPerCell's (setFloatingBlockBricksForTest)
std::atomic<int> g_block_bricks{-1};
// the grid the last assignFloating call searched (lastFloatingGridForTest)
enum : int { kGridFlat = 0, kGridBricked = 1, kGridHash = 2, kGridHashForBricks = 3 };
std::atomic<int> g_last_grid{-1};
[[maybe_unused]] bool useAvx2() {  // unused where no AVX2 path is built
  static const bool has = cpuHasAvx2();
  return kAvx2Built && has && g_avx2_allowed.load(std::memory_order_relaxed);
}

template <bool kCube, bool kNearest>
void assignDenseT(const PreparedMesh& p, float cube_width, float reach, const int32_t lo_cube[3],
                  const size_t dims[3], JoinRule rule, size_t expected, Assignment& out) {
  DenseGrid grid(dims, expected);
  auto& cells = grid.cells;
  auto& head = grid.head;
  const size_t sy = grid.sy, sz = grid.sz;
  const float inv = 1.0f / cube_width;
  const float slack = kSearchSlack * 2.0f * reach;  // the same fraction of a cell width
  const size_t n = p.order.size();
  // through the order where a chain dropped a small mesh's sorted copy (no copy made per level)
  const PositionsByWeight sorted(p);
  for (size_t i = 0; i < n; ++i) {
    const glm::vec3 pv = sorted[i];
    const glm::vec3 q = pv * inv;
    int32_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = floorToInt(q[a] - reach - slack) - lo_cube[a];
      hi[a] = floorToInt(q[a] + reach + slack) - lo_cube[a];
    }
    // the non-empty heads first, gathered without a branch: which of the 27 cubes hold a cell is
    // random, so testing each head would mispredict about once per vertex and cube
    uint32_t found[64 + 3];  // at most 4 cubes per axis (a vertex within the slack of a cube face)
    uint32_t found_count = 0;
    if (hi[0] - lo[0] == 2 && hi[1] - lo[1] == 2 && hi[2] - lo[2] == 2) {
      // the common case of cubes of side w/2 (3 per axis), unrolled
      const uint32_t* base = head.data() + size_t(lo[2]) * sz + size_t(lo[1]) * sy + size_t(lo[0]);
      for (int z = 0; z < 3; ++z)
        for (int y = 0; y < 3; ++y) {
          const uint32_t* row = base + size_t(z) * sz + size_t(y) * sy;
          for (int x = 0; x < 3; ++x) {
            found[found_count] = row[x];
            found_count += row[x] != 0;
          }
        }
    } else {
      for (int32_t z = lo[2]; z <= hi[2]; ++z)
        for (int32_t y = lo[1]; y <= hi[1]; ++y) {
          const uint32_t* row = head.data() + size_t(z) * sz + size_t(y) * sy;
          for (int32_t x = lo[0]; x <= hi[0]; ++x) {
            found[found_count] = row[x];
            found_count += row[x] != 0;
          }
        }
    }
    uint32_t best = kNone;
#if defined(__SSE2__)
    {
      // the cells found, four at a time, one per lane, without a branch per cell: each lane computes
      // d^2 and the containment with testCell's operations and keeps its least (d^2, id) under the
      // same order, then the four lanes' minima are reduced, so the cell chosen is the same; the
      // list is padded with the sentinel (never inside). A cube of side w/2 lists at most one cube
      // cell; where lists are longer (sphere cells, cubes of side w), the successors of the cells
      // just tested are gathered (without a branch) and tested the same way, one round per step
      // along the lists.
      const __m128 px = _mm_set1_ps(pv.x), py = _mm_set1_ps(pv.y), pz = _mm_set1_ps(pv.z);
      __m128 bd2 = _mm_set1_ps(std::numeric_limits<float>::infinity());
      __m128i bid = _mm_set1_epi32(0x7fffffff);
      uint32_t* list = found;
      uint32_t list_count = found_count;
      uint32_t successors[64 + 3];
      for (;;) {
        const __m128i chained =
            testCellLanes<kCube, kNearest>(cells.data(), list, list_count, px, py, pz, rule, bd2, bid);
        if (_mm_movemask_epi8(_mm_cmpeq_epi32(chained, _mm_setzero_si128())) == 0xffff) break;
        uint32_t* next_list = list == found ? successors : found;
        list_count = listSuccessors(cells.data(), list, list_count, next_list);
        list = next_list;
      }
      best = laneBest<kNearest>(bd2, bid);
    }
#else
    float best_d2 = std::numeric_limits<float>::infinity();
    for (uint32_t j = 0; j < found_count; ++j)
      for (uint32_t c = found[j]; c != 0; c = cells[c].next)
        testCellT<kCube, kNearest>(rule, pv, cells[c].x, cells[c].y, cells[c].z, c - 1, best, best_d2);
#endif
    if (best == kNone) {
      best = out.cluster_count++;
      out.heaviest.push_back(p.order[i]);
      const int32_t cx = floorToInt(q.x) - lo_cube[0], cy = floorToInt(q.y) - lo_cube[1],
                    cz = floorToInt(q.z) - lo_cube[2];
      grid.list(cx, cy, cz, pv, best);
    }
    out.cluster_of[p.order[i]] = best;
  }
}

// The bricks of 4 x 4 x 4 cubes of side 1 / inv (numbered as CellBlocks<true> numbers them) that
// hold a referenced vertex, counted until they pass `limit`: at least the bricks a level's cells
// take, each cell being listed in the cube of its centre, a vertex (the same products and floors)
size_t countVertexBricks(const PreparedMesh& p, float inv, const int32_t lo_cube[3], const size_t dims[3],
                         size_t limit) {
  const size_t bx = (dims[0] + 3) / 4, by = (dims[1] + 3) / 4, bz = (dims[2] + 3) / 4;
  std::vector<uint64_t> seen((bx * by * bz + 63) / 64, 0);  // (fewer than 2^32 bricks: the caller's test)
  const PositionsByWeight pos(p);
  const uint32_t sy = uint32_t(bx), sz = uint32_t(bx * by);
  size_t count = 0;
  uint32_t brick[512];  // a run's brick indices first (no dependence between vertices), then their bits
  for (size_t i0 = 0, n = p.order.size(); i0 < n && count <= limit; i0 += 512) {
    const size_t m = std::min<size_t>(512, n - i0);
    for (size_t k = 0; k < m; ++k) {
      const glm::vec3 v = pos[i0 + k];
      brick[k] = (uint32_t(floorToInt(v.z * inv) - lo_cube[2]) >> 2) * sz +
                 (uint32_t(floorToInt(v.y * inv) - lo_cube[1]) >> 2) * sy +
                 (uint32_t(floorToInt(v.x * inv) - lo_cube[0]) >> 2);
    }
    for (size_t k = 0; k < m; ++k) {
      const uint32_t b = brick[k];
      const uint64_t bit = uint64_t(1) << (b & 63);
      count += (seen[b >> 6] & bit) == 0;
      seen[b >> 6] |= bit;
    }
  }
  return count;
}

template <bool kCube, bool kNearest, bool kBricked>
void assignBlocksT(const PreparedMesh& p, float cube_width, const int32_t lo_cube[3], const size_t dims[3],
                   JoinRule rule, size_t expected, size_t brick_count, Assignment& out) {
  struct Cell {
    float x, y, z;
    uint32_t zero;  // no chain: testCellLanes' OR of these is unused
  };
  std::vector<Cell> cells;  // cells[k + 1] is cluster k's cell; cells[0] the sentinel at NaN
  cells.reserve(CellBlocks<kBricked>::reservedCells(expected, p.order.size()));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cells.push_back({nan, nan, nan, 0});
  CellBlocks<kBricked> grid(dims, expected, brick_count);
  std::vector<uint32_t> scratch;  // the general gather's list
  const float inv = 1.0f / cube_width;
  const float slack = kSearchSlack;  // the reach is half a cube
  const size_t n = p.order.size();
  std::vector<glm::vec3> local;  // (the sorted copy, where a chain dropped it)
  const glm::vec3* sorted = sortedPositions(p, local);
  for (size_t i = 0; i < n; ++i) {
    const glm::vec3 pv = sorted[i];
    const glm::vec3 q = pv * inv;
    int32_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = floorToInt(q[a] - 0.5f - slack) - lo_cube[a];
      hi[a] = floorToInt(q[a] + 0.5f + slack) - lo_cube[a];
    }
    uint32_t found[8 * 5 + 8];  // 8 blocks at counts up to 5, 3 sentinels of padding
    uint32_t* list = found;
    uint32_t count = 0;
    uint32_t chained = 0;
    const bool narrow = hi[0] - lo[0] == 1 && hi[1] - lo[1] == 1 && hi[2] - lo[2] == 1;
    if (narrow) {
      uint32_t h[8];
      grid.heads8(lo, size_t(lo[2]) * grid.sz + size_t(lo[1]) * grid.sy + size_t(lo[0]), h);
      count = grid.copyBlocks8(h, found, chained);
    }
    if (!narrow || (chained & 8u)) {
      count = grid.gatherAll(lo, hi, scratch, 3);
      list = scratch.data();
    }
    uint32_t best = kNone;
#if defined(__SSE2__)
    {
      __m128 bd2 = _mm_set1_ps(std::numeric_limits<float>::infinity());
      __m128i bid = _mm_set1_epi32(0x7fffffff);
      testCellLanes<kCube, kNearest>(cells.data(), list, count, _mm_set1_ps(pv.x), _mm_set1_ps(pv.y),
                                     _mm_set1_ps(pv.z), rule, bd2, bid);
      best = laneBest<kNearest>(bd2, bid);
    }
#else
    float best_d2 = std::numeric_limits<float>::infinity();
    for (uint32_t j = 0; j < count; ++j) {
      const Cell& c = cells[list[j]];
      testCellT<kCube, kNearest>(rule, pv, c.x, c.y, c.z, list[j] - 1, best, best_d2);
    }
#endif
    if (best == kNone) {
      best = out.cluster_count;
      grid.add(floorToInt(q.x) - lo_cube[0], floorToInt(q.y) - lo_cube[1], floorToInt(q.z) - lo_cube[2], best + 1);
      ++out.cluster_count;
      out.heaviest.push_back(p.order[i]);
      cells.push_back({pv.x, pv.y, pv.z, 0});
    }
    out.cluster_of[p.order[i]] = best;
  }
}

// the grid of side w in blocks (assignBlocksT), flat or bricked (brick_count: countVertexBricks)
void assignBlocks(const PreparedMesh& p, float cube_width, const int32_t lo_cube[3], const size_t dims[3],
                  JoinRule rule, size_t expected, bool bricked, size_t brick_count, Assignment& out) {
  using Fn = void (*)(const PreparedMesh&, float, const int32_t*, const size_t*, JoinRule, size_t, size_t,
                      Assignment&);
#if defined(SCENELOD_FLOATING_AVX2)
  if (useAvx2()) {
    assignBlocksAvx2(p, cube_width, lo_cube, dims, rule, expected, bricked, brick_count, out);
    return;
  }
#endif
  static constexpr Fn kBlockFns[2][2][2] = {
      {{assignBlocksT<false, false, false>, assignBlocksT<false, true, false>},
       {assignBlocksT<true, false, false>, assignBlocksT<true, true, false>}},
      {{assignBlocksT<false, false, true>, assignBlocksT<false, true, true>},
       {assignBlocksT<true, false, true>, assignBlocksT<true, true, true>}}};
  kBlockFns[bricked][rule.cube][rule.nearest](p, cube_width, lo_cube, dims, rule, expected, brick_count, out);
}

void assignDense(const PreparedMesh& p, float cube_width, float reach, const int32_t lo_cube[3],
                 const size_t dims[3], JoinRule rule, size_t expected, bool blocks, Assignment& out) {
  using Fn = void (*)(const PreparedMesh&, float, float, const int32_t*, const size_t*, JoinRule, size_t,
                      Assignment&);
  // cubes of side w (a reach of half a cube) in blocks where the caller found room for them, while
  // block ids fit a head's 29 bits (blocks are at most the cells, which are at most the vertices)
  if (blocks && reach == 0.5f && p.order.size() < (size_t(1) << 28)) {
    assignBlocks(p, cube_width, lo_cube, dims, rule, expected, false, 0, out);
    return;
  }
#if defined(SCENELOD_FLOATING_AVX2)
  // cubes of side w/2 with the candidate cache where cells are rare among the vertices
  if (useAvx2() && reach == 1.0f && g_cache_allowed.load(std::memory_order_relaxed) &&
      double(p.order.size()) >= kCacheVerticesPerCell * double(expected)) {
    assignDenseAvx2(p, cube_width, reach, lo_cube, dims, rule, expected, true, out);
    return;
  }
  if (useAvx2()) {
    assignDenseAvx2(p, cube_width, reach, lo_cube, dims, rule, expected, false, out);
    return;
  }
#endif
  static constexpr Fn kFns[2][2] = {{assignDenseT<false, false>, assignDenseT<false, true>},
                                    {assignDenseT<true, false>, assignDenseT<true, true>}};
  kFns[rule.cube][rule.nearest](p, cube_width, reach, lo_cube, dims, rule, expected, out);
}

}  // namespace

// The grid cubes of side 1 / inv around a box: the first one (lo_cube) and the counts along each
// axis (dims), 3 cubes of margin below and 3 above the box's, so that every searched cube lies
// inside (the slack is far below a cube)
namespace {
void gridBox(const Aabb& box, float inv, int32_t lo_cube[3], size_t dims[3]) {
  for (int a = 0; a < 3; ++a) {
    lo_cube[a] = floorToInt(box.min[a] * inv) - 3;
    dims[a] = size_t(floorToInt(box.max[a] * inv) + 4 - lo_cube[a]);
  }
}
}  // namespace

void assignFloating(const PreparedMesh& p, float cell_width, CellShape shape, bool nearest, Assignment& out) {
  out.reset(p.mesh->vertexCount(), cell_width, false, shape);
  const float inv = 1.0f / cell_width;
  const float half = 0.5f * cell_width;
  const float half2 = half * half;
  const bool cube = shape == CellShape::kCube;

  // cells: about one per w x w patch of surface, never more than the vertices
  const double patches = 2.0 * p.surface_area / (double(cell_width) * double(cell_width));
  const size_t expected = static_cast<size_t>(std::min(double(p.order.size()), patches)) + 16;
  out.heaviest.reserve(expected);
  const JoinRule rule{half, half2, cube, nearest};
  // grid cubes of side w/2 where their heads fit: a vertex then tests the cells of 3 x 3 x 3 cubes
  // of side w/2 instead of 2 x 2 x 2 of side w, 2.4 times less volume, which matters at coarse levels
  // where a cube of side w lists several cells; then cubes of side w; then the hash
  const double dense_budget = std::max(kDenseBaseBytes + kDenseBytesPerCell * double(expected),
                                       kDenseBytesPerVertex * double(p.order.size()));
  for (const int sub : {2, 1}) {
    const float cube_width = cell_width / float(sub);
    const float cube_inv = 1.0f / cube_width;
    // every searched cube lies within two cubes of the box's (the slack is far below a cube)
    int32_t lo_cube[3];
    size_t dims[3];
    gridBox(p.bounds, cube_inv, lo_cube, dims);
    const double volume = double(dims[0]) * double(dims[1]) * double(dims[2]);
    // a listed grid's heads hold a cell's index + 1 in 32 bits (heads of 16 bits, flat or in
    // bricks, were no faster here: tried and not kept)
    if (volume * sizeof(uint32_t) <= dense_budget) {
      // cubes of side w keep their cells in blocks where these fit the budget too (the 1 M sphere's
      // 10 % level): blocks take 11 bytes per expected cell beside the heads
      const bool blocks =
          sub == 1 && volume * sizeof(uint32_t) + kBlockBytes * double(expectedBlocks(expected)) <= dense_budget;
      assignDense(p, cube_width, 0.5f * float(sub), lo_cube, dims, rule, expected, blocks, out);
      g_last_grid.store(kGridFlat, std::memory_order_relaxed);
      return;
    }
  }
  // else cubes of side w in blocks under bricked heads where the table of the box's bricks (1/256 of
  // a flat array of heads) and the bricks holding vertices, counted first (a pass over the
  // positions, 3.1-3.3 ms on the 1 M sphere), take at most kBrickBytesPerCell per expected cell;
  // scattered parts, whose vertices spread over many bricks, and boxes whose table alone passes
  // that, take the hash. The bricks are reserved exactly, never regrown (a regrowth, old and new
  // bricks at once, a try given up past a limit and a table of up to the dense budget put a chain
  // of 10 M triangles in 8,000 parts 3 % past its memory target). The 1 M sphere's 50 % and 25 %
  // levels (the hash's 17 and 8.5 MB of slots) assigned in about 41 and 30 ms instead of 80.1 and
  // 74.2 (Intel Xeon, minima of 5; docs/bench/clustering.md)
  const int block_bricks = g_block_bricks.load(std::memory_order_relaxed);
  bool too_many_bricks = false;
  if (block_bricks != 0 && p.order.size() < (size_t(1) << 28)) {
    int32_t lo_cube[3];
    size_t dims[3];
    gridBox(p.bounds, inv, lo_cube, dims);
    double top_bytes = sizeof(uint32_t);
    for (int a = 0; a < 3; ++a) top_bytes *= double((dims[a] + 3) / 4);
    // the table and the bricks together within kBrickBytesPerCell per expected cell (16 KB at least)
    const double allowance = std::max(16384.0, kBrickBytesPerCell * double(expected));
    if (top_bytes <= dense_budget && top_bytes < kMaxBrickTableBytes && (block_bricks > 0 || top_bytes < allowance)) {
      const size_t brick_limit =
          block_bricks > 0 ? size_t(block_bricks) : size_t((allowance - top_bytes) / double(kBrickBytes));
      const size_t brick_count = countVertexBricks(p, inv, lo_cube, dims, brick_limit);
      if (brick_count <= brick_limit) {
        assignBlocks(p, cell_width, lo_cube, dims, rule, expected, true, brick_count, out);
        g_last_grid.store(kGridBricked, std::memory_order_relaxed);
        return;
      }
      too_many_bricks = true;  // scattered: the hash below
    }
  }
  g_last_grid.store(too_many_bricks ? kGridHashForBricks : kGridHash, std::memory_order_relaxed);
  // occupied grid cubes per expected cell, measured on the 1 M sphere's chain: 0.46 (the width
  // search's first probe), 0.48, 0.53, 0.48 (levels 1-3). Sized for 0.5, level 2 passed the 3/4 load
  // and doubled, old and new slots at once (3.9 + 7.9 MB): part of that chain's peak
  CellGrid grid(expected * 11 / 20);

  const size_t n = p.order.size();
  std::vector<glm::vec3> local;  // (the sorted copy, where a chain dropped it)
  const glm::vec3* sorted = sortedPositions(p, local);
  // the 2 x 2 x 2 grid cubes a vertex searches (all but a rare few need no third along an axis)
  struct Search {
    int32_t lo[3];
    bool wide;   // some axis needs 3 cubes (the vertex is within the slack of a cube face)
    uint64_t h;  // hash of the cube lo; the others add kHashX, kHashY, kHashZ
  };
  const uint64_t step[8] = {0, kHashX, kHashY, kHashX + kHashY, kHashZ, kHashX + kHashZ, kHashY + kHashZ,
                            kHashX + kHashY + kHashZ};
  Search ring[kPrefetchDistance];
  auto plan = [&](size_t i, Search& s) {
    const glm::vec3 q = sorted[i] * inv;
    s.wide = false;
    for (int a = 0; a < 3; ++a) {
      s.lo[a] = floorToInt(q[a] - 0.5f - kSearchSlack);
      s.wide |= floorToInt(q[a] + 0.5f + kSearchSlack) != s.lo[a] + 1;
    }
    s.h = cubeHash(s.lo[0], s.lo[1], s.lo[2]);
    for (int k = 0; k < 8; ++k) grid.prefetch(s.h + step[k]);
    // the cube holding the vertex, one of the 8 (floor(q) is lo or lo + 1 on each axis): where the
    // vertex becomes a centre, its cell is added there, most often to a cube holding none yet, whose
    // slot the filter kept from being prefetched above
    const int kc = (floorToInt(q.x) - s.lo[0]) + 2 * (floorToInt(q.y) - s.lo[1]) + 4 * (floorToInt(q.z) - s.lo[2]);
    grid.prefetchHome(s.h + step[kc]);
  };
  for (size_t i = 0; i < std::min(n, kPrefetchDistance); ++i) plan(i, ring[i]);

  for (size_t i = 0; i < n; ++i) {
    Search& s = ring[i % kPrefetchDistance];
    const int32_t lx = s.lo[0], ly = s.lo[1], lz = s.lo[2];
    const uint64_t h0 = s.h;
    const bool wide = s.wide;
    if (i + kPrefetchDistance < n) plan(i + kPrefetchDistance, s);
    const uint32_t v = p.order[i];
    const glm::vec3 pv = sorted[i];
    uint32_t best = kNone;
    float best_d2 = std::numeric_limits<float>::infinity();
    auto test = [&](float cx, float cy, float cz, uint32_t c) { testCell(rule, pv, cx, cy, cz, c, best, best_d2); };
    auto scan = [&](const CubeSlot* slot) {
      if (!slot) return;
      const uint32_t k = std::min(slot->n, 3u);
      for (uint32_t j = 0; j < k; ++j) test(slot->cx[j], slot->cy[j], slot->cz[j], slot->id[j]);
      if (slot->n > 3)
        for (uint32_t o = grid.overflowHead(slot); o != kNone; o = grid.overflow_next[o]) {
          const glm::vec3& c = grid.overflow_centre[o];
          test(c.x, c.y, c.z, grid.overflow_id[o]);
        }
    };
    if (!wide) {
      // the filter first, so that the loop below visits only cubes that may hold cells
      uint32_t held = 0;
      for (int k = 0; k < 8; ++k) held |= uint32_t(grid.mayHold(h0 + step[k])) << k;
      while (held) {
        const int k = __builtin_ctz(held);
        held &= held - 1;
        scan(grid.findHeld(lx + (k & 1), ly + ((k >> 1) & 1), lz + (k >> 2), h0 + step[k]));
      }
    } else {
      const glm::vec3 q = pv * inv;
      int32_t hi[3];
      for (int a = 0; a < 3; ++a) hi[a] = floorToInt(q[a] + 0.5f + kSearchSlack);
      for (int32_t x = lx; x <= hi[0]; ++x)
        for (int32_t y = ly; y <= hi[1]; ++y)
          for (int32_t z = lz; z <= hi[2]; ++z) scan(grid.find(x, y, z, cubeHash(x, y, z)));
    }
    if (best == kNone) {
      best = out.cluster_count++;
      out.heaviest.push_back(v);
      const glm::vec3 q = pv * inv;
      grid.add(floorToInt(q.x), floorToInt(q.y), floorToInt(q.z), pv, best);
    }
    out.cluster_of[v] = best;
  }
}

// (test_hooks.h)
bool setFloatingAvx2ForTest(bool on) { return g_avx2_allowed.exchange(on, std::memory_order_relaxed); }
int setFloatingBlockBricksForTest(int mode) { return g_block_bricks.exchange(mode < 0 ? -1 : mode); }
int lastFloatingGridForTest() { return g_last_grid.load(std::memory_order_relaxed); }
bool setFloatingCacheForTest(bool on) { return g_cache_allowed.exchange(on, std::memory_order_relaxed); }

Error checkCellWidth(const PreparedMesh& p, float cell_width) {
  if (!std::isfinite(cell_width) || !(cell_width > 0.0f))
    return {Status::kInvalidArgument, "cell width " + std::to_string(cell_width) + " is not a finite positive number"};
  const glm::vec3 far = glm::max(glm::abs(p.bounds.min), glm::abs(p.bounds.max));
  const double extent = std::max({double(far.x), double(far.y), double(far.z)});
  if (extent / double(cell_width) > kMaxGridCoordinate)
    return {Status::kInvalidArgument, "cell width " + std::to_string(cell_width) +
                                          " is too small for coordinates up to " + std::to_string(extent) +
                                          " (more than 2^30 cells along an axis)"};
  return {};
}

}  // namespace scenelod::detail
