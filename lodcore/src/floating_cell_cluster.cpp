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
// the joining rule breaks ties by id. A listed flat grid's heads take 16 bits where every cell index
// fits (at most 65,535 referenced vertices), kept in bricks of 4 x 4 x 4 cubes, allocated where cells
// are, when a flat array of them would take more than 16 bytes per vertex; the flat grids have AVX2
// variants, chosen at run time, that gather the heads by rows and test cells 8 at a time with the
// same operations and order; where cells are rare among the vertices (coarse levels of a small
// mesh), the AVX2 grid of side w/2 keeps per grid cube the cells its vertices test (CandidateCache).
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
#if defined(__SSE2__) && (defined(__x86_64__) || defined(__i386__))
#define SCENELOD_FLOATING_AVX2 1
#include <immintrin.h>
#endif

#include "cluster_internal.h"
#include "test_hooks.h"

namespace scenelod::detail {

namespace {
// slack on the searched range so that a centre exactly on a cell's face is never missed by rounding
constexpr float kSearchSlack = 1e-4f;
// vertices ahead of the current one whose grid slots are prefetched (the search is bound by the
// latency of its random slot reads, vertices being visited in weight order). With the home slot of
// the vertex's own cube prefetched too, the 1 M sphere's 50 % level (17 MB of slots) assigned in
// 105 ms instead of 124 (minima of 32, AMD Zen 3); 8 ahead, or the slot after each home as well,
// did no better
constexpr size_t kPrefetchDistance = 4;
// assignBlocksAvx2T (the flat grid of side w of large meshes) prefetches a vertex's 4 rows of heads
// and its cluster id's slot this many vertices ahead: on AMD Zen 3 (512 KiB of L2), the 1 M
// sphere's 10 % level, whose heads (2.9 MB) and cluster ids (2 MB) are far past L2, assigned in
// 24-25 ms instead of 28-31 (8, 12, 16 and 32 ahead within 1 ms of each other; prefetching the 8
// first blocks as well, which needs the heads read, cost more than it hid: 29-31 ms)
constexpr size_t kBlocksAhead = 16;
// CandidateCache is used where the referenced vertices are at least this many per expected cell:
// on the bunny, assignment 1.10 -> 0.85 ms at 2 % (53 per cell), 1.14 -> 0.97 at 3 % (23), even at
// 5 % (14: 1.18-1.20 ms, 9 % fewer instructions), a loss at 10 % (9.4: 1.35 -> 1.72 ms, an entry
// made for every ~4 vertices)
constexpr double kCacheVerticesPerCell = 12.0;

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

// The containment test and the joining rule, shared by all grids: the order in which candidate
// cells are tested never changes the result, because ties are broken by id. The best cell so far is
// the caller's locals (kept in registers; a struct holding them was spilled in the hash loop, which
// cost a quarter of its time on the 1 M sphere).
struct JoinRule {
  float half, half2;
  bool cube, nearest;
};
inline void testCell(const JoinRule& r, const glm::vec3& pv, float cx, float cy, float cz, uint32_t c, uint32_t& best,
                     float& best_d2) {
  const float dx = pv.x - cx, dy = pv.y - cy, dz = pv.z - cz;
  const float d2 = dx * dx + dy * dy + dz * dz;
  const bool inside = r.cube ? (std::max({std::fabs(dx), std::fabs(dy), std::fabs(dz)}) <= r.half) : d2 <= r.half2;
  // cells are numbered in creation order, which is the order of their centres' weights
  const bool better = r.nearest ? (d2 < best_d2 || (d2 == best_d2 && c < best)) : c < best;
  if (inside && better) {
    best = c;
    best_d2 = d2;
  }
}

// testCell with the shape and the rule fixed at compile time (the flat grid's loop is specialised)
template <bool kCube, bool kNearest>
inline void testCellT(const JoinRule& r, const glm::vec3& pv, float cx, float cy, float cz, uint32_t c,
                      uint32_t& best, float& best_d2) {
  const float dx = pv.x - cx, dy = pv.y - cy, dz = pv.z - cz;
  const float d2 = dx * dx + dy * dy + dz * dz;
  const bool inside = kCube ? (std::max({std::fabs(dx), std::fabs(dy), std::fabs(dz)}) <= r.half) : d2 <= r.half2;
  const bool better = kNearest ? (d2 < best_d2 || (d2 == best_d2 && c < best)) : c < best;
  if (inside && better) {
    best = c;
    best_d2 = d2;
  }
}

// Bytes of list heads a dense grid may take beyond the hash's measured ~50 bytes per cell: while
// the mesh's box in grid cubes stays below this, a flat array replaces the hash. On large meshes it
// may also take up to 8 bytes per referenced vertex (twice the level's cluster_of array): the 1 M
// sphere's 10 % level then takes the flat grid of side w (3 MB, the hash 2.2 MB), 115 -> 86 ms.
constexpr double kDenseBaseBytes = 1 << 20;
constexpr double kDenseBytesPerCell = 32.0;
constexpr double kDenseBytesPerVertex = 8.0;
// assignBlocksT's blocks of 4 cell ids and their links: reserved for 0.55 per expected cell (the
// occupied cubes of side w were 0.549 and 0.45 per expected cell on the 1 M sphere's 10 % level and
// the bunny's 50 % level; more only regrows the vectors)
constexpr double kBlockBytes = 20.0;
// the bricked grid of side w (CellBlocks) is taken where its table and bricks (256 bytes each) would
// take at most this many bytes per expected cell: about what the hash's slots (64 bytes for
// 0.55 x 4/3 per expected cell) take beyond the blocks and the cells' records, so that the bricked
// grid holds no more than the hash would (the 1 M sphere's 50 % level: one brick per 17.5 cells
// and a table of 1.2 MB, 19 bytes in all)
constexpr double kBrickBytesPerCell = 21.0;
constexpr size_t kBrickBytes = 256;  // one CellBlocks<true>::Brick
// bricks are numbered in 32 bits (countVertexBricks, CellBlocks::top): a table of 4 bytes per brick
constexpr double kMaxBrickTableBytes = 4.0 * 4294967296.0;
inline size_t expectedBlocks(size_t expected_cells) { return expected_cells * 11 / 20 + 16; }

#if defined(__SSE2__)
// the successors of the cells list[0 .. count) along their grid cubes' lists, the ended ones (0)
// dropped without a branch, into `next`; their count (shared by the SSE2 and AVX2 searches)
template <typename CellRecord>
SCENELOD_ALWAYS_INLINE uint32_t listSuccessors(const CellRecord* cells, const uint32_t* list, uint32_t count,
                                               uint32_t* next) {
  uint32_t next_count = 0;
  for (uint32_t j = 0; j < count; ++j) {
    const uint32_t c = cells[list[j]].next;
    next[next_count] = c;
    next_count += c != 0;
  }
  return next_count;
}

// Tests the cells list[0 .. count) four at a time, one per lane, without a branch per cell: each
// lane computes d^2 and the containment with testCell's operations and keeps its least (d^2, id)
// in (bd2, bid) under the same order, so that laneBest then gives the cell testCell would choose,
// whatever the order of the list. `cells` are 16-byte records, centre first, the cell of cluster k
// at k + 1 and a sentinel at NaN (never inside) at 0, which pads the list to a multiple of four (the
// list needs 3 spare entries). Returns the OR of the records' fourth words (a grid's chain links).
template <bool kCube, bool kNearest, typename CellRecord>
inline __m128i testCellLanes(const CellRecord* cells, uint32_t* list, uint32_t count, __m128 px, __m128 py,
                             __m128 pz, const JoinRule& rule, __m128& bd2, __m128i& bid) {
  static_assert(sizeof(CellRecord) == 16, "a cell is read as one 16-byte lane");
  list[count] = list[count + 1] = list[count + 2] = 0;  // pad with the sentinel
  __m128i chained = _mm_setzero_si128();
  for (uint32_t j = 0; j < count; j += 4) {
    __m128 a0 = _mm_loadu_ps(&cells[list[j]].x), a1 = _mm_loadu_ps(&cells[list[j + 1]].x);
    __m128 a2 = _mm_loadu_ps(&cells[list[j + 2]].x), a3 = _mm_loadu_ps(&cells[list[j + 3]].x);
    _MM_TRANSPOSE4_PS(a0, a1, a2, a3);
    const __m128 dx = _mm_sub_ps(px, a0), dy = _mm_sub_ps(py, a1), dz = _mm_sub_ps(pz, a2);
    const __m128 d2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
    __m128 inside;
    if (kCube) {
      const __m128 absmask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
      inside = _mm_cmple_ps(
          _mm_max_ps(_mm_max_ps(_mm_and_ps(dx, absmask), _mm_and_ps(dy, absmask)), _mm_and_ps(dz, absmask)),
          _mm_set1_ps(rule.half));
    } else {
      inside = _mm_cmple_ps(d2, _mm_set1_ps(rule.half2));
    }
    const __m128i id = _mm_sub_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(list + j)), _mm_set1_epi32(1));
    const __m128 id_less = _mm_castsi128_ps(_mm_cmplt_epi32(id, bid));
    const __m128 better =
        kNearest ? _mm_or_ps(_mm_cmplt_ps(d2, bd2), _mm_and_ps(_mm_cmpeq_ps(d2, bd2), id_less)) : id_less;
    const __m128 take = _mm_and_ps(inside, better);
    bd2 = _mm_or_ps(_mm_and_ps(take, d2), _mm_andnot_ps(take, bd2));
    const __m128i takei = _mm_castps_si128(take);
    bid = _mm_or_si128(_mm_and_si128(takei, id), _mm_andnot_si128(takei, bid));
    chained = _mm_or_si128(chained, _mm_castps_si128(a3));
  }
  return chained;
}

