// The pieces of the floating-cell assignment (Low & Tan 1997 §3.2, §4) that its baseline grids
// (floating_cell_cluster.cpp) and their AVX2 variants (floating_cell_avx2.cpp) share: the joining
// rule and its four-lane test, the flat grid of list heads (DenseGrid), the grid of side w in blocks
// (CellBlocks), and the AVX2 file's entry points. Private to lodcore.
#pragma once

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#if defined(__SSE2__)
#include <emmintrin.h>
#include <xmmintrin.h>
#endif

#if defined(__SSE2__) && (defined(__x86_64__) || defined(__i386__))
#define SCENELOD_FLOATING_AVX2 1
#include <immintrin.h>
#define SCENELOD_FLOATING_AVX2_TARGET __attribute__((target("avx2,popcnt")))
#endif

#include "cluster_internal.h"

namespace scenelod::detail::floating {

// slack on the searched range so that a centre exactly on a cell's face is never missed by rounding
constexpr float kSearchSlack = 1e-4f;
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

#if defined(SCENELOD_FLOATING_AVX2)
// floating_cell_avx2.cpp: the AVX2 variants of assignDenseT (cubes of side w/2 or w, flat heads;
// `cached`: with the candidate cache, cubes of side w/2 only) and of assignBlocksT, for any rule
void assignDenseAvx2(const PreparedMesh& p, float cube_width, float reach, const int32_t lo_cube[3],
                     const size_t dims[3], JoinRule rule, size_t expected, bool cached, Assignment& out);
void assignBlocksAvx2(const PreparedMesh& p, float cube_width, const int32_t lo_cube[3], const size_t dims[3],
                      JoinRule rule, size_t expected, bool bricked, size_t brick_count, Assignment& out);
#endif

}  // namespace scenelod::detail::floating
