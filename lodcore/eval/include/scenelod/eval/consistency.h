#pragma once
// The consistency measure of Low & Tan 1997 §3.2.2 (plate 5): how many output triangles of one
// simplification have no counterpart in another. Used to show that floating cells, centred on the
// heaviest vertices, do not move when the bounding box changes, while uniform cells do.
#include <cstddef>

#include "scenelod/lodcore/mesh.h"

namespace scenelod::eval {

struct TriangleChangeCount {
  size_t compared = 0;  // triangles of `before` with all three corners inside the region
  size_t changed = 0;   // of those, the ones with no matching triangle in `after`
};

// Counts the triangles of `before` lying inside `region` (all corners, bounds inclusive) that have
// no triangle of `after` inside the region with the same corners within `eps` (Euclidean, each
// corner) in the same cyclic order: a triangle with its corners rotated is the same triangle, a
// flipped one is not. Edges and points are ignored. Preconditions: eps >= 0, index ranges valid.
// Cost: O((T_before + T_after) · k) expected, k the triangles per grid cube of side ~ the mean
// triangle size (a hash grid of centroids); O(T_after) extra memory.
TriangleChangeCount countChangedTriangles(const Mesh& before, const Mesh& after, const Aabb& region, float eps);

}  // namespace scenelod::eval