// the least (d2, id) of the four lanes, without branches: the least d2, then the least id among the
// lanes holding it (for the heaviest rule the least id); kNone when no lane holds a cell
template <bool kNearest>
inline uint32_t laneBest(__m128 bd2, __m128i bid) {
  __m128i sel = bid;
  if (kNearest) {
    __m128 m = _mm_min_ps(bd2, _mm_shuffle_ps(bd2, bd2, _MM_SHUFFLE(2, 3, 0, 1)));
    m = _mm_min_ps(m, _mm_shuffle_ps(m, m, _MM_SHUFFLE(1, 0, 3, 2)));
    const __m128i at_min = _mm_castps_si128(_mm_cmpeq_ps(bd2, m));
    sel = _mm_or_si128(_mm_and_si128(at_min, bid), _mm_andnot_si128(at_min, _mm_set1_epi32(0x7fffffff)));
  }
  __m128i t = _mm_shuffle_epi32(sel, _MM_SHUFFLE(2, 3, 0, 1));
  __m128i lt = _mm_cmplt_epi32(t, sel);
  sel = _mm_or_si128(_mm_and_si128(lt, t), _mm_andnot_si128(lt, sel));
  t = _mm_shuffle_epi32(sel, _MM_SHUFFLE(1, 0, 3, 2));
  lt = _mm_cmplt_epi32(t, sel);
  sel = _mm_or_si128(_mm_and_si128(lt, t), _mm_andnot_si128(lt, sel));
  const int32_t id0 = _mm_cvtsi128_si32(sel);
  return id0 == 0x7fffffff ? kNone : uint32_t(id0);
}
#endif

// The AVX2 variant of the flat grid of side w/2 (chosen at run time, where the CPU has it): the 27
// heads gathered as 9 rows of 4 loads with one compaction per pair of rows, and the cells tested 8 at
// a time. The lanes use testCellLanes' operations (no FMA: "avx2" alone never contracts a * b + c)
// and keep the same order on (d^2, id), so the cell chosen, and every bit after it, is the same.
#if defined(SCENELOD_FLOATING_AVX2)
#define SCENELOD_FLOATING_AVX2_TARGET __attribute__((target("avx2,popcnt")))
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

#if defined(SCENELOD_FLOATING_AVX2)
// The packing of the non-empty heads among 8 lanes (two rows: lanes 0-2 and 4-6 of a pair of
// 4-head loads) takes kLaneCompaction's row of their mask.

// the non-zero heads of rows r0 and r1 (three each) appended to found[count ..); writes 8 entries
SCENELOD_FLOATING_AVX2_TARGET inline uint32_t packRows(const uint32_t* r0, const uint32_t* r1, uint32_t valid,
                                                       uint32_t* found, uint32_t count) {
  const __m256i v = _mm256_inserti128_si256(_mm256_castsi128_si256(_mm_loadu_si128(reinterpret_cast<const __m128i*>(r0))),
                                            _mm_loadu_si128(reinterpret_cast<const __m128i*>(r1)), 1);
  const uint32_t zero = uint32_t(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(v, _mm256_setzero_si256()))));
  const uint32_t m = ~zero & valid;
  const __m256i perm = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(&kLaneCompaction.lanes[m])));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(found + count), _mm256_permutevar8x32_epi32(v, perm));
  return count + uint32_t(_mm_popcnt_u32(m));
}

// the non-empty heads of the 3 x 3 x 3 cubes from base (rows at base + row_offset[0 .. 9)) into
// found; their count. Each load takes a fourth head (inside the grid: a row spans dims[0] >= 7 cubes
// and lo + 3 is at most dims[0] - 1), masked off; the rows go in pairs, the last alone.
SCENELOD_FLOATING_AVX2_TARGET SCENELOD_ALWAYS_INLINE uint32_t gatherRows27(const uint32_t* base, const size_t row_offset[9], uint32_t* found) {
  const size_t* r = row_offset;
  uint32_t count = packRows(base + r[0], base + r[1], 0x77u, found, 0);
  count = packRows(base + r[2], base + r[3], 0x77u, found, count);
  count = packRows(base + r[4], base + r[5], 0x77u, found, count);
  count = packRows(base + r[6], base + r[7], 0x77u, found, count);
  return packRows(base + r[8], base + r[8], 0x07u, found, count);
}

// floorToInt per lane
SCENELOD_FLOATING_AVX2_TARGET inline __m128i floorToInt4(__m128 x) {
  const __m128i t = _mm_cvttps_epi32(x);
  return _mm_add_epi32(t, _mm_castps_si128(_mm_cmplt_ps(x, _mm_cvtepi32_ps(t))));
}

// a vertex's position in grid units and its searched range of cubes (lo, hi), x, y, z in lanes 0-2
struct Located {
  __m128 q4;
  __m128i lo4, hi4;
};

// cells a and b as the two halves of a vector
template <typename CellRecord>
SCENELOD_FLOATING_AVX2_TARGET inline __m256 load2Cells(const CellRecord* cells, uint32_t a, uint32_t b) {
  return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(&cells[a].x)), _mm_loadu_ps(&cells[b].x), 1);
}

// testCellLanes, 8 lanes: lane k holds list[j + k] (records k and k + 4 share a 128-bit half, so the
// in-half transpose leaves the lanes in list order). Needs 8 spare entries after the list.
template <bool kCube, bool kNearest, typename CellRecord>
SCENELOD_FLOATING_AVX2_TARGET inline __m256i testCellLanes8(const CellRecord* cells, uint32_t* list, uint32_t count, __m256 px,
                                                   __m256 py, __m256 pz, const JoinRule& rule, __m256& bd2,
                                                   __m256i& bid) {
  static_assert(sizeof(CellRecord) == 16, "a cell is read as one 16-byte lane");
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(list + count), _mm256_setzero_si256());  // pad with the sentinel
  __m256i chained = _mm256_setzero_si256();
  for (uint32_t j = 0; j < count; j += 8) {
    const __m256 a0 = load2Cells(cells, list[j], list[j + 4]), a1 = load2Cells(cells, list[j + 1], list[j + 5]);
    const __m256 a2 = load2Cells(cells, list[j + 2], list[j + 6]), a3 = load2Cells(cells, list[j + 3], list[j + 7]);
    const __m256 t0 = _mm256_unpacklo_ps(a0, a1), t1 = _mm256_unpacklo_ps(a2, a3);
    const __m256 t2 = _mm256_unpackhi_ps(a0, a1), t3 = _mm256_unpackhi_ps(a2, a3);
    const __m256 cx = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0));
    const __m256 cy = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2));
    const __m256 cz = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0));
    const __m256 cw = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(3, 2, 3, 2));
    const __m256 dx = _mm256_sub_ps(px, cx), dy = _mm256_sub_ps(py, cy), dz = _mm256_sub_ps(pz, cz);
    const __m256 d2 =
        _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
    __m256 inside;
    if (kCube) {
      const __m256 absmask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
      inside = _mm256_cmp_ps(_mm256_max_ps(_mm256_max_ps(_mm256_and_ps(dx, absmask), _mm256_and_ps(dy, absmask)),
                                           _mm256_and_ps(dz, absmask)),
                             _mm256_set1_ps(rule.half), _CMP_LE_OQ);
    } else {
      inside = _mm256_cmp_ps(d2, _mm256_set1_ps(rule.half2), _CMP_LE_OQ);
    }
    const __m256i id =
        _mm256_sub_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(list + j)), _mm256_set1_epi32(1));
    const __m256 id_less = _mm256_castsi256_ps(_mm256_cmpgt_epi32(bid, id));
    const __m256 better =
        kNearest ? _mm256_or_ps(_mm256_cmp_ps(d2, bd2, _CMP_LT_OQ),
                                _mm256_and_ps(_mm256_cmp_ps(d2, bd2, _CMP_EQ_OQ), id_less))
                 : id_less;
    const __m256 take = _mm256_and_ps(inside, better);
    bd2 = _mm256_blendv_ps(bd2, d2, take);
    bid = _mm256_castps_si256(_mm256_blendv_ps(_mm256_castsi256_ps(bid), _mm256_castsi256_ps(id), take));
    chained = _mm256_or_si256(chained, _mm256_castps_si256(cw));
  }
  return chained;
}

// laneBest over 8 lanes: the least d2, then the least id among the lanes holding it
template <bool kNearest>
SCENELOD_FLOATING_AVX2_TARGET inline uint32_t laneBest8(__m256 bd2, __m256i bid) {
  __m256i sel = bid;
  if (kNearest) {
    __m256 m = _mm256_min_ps(bd2, _mm256_permute2f128_ps(bd2, bd2, 1));
    m = _mm256_min_ps(m, _mm256_shuffle_ps(m, m, _MM_SHUFFLE(1, 0, 3, 2)));
    m = _mm256_min_ps(m, _mm256_shuffle_ps(m, m, _MM_SHUFFLE(2, 3, 0, 1)));
    sel = _mm256_castps_si256(_mm256_blendv_ps(_mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff)),
                                               _mm256_castsi256_ps(bid), _mm256_cmp_ps(bd2, m, _CMP_EQ_OQ)));
  }
  __m128i s = _mm_min_epi32(_mm256_castsi256_si128(sel), _mm256_extracti128_si256(sel, 1));
  s = _mm_min_epi32(s, _mm_shuffle_epi32(s, _MM_SHUFFLE(1, 0, 3, 2)));
  s = _mm_min_epi32(s, _mm_shuffle_epi32(s, _MM_SHUFFLE(2, 3, 0, 1)));
  const int32_t id0 = _mm_cvtsi128_si32(s);
  return id0 == 0x7fffffff ? kNone : uint32_t(id0);
}

