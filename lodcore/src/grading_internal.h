// The grading pass's lane paths (grading_lanes.cpp), for gradeAndSum in grading.cpp: a row of a
// vertex's incidences graded four incidences at a time (SSE2), or two rows side by side in eight
// lanes (AVX2, where the CPU has it), with the scalar pass's operations, so the same bits
// (tests/lodcore/grading_test.cpp). Private to lodcore.
#pragma once

#include <cstddef>
#include <cstdint>

#include <glm/vec3.hpp>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "cluster_internal.h"

namespace scenelod::grading {

// a vertex's incidence: a triangle corner or an input edge's end
struct Incidence {
  uint32_t a, b;  // triangle corner: the next two corners (winding order); edge end: other end, kNone
};

// above this many directions, the widest pair is found by two sweeps
constexpr size_t kExactPairLimit = 64;

#if defined(__SSE2__)
// Rows of up to kLaneRow triangle corners and no input edge, on meshes without colours (all but
// a few vertices of a typical mesh), take a four-lane path: the same float operations as the
// scalar pass in gradeAndSum, in the same order where the order matters, four incidences or
// neighbours per SSE2 operation. Every lane does the scalar code's arithmetic (mulps / addps /
// divps / sqrtps round like their scalar forms; no FMA without -mfma), so the results are
// bit-identical:
// - the face sums add, in row order, the products of every incidence; a skipped face (zero area)
//   adds +0.0, which leaves a sum unchanged (a sum that starts at +0.0 is never -0.0);
// - the distinct neighbours come from comparing every candidate (the two other corners of each
//   incidence) with the later ones; their order does not matter here: the widest pair is the exact
//   minimum over pairs for up to 2 x kLaneRow <= kExactPairLimit directions, and min and max do not
//   depend on the order (up to the sign of a zero dot product, which 1 +- cos makes the same);
// - unused lanes (padding, repeated neighbours, zero-length edges, zero-area faces) hold NaN in the
//   direction and normal columns: their dot products are NaN, which the minimum skips.

constexpr size_t kLaneRow = 16;
static_assert(2 * kLaneRow <= kExactPairLimit, "the lane path needs the exact pair minimum");

struct alignas(16) LaneScratch {
  uint32_t ia[kLaneRow], ib[kLaneRow];  // per incidence the corners a and b (the vertex itself in padding lanes)
  float nrm[3][kLaneRow];         // unit face normals (x, y, z columns) per incidence; NaN if not a face
  float dir[3][2 * kLaneRow];     // unit directions per candidate; NaN unless a distinct non-zero edge
};

struct LaneRow {
  float sums[12];      // quadric xx..zz, normal x, y, z, then the summed area (10, 11 unused); not
                       // written by gradeTwoRowsAvx2 when it encodes them itself
  float longest;       // longest incident edge
  float cos_dirs;      // minPairDot of the directions (1 when fewer than two)
  float cos_normals;   // minPairDot of the face normals, when asked
  bool any_dir;        // some incident edge has non-zero length
  bool boundary;       // some neighbour is shared by only one incident triangle
};

// coordinate c of four points, one per lane
inline __m128 column(const glm::vec3 p[4], int c) { return _mm_setr_ps(p[0][c], p[1][c], p[2][c], p[3][c]); }

// Grades one row of r (1 <= r <= kLaneRow) triangle corners of vertex v; false (and nothing
// computed) when the row holds an input edge. `row` may be read up to the next multiple of 4.
bool gradeRowLanes(const glm::vec3* pos, uint32_t v, const Incidence* row, size_t r, bool want_normals,
                   LaneScratch& s, LaneRow& out);
// Two rows of 5 to 8 triangle corners, of vertices v0 and v0 + 1, in one AVX2 pass (callers check
// detail::avx2Paths()); false (nothing computed) when either row holds an input edge. With `sums`
// (else null), the rows' face sums are encoded into sums[0] and sums[1] and out[i].sums is not written.
bool gradeTwoRowsAvx2(const glm::vec3* pos, uint32_t v0, const Incidence* row0, size_t r0, size_t r1,
                      bool want_normals, LaneScratch s[2], LaneRow out[2], VertexFaceSums* sums);
#endif

}  // namespace scenelod::grading
