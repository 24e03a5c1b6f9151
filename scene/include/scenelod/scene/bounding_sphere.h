#pragma once
// Bounding spheres of point sets and LOD chains: Ritter's fast approximate sphere and the minimal
// enclosing sphere (Welzl's algorithm in Gärtner's move-to-front form).
#include <cstddef>

#include <glm/vec3.hpp>

#include "scenelod/lodcore/lod_chain.h"
#include "scenelod/lodcore/span.h"

namespace scenelod::scene {

// Ritter 1990 ("An efficient bounding sphere", Graphics Gems): the sphere through the two far-apart
// points found from an extreme point, grown point by point. Contains every point; typically 5-20 %
// larger than minimal. An empty input gives a zero sphere. Cost: 3 passes, no allocation.
Sphere ritterSphere(Span<const glm::vec3> points);

// The smallest sphere containing every point (Welzl 1991, move-to-front as in Gärtner 1999), in
// double precision, then grown by a few ulps so that every float point is inside when tested in
// float. Deterministic (fixed shuffle seed). An empty input gives a zero sphere.
// Cost: expected O(n); allocates O(n) scratch.
Sphere minimalSphere(Span<const glm::vec3> points);

// Smallest radius r such that every point is within r of `center` (rounded up): the radius a sphere
// at `center` needs to contain the points. Cost: one pass.
float coveringRadius(Span<const glm::vec3> points, const glm::vec3& center);

// Sets every level's `bounds` to the minimal sphere of that level's vertices and returns one
// object-space sphere containing every level (the minimal sphere of all levels' vertices).
// Cost: O(total vertices); allocates scratch.
Sphere computeChainBounds(LodChain& chain);

// The sphere containing both spheres (smallest such). Cost: O(1).
Sphere mergeSpheres(const Sphere& a, const Sphere& b);

}  // namespace scenelod::scene