// The AVX2 flat-grid loops' shared steps (inlined into each). The non-empty heads of the cubes
// lo..hi along each axis, any span (the uncommon case: a vertex within the slack of a cube face),
// appended to `found` without a branch per head.
SCENELOD_FLOATING_AVX2_TARGET SCENELOD_ALWAYS_INLINE uint32_t gatherHeadsAnySpan(const uint32_t* head, size_t sy, size_t sz,
                                                                                 const int32_t lo[3], const int32_t hi[3],
                                                                                 uint32_t* found, uint32_t found_count) {
  for (int32_t z = lo[2]; z <= hi[2]; ++z)
    for (int32_t y = lo[1]; y <= hi[1]; ++y) {
      const uint32_t* row = head + size_t(z) * sz + size_t(y) * sy;
      for (int32_t x = lo[0]; x <= hi[0]; ++x) {
        found[found_count] = row[x];
        found_count += row[x] != 0;
      }
    }
  return found_count;
}

// The cell a vertex at pv joins among the listed cells `found` (padded as testCellLanes8 reads it;
// 64 + 8 entries) and their successors along the lists, one round of 8 lanes per step, or kNone.
template <bool kCube, bool kNearest, typename CellRecord>
SCENELOD_FLOATING_AVX2_TARGET SCENELOD_ALWAYS_INLINE uint32_t bestListedCell8(const CellRecord* cells, uint32_t* found,
                                                                              uint32_t found_count, const glm::vec3& pv,
                                                                              const JoinRule& rule) {
  const __m256 px = _mm256_set1_ps(pv.x), py = _mm256_set1_ps(pv.y), pz = _mm256_set1_ps(pv.z);
  __m256 bd2 = _mm256_set1_ps(std::numeric_limits<float>::infinity());
  __m256i bid = _mm256_set1_epi32(0x7fffffff);
  uint32_t* list = found;
  uint32_t list_count = found_count;
  uint32_t successors[64 + 8];
  for (;;) {
    const __m256i chained = testCellLanes8<kCube, kNearest>(cells, list, list_count, px, py, pz, rule, bd2, bid);
    if (_mm256_testz_si256(chained, chained)) break;
    uint32_t* next_list = list == found ? successors : found;
    list_count = listSuccessors(cells, list, list_count, next_list);
    list = next_list;
  }
  return laneBest8<kNearest>(bd2, bid);
}

#endif

#if defined(SCENELOD_FLOATING_AVX2)
// testCellLanes8 and laneBest8 on 8 cells whose indices c ascend along the lanes (0, the sentinel,
// in free lanes), given with their centres (cx, cy, cz: NaN in free lanes): the same cell, found with
// one reduction of d^2 and the first lane holding it, the least id on a tie (for the heaviest rule
// the first inside lane); kNone if none
// the centres of the 8 cells c[0 .. 8) into cx, cy, cz (lane k: c[k]; records k and k + 4 share a
// 128-bit half, so the in-half transpose leaves the lanes in order)
template <typename CellRecord>
SCENELOD_FLOATING_AVX2_TARGET SCENELOD_ALWAYS_INLINE void loadCentres8(const CellRecord* cells, const uint16_t* c, __m256& cx,
                                                                       __m256& cy, __m256& cz) {
  const __m256 a0 = load2Cells(cells, c[0], c[4]), a1 = load2Cells(cells, c[1], c[5]);
  const __m256 a2 = load2Cells(cells, c[2], c[6]), a3 = load2Cells(cells, c[3], c[7]);
  const __m256 t0 = _mm256_unpacklo_ps(a0, a1), t1 = _mm256_unpacklo_ps(a2, a3);
  const __m256 t2 = _mm256_unpackhi_ps(a0, a1), t3 = _mm256_unpackhi_ps(a2, a3);
  cx = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0));
  cy = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2));
  cz = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0));
}

template <bool kCube, bool kNearest>
SCENELOD_FLOATING_AVX2_TARGET SCENELOD_ALWAYS_INLINE uint32_t testEntry8(const uint16_t* c, __m256 cx, __m256 cy, __m256 cz,
                                                                         __m256 px, __m256 py, __m256 pz,
                                                                         const JoinRule& rule) {
  const __m256 dx = _mm256_sub_ps(px, cx), dy = _mm256_sub_ps(py, cy), dz = _mm256_sub_ps(pz, cz);
  const __m256 d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
  __m256 inside;
  if (kCube) {
    const __m256 absmask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
    inside = _mm256_cmp_ps(_mm256_max_ps(_mm256_max_ps(_mm256_and_ps(dx, absmask), _mm256_and_ps(dy, absmask)),
                                         _mm256_and_ps(dz, absmask)),
                           _mm256_set1_ps(rule.half), _CMP_LE_OQ);
  } else {
    inside = _mm256_cmp_ps(d2, _mm256_set1_ps(rule.half2), _CMP_LE_OQ);
  }
  uint32_t lanes = uint32_t(_mm256_movemask_ps(inside));
  if (kNearest) {
    // an inside cell's d^2 is finite (at most 3 (w/2)^2), so +inf elsewhere never ties with it
    const __m256 v = _mm256_blendv_ps(_mm256_set1_ps(std::numeric_limits<float>::infinity()), d2, inside);
    __m256 m = _mm256_min_ps(v, _mm256_permute2f128_ps(v, v, 1));
    m = _mm256_min_ps(m, _mm256_shuffle_ps(m, m, _MM_SHUFFLE(1, 0, 3, 2)));
    m = _mm256_min_ps(m, _mm256_shuffle_ps(m, m, _MM_SHUFFLE(2, 3, 0, 1)));
    lanes &= uint32_t(_mm256_movemask_ps(_mm256_cmp_ps(v, m, _CMP_EQ_OQ)));
  }
  return lanes == 0 ? kNone : uint32_t(c[__builtin_ctz(lanes)]) - 1;
}
#endif

// §4's grid as a flat array of list heads over the mesh's box in grid cubes (still anchored at the
// origin, so the cells do not depend on the box): finding a cube is one load at a computed index,
// with no hashing, probing or key test. Shared by assignDenseT and its AVX2 variants: the cells,
// chained through `next` newest first per grid cube, and the heads.
// cells[k + 1] is cluster k's cell; cells[0] is a sentinel at NaN, which contains no vertex: empty
// heads (0) point to it, so that the cells found can be tested four (or eight) at a time, padded
// with it.
struct DenseGrid {
  struct Cell {
    float x, y, z;
    uint32_t next;  // index of the next cell listed in the same grid cube; 0 ends the list
  };
  DenseGrid(const size_t dims[3], size_t expected) : sy(dims[0]), sz(dims[0] * dims[1]), head(sz * dims[2], 0) {
    cells.reserve(expected + 1);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    cells.push_back({nan, nan, nan, 0});
  }
  // a new cell (cluster `id`) at pv, listed first in grid cube (cx, cy, cz) (inlined into each variant)
  SCENELOD_ALWAYS_INLINE void list(int32_t cx, int32_t cy, int32_t cz, const glm::vec3& pv, uint32_t id) {
    const size_t k = size_t(cz) * sz + size_t(cy) * sy + size_t(cx);
    cells.push_back({pv.x, pv.y, pv.z, head[k]});
    head[k] = id + 1;
  }

  const size_t sy, sz;  // strides of y and z in the flat array
  std::vector<Cell> cells;
  std::vector<uint32_t> head;
};

#if defined(SCENELOD_FLOATING_AVX2)
// The cells that the vertices of one grid cube of side w/2 test, cached per cube: those listed in
// the 3 x 3 x 3 cubes around it, up to 8, as their indices into the cells (16 bits, ascending, 0 for
// a free place: the sentinel), so that a vertex reads one entry instead of gathering 27 heads and
// walking their lists. An entry is made at its cube's first vertex and kept current by adding each
// new cell to the built entries of the 27 cubes it is near; a cube near more than 8 cells is marked
// (kOverflow) and takes the general path, as does one near a cell whose index needs more than 16
// bits (32-bit heads). Worth it where cells are rare among the vertices (at the bunny's 2 % level
// 700 cells among 35 k vertices: 1,721 entries made, each then read ~20 times; the 1 M sphere's 1 %
// level 5 k cells among 519 k vertices).
// Small, for the chain's memory peak (reached in its width search's coarse probes): entries of
// 16 bytes, and the cubes' entry numbers in bricks of 4 x 4 x 4 cubes allocated where a cube has
// an entry: about 55 KB at the 2 % level. (Entries that kept their cells' centres, and the entry
// numbers in one flat array, were no faster here: tried and not kept.)
class CandidateCache {
 public:
  static constexpr uint16_t kOverflow = 0xffff;
  struct Entry {
    uint16_t cell[8];  // the cells' indices (cluster + 1), ascending, 0 (the sentinel) in free places
  };
  // `reserve_entries`: about the cubes the vertices fall in (0: no cache, nothing allocated)
  CandidateCache(const size_t dims[3], size_t reserve_entries) : bx_((dims[0] + 3) / 4), by_((dims[1] + 3) / 4) {
    if (reserve_entries == 0) return;
    top_.assign(bx_ * by_ * ((dims[2] + 3) / 4), 0);
    slots_.reserve((reserve_entries / 16 + 16) * 64);  // 15.6 to 16 entries per brick used (bunny 2-5 %)
    slots_.assign(64, 0);  // brick 0: no entries
    entries_.reserve(reserve_entries + 1);
    entries_.push_back(Entry{});
  }
  const Entry& entry(uint16_t e) const { return entries_[e]; }
  const Entry* entries() const { return entries_.data(); }  // moves when make adds an entry
  // for the caller's SIMD loop: the strides of the bricks' y and z, the bricks (which never move) and
  // the slots (which move when make allocates a brick)
  size_t brickStrideY() const { return bx_; }
  size_t brickStrideZ() const { return bx_ * by_; }
  const uint32_t* bricks() const { return top_.data(); }
  const uint16_t* slots() const { return slots_.data(); }
  // a new entry for cube (x, y, z) holding the cells list[0 .. count), ascending: its number, or
  // kOverflow (the cube marked so) where they are more than 8 or the entry numbers are used up
  uint16_t make(int32_t x, int32_t y, int32_t z, const uint32_t* list, uint32_t count) {
    uint16_t& slot = slotFor(x, y, z);
    if (count > 8 || entries_.size() >= kOverflow || (count > 0 && list[count - 1] > 0xffff)) {
      slot = kOverflow;
      return kOverflow;
    }
    const uint16_t number = uint16_t(entries_.size());
    slot = number;
    Entry e{};
    for (uint32_t k = 0; k < count; ++k) e.cell[k] = uint16_t(list[k]);
    entries_.push_back(e);
    return number;
  }
  // cell index c (the newest: entries stay ascending) in cube (cx, cy, cz), into the built entries of
  // the 27 cubes whose 3 x 3 x 3 hold that cube
  void add(int32_t cx, int32_t cy, int32_t cz, uint32_t c) {
    // the brick and in-brick parts of the three coordinates on each axis once
    size_t xb[3], xi[3], yb[3], yi[3], zb[3], zi[3];
    for (int k = 0; k < 3; ++k) {
      xb[k] = size_t((cx - 2 + k) >> 2), xi[k] = size_t((cx - 2 + k) & 3);
      yb[k] = size_t((cy - 2 + k) >> 2) * bx_, yi[k] = size_t((cy - 2 + k) & 3) << 2;
      zb[k] = size_t((cz - 2 + k) >> 2) * bx_ * by_, zi[k] = size_t((cz - 2 + k) & 3) << 4;
    }
    // the slots holding a built entry first, without a branch per slot (which of the 27 do is
    // random: the test per slot mispredicted about twice per new cell, 8.5 k times at the bunny's
    // chain level 3, with 1,681 cells), then those entries
    uint16_t* built[27];
    uint32_t built_count = 0;
    for (int z = 0; z < 3; ++z)
      for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 3; ++x) {
          // brick 0's slots are all 0 (none built): one test for no brick, no entry or overflow
          uint16_t* slot = &slots_[size_t(top_[zb[z] + yb[y] + xb[x]]) << 6 | zi[z] | yi[y] | xi[x]];
          built[built_count] = slot;
          built_count += uint16_t(*slot - 1) < kOverflow - 1;
        }
    for (uint32_t b = 0; b < built_count; ++b) {
      uint16_t& slot = *built[b];
      Entry& e = entries_[slot];
      // the free places (a full entry has none), without a loop whose exit would mispredict
      const uint32_t free_places = uint32_t(_mm_movemask_epi8(_mm_cmpeq_epi16(
                                       _mm_loadu_si128(reinterpret_cast<const __m128i*>(e.cell)), _mm_setzero_si128()))) &
                                   0x5555u;
      if (free_places == 0 || c > 0xffff) {  // full, or a cell index past 16 bits (32-bit heads)
        slot = kOverflow;
        continue;
      }
      const int k = __builtin_ctz(free_places) >> 1;
      e.cell[k] = uint16_t(c);
    }
  }

 private:
  size_t brick(int32_t x, int32_t y, int32_t z) const {
    return (size_t(z >> 2) * by_ + size_t(y >> 2)) * bx_ + size_t(x >> 2);
  }
  static size_t inBrick(int32_t x, int32_t y, int32_t z) { return size_t((z & 3) << 4 | (y & 3) << 2 | (x & 3)); }
  uint16_t& slotFor(int32_t x, int32_t y, int32_t z) {
    uint32_t& b = top_[brick(x, y, z)];
    if (b == 0) {
      b = uint32_t(slots_.size() >> 6);
      slots_.resize(slots_.size() + 64, 0);
    }
    return slots_[size_t(b) << 6 | inBrick(x, y, z)];
  }
  size_t bx_, by_;                 // bricks along x and y
  std::vector<uint32_t> top_;      // per brick position: its brick, 0 for the shared empty one
  std::vector<uint16_t> slots_;    // 64 per brick: the cubes' entry numbers
  std::vector<Entry> entries_;     // entries_[0] unused
};
#endif

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
  std::vector<glm::vec3> local;  // (the sorted copy, where a chain dropped it)
  const glm::vec3* sorted = sortedPositions(p, local);
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

#if defined(SCENELOD_FLOATING_AVX2)
// assignDenseT on AVX2 (see there): the same grid, cells and order of creation; the gather of the
// 3 x 3 x 3 heads packs pairs of rows (packRows) instead of 27 scalar steps, and the cells found
// are tested 8 at a time
template <bool kCube, bool kNearest>
SCENELOD_FLOATING_AVX2_TARGET void assignDenseAvx2T(const PreparedMesh& p, float cube_width, float reach,
                                                    const int32_t lo_cube[3], const size_t dims[3], JoinRule rule,
                                                    size_t expected, Assignment& out) {
  DenseGrid grid(dims, expected);  // as in assignDenseT
  auto& cells = grid.cells;
  auto& head = grid.head;
  const size_t sy = grid.sy, sz = grid.sz;
  const float inv = 1.0f / cube_width;
  const float slack = kSearchSlack * 2.0f * reach;
  const __m128 inv4 = _mm_set1_ps(inv), reach4 = _mm_set1_ps(reach), slack4 = _mm_set1_ps(slack);
  const __m128i lo_cube4 = _mm_setr_epi32(lo_cube[0], lo_cube[1], lo_cube[2], 0);
  // offsets of the 9 rows of 3 x 3 x 3 cubes from the first
  size_t row_offset[9];
  for (int z = 0; z < 3; ++z)
    for (int y = 0; y < 3; ++y) row_offset[3 * z + y] = size_t(z) * sz + size_t(y) * sy;
  const size_t n = p.order.size();
  std::vector<glm::vec3> local;  // (the sorted copy, where a chain dropped it)
  const glm::vec3* sorted = sortedPositions(p, local);
  // the range of cubes along the three axes at once, with the scalar path's operations per lane
  // ((q - reach) - slack and floorToInt's truncation and correction)
  auto locate = [&](const glm::vec3& pv) SCENELOD_FLOATING_AVX2_TARGET {
    Located l;
    l.q4 = _mm_mul_ps(_mm_setr_ps(pv.x, pv.y, pv.z, 0.0f), inv4);
    l.lo4 = _mm_sub_epi32(floorToInt4(_mm_sub_ps(_mm_sub_ps(l.q4, reach4), slack4)), lo_cube4);
    l.hi4 = _mm_sub_epi32(floorToInt4(_mm_add_ps(_mm_add_ps(l.q4, reach4), slack4)), lo_cube4);
    return l;
  };
  // the next vertex's range and the offset of its first cube in the flat array, a vertex ahead
  Located ahead{};
  size_t ahead_offset = 0;
  glm::vec3 ahead_pv{0.0f};
  auto plan = [&](size_t k) SCENELOD_FLOATING_AVX2_TARGET {
    ahead_pv = sorted[k];
    ahead = locate(ahead_pv);
    // lo >= 0: lo_cube is 3 cubes below the box
    ahead_offset = size_t(uint32_t(_mm_extract_epi32(ahead.lo4, 2))) * sz +
                   size_t(uint32_t(_mm_extract_epi32(ahead.lo4, 1))) * sy + size_t(uint32_t(_mm_cvtsi128_si32(ahead.lo4)));
  };
  // the order and cluster_of as plain pointers (through the vectors, each vertex reloaded their data
  // pointers: heaviest's push_back may, for the compiler, change them)
  const uint32_t* const order = p.order.data();
  uint32_t* const cluster_of = out.cluster_of.data();
  if (n > 0) plan(0);
  for (size_t i = 0; i < n; ++i) {
    const glm::vec3 pv = ahead_pv;
    const Located here = ahead;
    const size_t offset = ahead_offset;
    if (i + 1 < n) plan(i + 1);
    const __m128 q4 = here.q4;
    const __m128i lo4 = here.lo4, hi4 = here.hi4;
    const __m128i span = _mm_sub_epi32(hi4, lo4);
    uint32_t found[64 + 8];  // 8 spare: packRows and testCellLanes8 write 8 entries
    uint32_t found_count = 0;
    const int32_t lo[3] = {_mm_cvtsi128_si32(lo4), _mm_extract_epi32(lo4, 1), _mm_extract_epi32(lo4, 2)};
    if ((_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(span, _mm_set1_epi32(2)))) & 7) == 7) {
      // 9 rows of 3 heads; each load takes a fourth head (inside the grid: a row spans dims[0] >= 7
      // cubes and lo + 3 is at most dims[0] - 1), masked off. The rows go in pairs, the last alone.
      const uint32_t* base = head.data() + offset;
      const size_t* r = row_offset;
      found_count = packRows(base + r[0], base + r[1], 0x77u, found, found_count);
      found_count = packRows(base + r[2], base + r[3], 0x77u, found, found_count);
      found_count = packRows(base + r[4], base + r[5], 0x77u, found, found_count);
      found_count = packRows(base + r[6], base + r[7], 0x77u, found, found_count);
      found_count = packRows(base + r[8], base + r[8], 0x07u, found, found_count);
    } else if ((_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(span, _mm_set1_epi32(1)))) & 7) == 7) {
      // 2 x 2 x 2 cubes (the grid of side w): 4 rows of 2 heads, in two pairs
      const uint32_t* base = head.data() + offset;
      const size_t* r = row_offset;
      found_count = packRows(base + r[0], base + r[1], 0x33u, found, found_count);
      found_count = packRows(base + r[3], base + r[4], 0x33u, found, found_count);
    } else {
      const int32_t hi[3] = {_mm_cvtsi128_si32(hi4), _mm_extract_epi32(hi4, 1), _mm_extract_epi32(hi4, 2)};
      found_count = gatherHeadsAnySpan(head.data(), sy, sz, lo, hi, found, found_count);
    }
    uint32_t best = bestListedCell8<kCube, kNearest>(cells.data(), found, found_count, pv, rule);
    if (best == kNone) {
      best = out.cluster_count++;
      out.heaviest.push_back(order[i]);
      const __m128i c4 = _mm_sub_epi32(floorToInt4(q4), lo_cube4);
      const int32_t cx = _mm_cvtsi128_si32(c4), cy = _mm_extract_epi32(c4, 1), cz = _mm_extract_epi32(c4, 2);
      grid.list(cx, cy, cz, pv, best);
    }
    cluster_of[order[i]] = best;
  }
}

#endif

// setFloatingCacheRunsForTest's choice: -1 the default (runs where the bricks' strides allow them),
// 0 no runs, 1 runs
std::atomic<int> g_cache_runs{-1};

#if defined(SCENELOD_FLOATING_AVX2)
// An entry's cells where at most 8 heads were found and each lists one cell (cube cells: a cube of
// side w/2 lists at most one): found[0 .. count) sorted into listed[0 .. count), each placed at its
// rank (the number of smaller ones), without a branch per cell; false (nothing sorted) where a list
// is longer. found must have 8 places; listed, 9. The walk along the lists with an insertion sort
// mispredicted about 2.3 times per entry made (9.6 k at the bunny's chain level 3, 4,265 entries).
template <typename CellRecord>
SCENELOD_FLOATING_AVX2_TARGET SCENELOD_ALWAYS_INLINE bool sortLoneHeads8(const CellRecord* cells, uint32_t* found,
                                                                         uint32_t count, uint32_t* listed) {
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256i used = _mm256_cmpgt_epi32(_mm256_set1_epi32(int32_t(count)), lane);
  // the free lanes at 0 (the sentinel, whose next is 0)
  const __m256i v = _mm256_and_si256(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(found)), used);
  alignas(32) uint32_t c[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(c), v);
  uint32_t chained = 0;
  for (int k = 0; k < 8; ++k) chained |= cells[c[k]].next;
  if (chained != 0) return false;
  // the indices (below 2^31) ranked with the free lanes past them all
  const __m256i key = _mm256_blendv_epi8(_mm256_set1_epi32(0x7fffffff), v, used);
  alignas(32) int32_t keys[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(keys), key);
  for (int k = 0; k < 8; ++k) {
    const uint32_t rank = uint32_t(
        _mm_popcnt_u32(uint32_t(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(keys[k]), key))))));
    listed[rank] = c[k];  // a free lane writes listed[count], past the cells
  }
  return true;
}

// What cachedRun reads: plain pointers and constants, copied into registers. The cache's pointers
// are taken at each call (make moves them, and make is never called inside a run).
template <typename CellRecord>
struct CachedRunInputs {
  const CellRecord* cells;
  const CandidateCache::Entry* entries;
  const uint32_t* cache_bricks;
  const uint16_t* slots;
  const glm::vec3* positions;  // sorted
  const uint32_t* order;
  uint32_t* cluster_of;
  __m128 inv4, reach4, slack4;
  __m128i lo_cube4, brick_stride4;
  JoinRule rule;
};

// assignDenseCachedAvx2T's common vertex, in a loop of its own that calls nothing, so that its state
// stays in registers (inside the whole loop, with the rare paths' calls and the cache's vectors, the
// compiler kept the counter, the pointers and the position on the stack: ~199 instructions a vertex
// at the bunny's chain level 4, of which ~40 loads and stores of these): a vertex whose 3 x 3 x 3
// cubes have an entry and which is inside one of its cells. From vertex i on, it joins such vertices
// and returns the first one that is not (it or one of the last two: the caller takes that one).
// Each vertex's entry is found two vertices ahead: the loop is bound by the latency from a position
// to its cell (~100 cycles: the range, the brick, the slot, the centres, d^2, the reduction) over
// the reorder window, not by its ~100 instructions; one vertex ahead, levels 4, 6 and 8 took
// 0.51, 0.39 and 0.34 ms instead of 0.42-0.47, 0.32-0.34 and 0.28-0.29 (three ahead: no better).
template <bool kCube, bool kNearest, typename CellRecord>
SCENELOD_FLOATING_AVX2_TARGET __attribute__((noinline)) size_t cachedRun(const CachedRunInputs<CellRecord>& in, size_t i,
                                                                          size_t n) {
  const CellRecord* const cells = in.cells;
  const CandidateCache::Entry* const entries = in.entries;
  const uint32_t* const cache_bricks = in.cache_bricks;
  const uint16_t* const slots = in.slots;
  const glm::vec3* const positions = in.positions;
  const uint32_t* const order = in.order;
  uint32_t* const cluster_of = in.cluster_of;
  const __m128 inv4 = in.inv4, reach4 = in.reach4, slack4 = in.slack4;
  const __m128i lo_cube4 = in.lo_cube4, brick_stride4 = in.brick_stride4;
  const JoinRule rule = in.rule;
  // vertex k's position, its vertex index and its entry (0 where it has none or its cubes are not
  // 3 x 3 x 3)
  struct Planned {
    const float* pv;
    uint32_t v;
    uint32_t e;
  };
  auto plan = [&](size_t k) SCENELOD_FLOATING_AVX2_TARGET {
    Planned pl;
    pl.v = order[k];
    pl.pv = &positions[k].x;
    // x, y from one 8-byte load (movq, unaligned-safe: _mm_load_sd would dereference a double* at a
    // float's alignment), z inserted (a 16-byte load could read past the positions)
    const __m128 pk = _mm_insert_ps(_mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(pl.pv))),
                                    _mm_load_ss(pl.pv + 2), 0x20);
    // the caller's operations per lane ((q - reach) - slack and floorToInt's truncation and correction)
    const __m128 q4 = _mm_mul_ps(pk, inv4);
    const __m128i lo4 = _mm_sub_epi32(floorToInt4(_mm_sub_ps(_mm_sub_ps(q4, reach4), slack4)), lo_cube4);
    const __m128i hi4 = _mm_sub_epi32(floorToInt4(_mm_add_ps(_mm_add_ps(q4, reach4), slack4)), lo_cube4);
    const bool span2 =
        (_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(_mm_sub_epi32(hi4, lo4), _mm_set1_epi32(2)))) & 7) == 7;
    // the brick (lanes' sum) and in-brick place (lanes' or, the same as their sum: disjoint bits) of
    // cube lo, both summed by two horizontal additions; lane 3 is 0 in both (a stride of 0, a shift of 32)
    // the products by 16-bit halves (vpmaddwd, 5 cycles of latency on the way to the entry, against
    // vpmulld's 10): the bricks' coordinates and strides fit 15 bits (assignDenseCachedAvx2T)
    // lo is inside the grid even where the span is not 2 (lo_cube is 3 cubes below the box)
    const __m128i bm = _mm_madd_epi16(_mm_srai_epi32(lo4, 2), brick_stride4);
    const __m128i im = _mm_sllv_epi32(_mm_and_si128(lo4, _mm_set1_epi32(3)), _mm_setr_epi32(0, 2, 4, 32));
    const __m128i sums = _mm_hadd_epi32(_mm_hadd_epi32(bm, im), _mm_setzero_si128());
    const uint32_t e =
        slots[size_t(cache_bricks[uint32_t(_mm_cvtsi128_si32(sums))]) << 6 | uint32_t(_mm_extract_epi32(sums, 1))];
    pl.e = span2 ? e : 0;
    return pl;
  };
  if (i + 2 >= n) return i;
  Planned here = plan(i), next = plan(i + 1);
  for (; i + 2 < n; ++i) {
    const Planned after = plan(i + 2);
    // 0 (no entry) and kOverflow: the caller's paths
    if (uint16_t(here.e - 1) >= CandidateCache::kOverflow - 1) break;
    __m256 cx, cy, cz;
    loadCentres8(cells, entries[here.e].cell, cx, cy, cz);
    const uint32_t best =
        testEntry8<kCube, kNearest>(entries[here.e].cell, cx, cy, cz, _mm256_broadcast_ss(here.pv),
                                    _mm256_broadcast_ss(here.pv + 1), _mm256_broadcast_ss(here.pv + 2), rule);
    if (best == kNone) break;
    cluster_of[here.v] = best;
    here = next;
    next = after;
  }
  return i;
}

// assignDenseAvx2T with a CandidateCache (see there): the vertices whose 3 x 3 x 3 cubes' cells are
// in an entry test those; the others (wide ranges, overflowing entries) take assignDenseAvx2T's path.
// kRuns: the common vertices go through cachedRun (see there)
template <bool kCube, bool kNearest, bool kRuns>
SCENELOD_FLOATING_AVX2_TARGET void assignDenseCachedAvx2Impl(const PreparedMesh& p, float cube_width, float reach,
                                                             const int32_t lo_cube[3], const size_t dims[3], JoinRule rule,
                                                             size_t expected, Assignment& out) {
  const size_t n = p.order.size();
  DenseGrid grid(dims, expected);  // as in assignDenseT
  auto& cells = grid.cells;
  auto& head = grid.head;
  const size_t sy = grid.sy, sz = grid.sz;
  const float inv = 1.0f / cube_width;
  const float slack = kSearchSlack * 2.0f * reach;
  const __m128 inv4 = _mm_set1_ps(inv), reach4 = _mm_set1_ps(reach), slack4 = _mm_set1_ps(slack);
  const __m128i lo_cube4 = _mm_setr_epi32(lo_cube[0], lo_cube[1], lo_cube[2], 0);
  // offsets of the 9 rows of 3 x 3 x 3 cubes from the first
  size_t row_offset[9];
  for (int z = 0; z < 3; ++z)
    for (int y = 0; y < 3; ++y) row_offset[3 * z + y] = size_t(z) * sz + size_t(y) * sy;
  // entries for the cubes the vertices fall in: 2.6 and 2.4 per expected cell at the bunny's 2 % and
  // 10 % levels
  CandidateCache cache(dims, expected * 3);
  const uint32_t* const cache_bricks = cache.bricks();
  const uint16_t* slots = cache.slots();
  // lane 3 of lo4 is not a coordinate: a stride of 0, a shift of 32 (0)
  const __m128i brick_stride4 = _mm_setr_epi32(1, int32_t(cache.brickStrideY()), int32_t(cache.brickStrideZ()), 0);
  const __m128i in_brick_shift4 = _mm_setr_epi32(0, 2, 4, 32);
  std::vector<glm::vec3> local;  // (the sorted copy, where a chain dropped it)
  const glm::vec3* sorted = sortedPositions(p, local);
  // vertex k's range and the place of its cube in the cache (cache.find with the three axes at once:
  // the scalar form took 30 instructions a vertex), a vertex ahead (as in assignDenseAvx2T; the
  // bricks themselves may be allocated meanwhile), or for the vertices cachedRun leaves. The first
  // head's offset, needed by the few vertices that gather, is not (ahead, it cost 9 instructions a vertex)
  Located ahead{};
  uint32_t ahead_brick = 0, ahead_in_brick = 0;
  auto plan = [&](size_t k) SCENELOD_FLOATING_AVX2_TARGET {
    const glm::vec3 pk = sorted[k];
    // the range of cubes along the three axes at once, with the scalar path's operations per lane
    // ((q - reach) - slack and floorToInt's truncation and correction)
    ahead.q4 = _mm_mul_ps(_mm_setr_ps(pk.x, pk.y, pk.z, 0.0f), inv4);
    ahead.lo4 = _mm_sub_epi32(floorToInt4(_mm_sub_ps(_mm_sub_ps(ahead.q4, reach4), slack4)), lo_cube4);
    ahead.hi4 = _mm_sub_epi32(floorToInt4(_mm_add_ps(_mm_add_ps(ahead.q4, reach4), slack4)), lo_cube4);
    const __m128i lo4 = ahead.lo4;
    const __m128i bm = _mm_mullo_epi32(_mm_srai_epi32(lo4, 2), brick_stride4);
    const __m128i im = _mm_sllv_epi32(_mm_and_si128(lo4, _mm_set1_epi32(3)), in_brick_shift4);
    __m128i bs = _mm_add_epi32(bm, _mm_shuffle_epi32(bm, _MM_SHUFFLE(1, 0, 3, 2)));
    __m128i is = _mm_or_si128(im, _mm_shuffle_epi32(im, _MM_SHUFFLE(1, 0, 3, 2)));
    bs = _mm_add_epi32(bs, _mm_shuffle_epi32(bs, _MM_SHUFFLE(2, 3, 0, 1)));
    is = _mm_or_si128(is, _mm_shuffle_epi32(is, _MM_SHUFFLE(2, 3, 0, 1)));
    ahead_brick = uint32_t(_mm_cvtsi128_si32(bs));
    ahead_in_brick = uint32_t(_mm_cvtsi128_si32(is));
  };
  // the order and cluster_of as plain pointers: through the vectors, each vertex reloaded both data
  // pointers from the stack and from p and out (the rare paths' calls may, for the compiler, change
  // them), 6 of the ~190 instructions a vertex at the 1 M sphere's 1 % level
  const uint32_t* const order = p.order.data();
  uint32_t* const cluster_of = out.cluster_of.data();
  CachedRunInputs<DenseGrid::Cell> run_in{nullptr, nullptr, cache_bricks, nullptr, sorted, order, cluster_of,
                                          inv4, reach4, slack4, lo_cube4, brick_stride4, rule};
  // the vertices from k on that their entries settle; the first that needs more
  auto runFrom = [&](size_t k) SCENELOD_FLOATING_AVX2_TARGET {
    run_in.entries = cache.entries();
    run_in.cells = cells.data();
    run_in.slots = cache.slots();
    return cachedRun<kCube, kNearest>(run_in, k, n);
  };
  // without runs (grids whose bricks' strides pass 15 bits, and a test's choice) as before them
  if (n > 0 && !kRuns) plan(0);
  for (size_t i = 0; i < n; ++i) {
    // after a run, vertex i: its cubes not 3 x 3 x 3, no entry yet or an overflowing one, inside
    // none of its entry's cells (a new cell), or the last vertex
    if constexpr (kRuns) {
      i = runFrom(i);
      plan(i);
    }
    const glm::vec3 pv = sorted[i];
    const __m128 q4 = ahead.q4;
    const __m128i lo4 = ahead.lo4, hi4 = ahead.hi4;
    const uint32_t brick_at = ahead_brick, in_brick = ahead_in_brick;
    if (!kRuns && i + 1 < n) plan(i + 1);
    const __m128i span = _mm_sub_epi32(hi4, lo4);
    const bool span2 = (_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(span, _mm_set1_epi32(2)))) & 7) == 7;
    uint32_t found[64 + 8];  // 8 spare: packRows and testCellLanes8 write 8 entries
    uint32_t found_count = 0;
    const int32_t lo[3] = {_mm_cvtsi128_si32(lo4), _mm_extract_epi32(lo4, 1), _mm_extract_epi32(lo4, 2)};
    uint32_t best = kNone;
    bool tested = false;
    if (span2) {
      uint16_t e = slots[size_t(cache_bricks[brick_at]) << 6 | in_brick];
      if (e == 0) {  // the cube's first vertex: its cells from the heads and lists, by index
        const uint32_t heads =
            gatherRows27(head.data() + size_t(lo[2]) * sz + size_t(lo[1]) * sy + size_t(lo[0]), row_offset, found);
        uint32_t listed[27 * 8];
        uint32_t count = 0;
        if (heads > 8 || !sortLoneHeads8(cells.data(), found, heads, listed)) {
          for (uint32_t j = 0; j < heads; ++j)
            for (uint32_t c = found[j]; c != 0; c = cells[c].next) {
              uint32_t k = count++;
              for (; k > 0 && listed[k - 1] > c; --k) listed[k] = listed[k - 1];
              listed[k] = c;
            }
        } else {
          count = heads;
        }
        e = cache.make(lo[0], lo[1], lo[2], listed, count);
        slots = cache.slots();
      }
      if (e != CandidateCache::kOverflow) {
        const CandidateCache::Entry& entry = cache.entry(e);
        __m256 cx, cy, cz;
        loadCentres8(cells.data(), entry.cell, cx, cy, cz);
        best = testEntry8<kCube, kNearest>(entry.cell, cx, cy, cz, _mm256_set1_ps(pv.x), _mm256_set1_ps(pv.y),
                                           _mm256_set1_ps(pv.z), rule);
        tested = true;
      }
    }
    if (!tested) {  // the general path (reach 1: 3 or 4 cubes per axis)
      if (span2) {
        found_count = gatherRows27(head.data() + size_t(lo[2]) * sz + size_t(lo[1]) * sy + size_t(lo[0]), row_offset, found);
      } else {
        const int32_t hi[3] = {_mm_cvtsi128_si32(hi4), _mm_extract_epi32(hi4, 1), _mm_extract_epi32(hi4, 2)};
        found_count = gatherHeadsAnySpan(head.data(), sy, sz, lo, hi, found, found_count);
      }
      best = bestListedCell8<kCube, kNearest>(cells.data(), found, found_count, pv, rule);
    }
    if (best == kNone) {
      best = out.cluster_count++;
      out.heaviest.push_back(order[i]);
      const __m128i c4 = _mm_sub_epi32(floorToInt4(q4), lo_cube4);
      const int32_t cx = _mm_cvtsi128_si32(c4), cy = _mm_extract_epi32(c4, 1), cz = _mm_extract_epi32(c4, 2);
      grid.list(cx, cy, cz, pv, best);
      cache.add(cx, cy, cz, best + 1);
    }
    cluster_of[order[i]] = best;
  }
}

// the runs wherever the bricks' strides fit 15 bits (on entries of indices, the cells' centres
// gathered and transposed: at the bunny's chain level 3 and 2 % level, where 1 vertex in 6-8 leaves
// a run, 0.84-0.89 -> 0.79-0.86 ms and 0.64 -> 0.54)
template <bool kCube, bool kNearest>
SCENELOD_FLOATING_AVX2_TARGET void assignDenseCachedAvx2T(const PreparedMesh& p, float cube_width, float reach,
                                                          const int32_t lo_cube[3], const size_t dims[3], JoinRule rule,
                                                          size_t expected, Assignment& out) {
  const int forced = g_cache_runs.load(std::memory_order_relaxed);
  // cachedRun's brick places as products of 16-bit halves: the strides of the bricks below 2^15
  const size_t bx = (dims[0] + 3) / 4, by = (dims[1] + 3) / 4, bz = (dims[2] + 3) / 4;
  const bool small_bricks = bx * by < 32768 && bz < 32768;
  if (small_bricks && forced != 0)
    assignDenseCachedAvx2Impl<kCube, kNearest, true>(p, cube_width, reach, lo_cube, dims, rule, expected, out);
  else
    assignDenseCachedAvx2Impl<kCube, kNearest, false>(p, cube_width, reach, lo_cube, dims, rule, expected, out);
}
#endif

// The grid of cubes of side w (where cubes of side w/2 would not fit): such a cube lists up to
// 8 cube cells and 64 sphere cells, so that chained lists took several rounds of dependent loads
// and a mispredicted exit per vertex (the 1 M sphere's 10 % level: 2.5 rounds, 0.7 mispredicts and
// 630 instructions per vertex). Here a cube's cells are kept in blocks of 4 ids; a vertex copies
// the 2 x 2 x 2 cubes' first blocks, whole, into one list (an empty cube copies block 0, all
// sentinels) and tests it in one pass. A head holds its first block's index and count (b << 3 | n,
// n = 5 when more blocks follow: 11 of the 25 k occupied cubes of the 1 M sphere's 10 % level, none
// of the bunny's 50 % level); such cubes, and vertices within the slack of a cube face (3 cubes
// along an axis), take a general gather. 20 bytes per block (kBlockBytes), one block per occupied
// cube: 1.4 to 2 cells per occupied cube on the bunny and the sphere.
// The heads are a flat array over the box where it fits the dense budget, else (kBricked) bricks
// of 4 x 4 x 4 cubes (256 bytes: 4 z-slices of one cache line each) allocated where a cell is
// listed, under a table of the box's bricks (4 bytes a brick, 1/256 of the flat heads): a fine
// level's surface then takes the bricks its cells touch, not its box. Bricked, a vertex's 2 x 2 x 2
// cubes cost 8 more loads (their bricks' indices, mostly one cache line) and its heads mostly 2
// lines. The bricks are reserved for the count the caller found (countVertexBricks), which takes
// the hash instead where they would be too many (scattered parts).
template <bool kBricked>
struct CellBlocks {
  struct Block {
    uint32_t id[4];  // cell indices, filled in order, 0 where free
  };
  struct alignas(64) Brick {
    uint32_t h[64];  // (z & 3) << 4 | (y & 3) << 2 | (x & 3)
  };
  static_assert(sizeof(Brick) == kBrickBytes, "a brick is 4 x 4 x 4 heads of 32 bits");
  std::vector<Block> blocks;  // blocks[0] stays empty
  std::vector<uint32_t> more;  // per block: the cube's next block once it is full, 0 for none
  std::vector<uint32_t> head;  // flat: per cube of the box
  std::vector<uint32_t> top;   // bricked: per brick of the box, its index in `bricks`, 0 for none
  std::vector<Brick> bricks;   // bricked: bricks[0] stays empty
  size_t sy, sz;               // the strides of `head` (flat) or of `top` (bricked, in bricks)

  // bricked: `brick_count` the bricks the level can fill (countVertexBricks), reserved whole
  CellBlocks(const size_t dims[3], size_t expected, size_t brick_count = 0) : blocks(1, Block{}), more(1, 0) {
    blocks.reserve(expectedBlocks(expected));
    more.reserve(expectedBlocks(expected));
    if (kBricked) {
      const size_t b[3] = {(dims[0] + 3) / 4, (dims[1] + 3) / 4, (dims[2] + 3) / 4};
      sy = b[0], sz = b[0] * b[1];
      top.assign(sz * b[2], 0);
      bricks.reserve(brick_count + 1);
      bricks.emplace_back();  // value-initialised: all heads empty
    } else {
      sy = dims[0], sz = dims[0] * dims[1];
      head.assign(sz * dims[2], 0);
    }
  }
  // cells reserved: an eighth over the expected count, which fell short by 3-4 % on the 1 M sphere's
  // chain levels of 118-137 k cells (their 16-byte records then doubled beside the old ones, up to
  // 5.7 MB at once, while the other thread held level 1's output: the chain's peak passed its budget)
  static size_t reservedCells(size_t expected_cells, size_t vertices) {
    return std::min(vertices, expected_cells + expected_cells / 8) + 1;
  }
  static size_t inBrick(int32_t x, int32_t y, int32_t z) { return size_t((z & 3) << 4 | (y & 3) << 2 | (x & 3)); }
  size_t brickOf(int32_t x, int32_t y, int32_t z) const {
    return size_t(z >> 2) * sz + size_t(y >> 2) * sy + size_t(x >> 2);
  }
  uint32_t headAt(int32_t x, int32_t y, int32_t z) const {
    if constexpr (kBricked) return bricks[top[brickOf(x, y, z)]].h[inBrick(x, y, z)];
    else return head[size_t(z) * sz + size_t(y) * sy + size_t(x)];
  }
  // the heads of the 2 x 2 x 2 cubes from lo into h (flat: `first` is lo's index in head)
  SCENELOD_ALWAYS_INLINE void heads8(const int32_t lo[3], size_t first, uint32_t h[8]) const {
    if constexpr (kBricked) {
      const size_t bx[2] = {size_t(lo[0] >> 2), size_t((lo[0] + 1) >> 2)};
      const size_t ix[2] = {size_t(lo[0] & 3), size_t((lo[0] + 1) & 3)};
      for (int z = 0; z < 2; ++z)
        for (int y = 0; y < 2; ++y) {
          const int32_t cy = lo[1] + y, cz = lo[2] + z;
          const uint32_t* row = top.data() + size_t(cz >> 2) * sz + size_t(cy >> 2) * sy;
          const size_t in = size_t((cz & 3) << 4 | (cy & 3) << 2);
          h[4 * z + 2 * y] = bricks[row[bx[0]]].h[in | ix[0]];
          h[4 * z + 2 * y + 1] = bricks[row[bx[1]]].h[in | ix[1]];
        }
    } else {
      const uint32_t* base = head.data() + first;
      for (int z = 0; z < 2; ++z)
        for (int y = 0; y < 2; ++y) {
          h[4 * z + 2 * y] = base[size_t(z) * sz + size_t(y) * sy];
          h[4 * z + 2 * y + 1] = base[size_t(z) * sz + size_t(y) * sy + 1];
        }
    }
  }
  // copies the first blocks of the 8 heads into found (4 entries each, whole), appending each
  // head's count; returns the count, and in `chained` bit 3 where some cube has more blocks
  SCENELOD_ALWAYS_INLINE uint32_t copyBlocks8(const uint32_t h[8], uint32_t* found, uint32_t& chained) const {
    uint32_t count = 0;
    chained = 0;
    for (int k = 0; k < 8; ++k) {
      const uint32_t* ids = blocks[h[k] >> 3].id;
#if defined(__SSE2__)
      _mm_storeu_si128(reinterpret_cast<__m128i*>(found + count), _mm_loadu_si128(reinterpret_cast<const __m128i*>(ids)));
#else
      for (int j = 0; j < 4; ++j) found[count + j] = ids[j];
#endif
      const uint32_t c = h[k] & 7u;  // 5 when more blocks follow: the list is then made again
      count += c;
      chained |= c + 3u;
    }
    return count;
  }
  // every cell listed in the cubes lo .. hi (grid indices), into scratch, followed by `pad` spare
  // entries; returns the count
  uint32_t gatherAll(const int32_t lo[3], const int32_t hi[3], std::vector<uint32_t>& scratch, size_t pad) const {
    scratch.clear();
    for (int32_t z = lo[2]; z <= hi[2]; ++z)
      for (int32_t y = lo[1]; y <= hi[1]; ++y)
        for (int32_t x = lo[0]; x <= hi[0]; ++x)
          for (uint32_t b = headAt(x, y, z) >> 3; b != 0; b = more[b])
            for (uint32_t k = 0; k < 4; ++k)
              if (blocks[b].id[k] != 0) scratch.push_back(blocks[b].id[k]);
    const uint32_t count = static_cast<uint32_t>(scratch.size());
    scratch.resize(scratch.size() + pad);
    return count;
  }
  // lists cell index `id` in cube (x, y, z)
  void add(int32_t x, int32_t y, int32_t z, uint32_t id) {
    uint32_t* hp;
    if constexpr (kBricked) {
      uint32_t& b = top[brickOf(x, y, z)];
      if (b == 0) {
        assert(bricks.size() < bricks.capacity());  // reserved for countVertexBricks's count
        b = uint32_t(bricks.size());
        bricks.emplace_back();
      }
      hp = &bricks[b].h[inBrick(x, y, z)];
    } else {
      hp = &head[size_t(z) * sz + size_t(y) * sy + size_t(x)];
    }
    uint32_t& h = *hp;
    if (h == 0) {
      h = uint32_t(blocks.size()) << 3 | 1u;
      blocks.push_back(Block{});
      more.push_back(0);
      blocks.back().id[0] = id;
    } else if ((h & 7u) < 4) {
      blocks[h >> 3].id[h & 7u] = id;
      ++h;
    } else {  // the first block is full: the last block of the cube's chain, or a new one
      h = (h & ~7u) | 5u;
      uint32_t b = h >> 3;
      while (more[b] != 0) b = more[b];
      uint32_t k4 = 0;
      while (k4 < 4 && blocks[b].id[k4] != 0) ++k4;
      if (k4 == 4) {
        more[b] = uint32_t(blocks.size());
        b = more[b];
        blocks.push_back(Block{});
        more.push_back(0);
        k4 = 0;
      }
      blocks[b].id[k4] = id;
    }
  }
};

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

#if defined(SCENELOD_FLOATING_AVX2)
// assignBlocksT on AVX2: the searched range on the three axes at once, the same copies of the
// first blocks, the cells tested 8 at a time (testCellLanes8, laneBest8)
template <bool kCube, bool kNearest, bool kBricked>
SCENELOD_FLOATING_AVX2_TARGET void assignBlocksAvx2T(const PreparedMesh& p, float cube_width, const int32_t lo_cube[3],
                                                     const size_t dims[3], JoinRule rule, size_t expected,
                                                     size_t brick_count, Assignment& out) {
  struct Cell {
    float x, y, z;
    uint32_t zero;
  };
  std::vector<Cell> cells;
  cells.reserve(CellBlocks<kBricked>::reservedCells(expected, p.order.size()));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cells.push_back({nan, nan, nan, 0});
  CellBlocks<kBricked> grid(dims, expected, brick_count);
  const size_t sy = grid.sy, sz = grid.sz;
  std::vector<uint32_t> scratch;
  const float inv = 1.0f / cube_width;
  const __m128 inv4 = _mm_set1_ps(inv), half4 = _mm_set1_ps(0.5f), slack4 = _mm_set1_ps(kSearchSlack);
  const __m128i lo_cube4 = _mm_setr_epi32(lo_cube[0], lo_cube[1], lo_cube[2], 0);
  const size_t n = p.order.size();
  std::vector<glm::vec3> local;  // (the sorted copy, where a chain dropped it)
  const glm::vec3* sorted = sortedPositions(p, local);
  // each vertex's range and (flat) the offset of its first head, planned kBlocksAhead vertices
  // ahead, when its heads' cache lines and its cluster id's slot are prefetched (see kBlocksAhead;
  // bricked, the lines of the bricks the table names then, re-read when the vertex is reached)
  struct Planned {
    Located at;
    size_t offset;
  };
  Planned ring[kBlocksAhead];
  const uint32_t* order = p.order.data();
  uint32_t* cluster_of = out.cluster_of.data();
  auto plan = [&](size_t k) SCENELOD_FLOATING_AVX2_TARGET {
    Planned& a = ring[k % kBlocksAhead];
    const glm::vec3 pk = sorted[k];
    a.at.q4 = _mm_mul_ps(_mm_setr_ps(pk.x, pk.y, pk.z, 0.0f), inv4);
    a.at.lo4 = _mm_sub_epi32(floorToInt4(_mm_sub_ps(_mm_sub_ps(a.at.q4, half4), slack4)), lo_cube4);
    a.at.hi4 = _mm_sub_epi32(floorToInt4(_mm_add_ps(_mm_add_ps(a.at.q4, half4), slack4)), lo_cube4);
    // lo >= 0: lo_cube is 3 cubes below the box
    const size_t x = size_t(uint32_t(_mm_cvtsi128_si32(a.at.lo4))), y = size_t(uint32_t(_mm_extract_epi32(a.at.lo4, 1))),
                 z = size_t(uint32_t(_mm_extract_epi32(a.at.lo4, 2)));
    if constexpr (kBricked) {
      a.offset = 0;  // (unused: the bricks are looked up again when the vertex is reached)
      // the z-slices of lo's cubes and of lo + (1, 1, 1)'s (the other cubes' lines but where a
      // row crosses a brick along x or y)
      const uint32_t* top = grid.top.data();
      const size_t in0 = (z & 3) << 4 | (y & 3) << 2, in1 = ((z + 1) & 3) << 4 | ((y + 1) & 3) << 2;
      const size_t b0 = top[(z >> 2) * sz + (y >> 2) * sy + (x >> 2)];
      const size_t b1 = top[((z + 1) >> 2) * sz + ((y + 1) >> 2) * sy + ((x + 1) >> 2)];
      const size_t b2 = top[((z + 1) >> 2) * sz + (y >> 2) * sy + (x >> 2)];
      const size_t b3 = top[(z >> 2) * sz + ((y + 1) >> 2) * sy + ((x + 1) >> 2)];
      const auto* bricks = grid.bricks.data();
      _mm_prefetch(reinterpret_cast<const char*>(bricks[b0].h + in0), _MM_HINT_T0);
      _mm_prefetch(reinterpret_cast<const char*>(bricks[b1].h + in1), _MM_HINT_T0);
      _mm_prefetch(reinterpret_cast<const char*>(bricks[b2].h + (((z + 1) & 3) << 4 | (y & 3) << 2)), _MM_HINT_T0);
      _mm_prefetch(reinterpret_cast<const char*>(bricks[b3].h + ((z & 3) << 4 | ((y + 1) & 3) << 2)), _MM_HINT_T0);
    } else {
      a.offset = z * sz + y * sy + x;
      const uint32_t* h = grid.head.data() + a.offset;
      _mm_prefetch(reinterpret_cast<const char*>(h), _MM_HINT_T0);
      _mm_prefetch(reinterpret_cast<const char*>(h + sy), _MM_HINT_T0);
      _mm_prefetch(reinterpret_cast<const char*>(h + sz), _MM_HINT_T0);
      _mm_prefetch(reinterpret_cast<const char*>(h + sz + sy), _MM_HINT_T0);
    }
    _mm_prefetch(reinterpret_cast<const char*>(cluster_of + order[k]), _MM_HINT_T0);
  };
  for (size_t k = 0; k < std::min(n, kBlocksAhead); ++k) plan(k);
  for (size_t i = 0; i < n; ++i) {
    const glm::vec3 pv = sorted[i];
    const Planned& planned = ring[i % kBlocksAhead];
    const __m128 q4 = planned.at.q4;
    const __m128i lo4 = planned.at.lo4, hi4 = planned.at.hi4;
    const size_t first = planned.offset;
    if (i + kBlocksAhead < n) plan(i + kBlocksAhead);
    const int32_t lo[3] = {_mm_cvtsi128_si32(lo4), _mm_extract_epi32(lo4, 1), _mm_extract_epi32(lo4, 2)};
    uint32_t found[8 * 5 + 8];  // 8 blocks at counts up to 5, then 8 sentinels of padding
    uint32_t* list = found;
    uint32_t count = 0;
    uint32_t chained = 0;
    const bool narrow =
        (_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(_mm_sub_epi32(hi4, lo4), _mm_set1_epi32(1)))) & 7) == 7;
    if (narrow) {
      uint32_t h[8];
      grid.heads8(lo, first, h);
      count = grid.copyBlocks8(h, found, chained);
    }
    if (!narrow || (chained & 8u)) {
      const int32_t hi[3] = {_mm_cvtsi128_si32(hi4), _mm_extract_epi32(hi4, 1), _mm_extract_epi32(hi4, 2)};
      count = grid.gatherAll(lo, hi, scratch, 8);
      list = scratch.data();
    }
    __m256 bd2 = _mm256_set1_ps(std::numeric_limits<float>::infinity());
    __m256i bid = _mm256_set1_epi32(0x7fffffff);
    testCellLanes8<kCube, kNearest>(cells.data(), list, count, _mm256_set1_ps(pv.x), _mm256_set1_ps(pv.y),
                                    _mm256_set1_ps(pv.z), rule, bd2, bid);
    uint32_t best = laneBest8<kNearest>(bd2, bid);
    if (best == kNone) {
      best = out.cluster_count;
      const __m128i c4 = _mm_sub_epi32(floorToInt4(q4), lo_cube4);
      grid.add(_mm_cvtsi128_si32(c4), _mm_extract_epi32(c4, 1), _mm_extract_epi32(c4, 2), best + 1);
      ++out.cluster_count;
      out.heaviest.push_back(p.order[i]);
      cells.push_back({pv.x, pv.y, pv.z, 0});
    }
    cluster_of[order[i]] = best;
  }
}
#endif

// the grid of side w in blocks (assignBlocksT), flat or bricked (brick_count: countVertexBricks)
void assignBlocks(const PreparedMesh& p, float cube_width, const int32_t lo_cube[3], const size_t dims[3],
                  JoinRule rule, size_t expected, bool bricked, size_t brick_count, Assignment& out) {
  using Fn = void (*)(const PreparedMesh&, float, const int32_t*, const size_t*, JoinRule, size_t, size_t,
                      Assignment&);
#if defined(SCENELOD_FLOATING_AVX2)
  if (useAvx2()) {
    static constexpr Fn kAvx2BlockFns[2][2][2] = {
        {{assignBlocksAvx2T<false, false, false>, assignBlocksAvx2T<false, true, false>},
         {assignBlocksAvx2T<true, false, false>, assignBlocksAvx2T<true, true, false>}},
        {{assignBlocksAvx2T<false, false, true>, assignBlocksAvx2T<false, true, true>},
         {assignBlocksAvx2T<true, false, true>, assignBlocksAvx2T<true, true, true>}}};
    kAvx2BlockFns[bricked][rule.cube][rule.nearest](p, cube_width, lo_cube, dims, rule, expected, brick_count, out);
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
    static constexpr Fn kCachedFns[2][2] = {{assignDenseCachedAvx2T<false, false>, assignDenseCachedAvx2T<false, true>},
                                            {assignDenseCachedAvx2T<true, false>, assignDenseCachedAvx2T<true, true>}};
    kCachedFns[rule.cube][rule.nearest](p, cube_width, reach, lo_cube, dims, rule, expected, out);
    return;
  }
  if (useAvx2()) {
    static constexpr Fn kAvx2Fns[2][2] = {{assignDenseAvx2T<false, false>, assignDenseAvx2T<false, true>},
                                          {assignDenseAvx2T<true, false>, assignDenseAvx2T<true, true>}};
    kAvx2Fns[rule.cube][rule.nearest](p, cube_width, reach, lo_cube, dims, rule, expected, out);
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
int setFloatingCacheRunsForTest(int runs) { return g_cache_runs.exchange(runs < 0 ? -1 : runs > 0 ? 1 : 0); }

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
