#pragma once
// Ordering of a mesh for the GPU: triangles for the post-transform vertex cache (Forsyth's linear-
// speed optimiser), vertices in order of first use for vertex fetch, and the ACMR measure.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "scenelod/lodcore/mesh.h"
#include "scenelod/lodcore/span.h"

namespace scenelod::scene {

// Reorders the triangles of `indices` (3 per triangle) for a small LRU vertex cache (Forsyth 2006,
// "Linear-Speed Vertex Cache Optimisation": 32-entry cache model, scores from cache position and
// remaining valence). Writes index_count indices to `destination` (may not alias `indices`); the
// same triangles with the same corner order, only the triangle order changes.
// Preconditions: indices.size() % 3 == 0, every index < vertex_count, destination.size() >=
// indices.size(). Cost: O(index_count) time, O(vertex_count + index_count) allocated scratch.
void optimizeVertexCache(Span<uint32_t> destination, Span<const uint32_t> indices, size_t vertex_count);

// Fills `remap` (vertex_count entries) with each vertex's new index so that vertices are numbered
// in order of first use in `indices`; unused vertices get the following numbers in their old order
// (nothing is dropped). Returns the number of used vertices. Cost: O(index_count + vertex_count).
size_t vertexFetchRemap(Span<uint32_t> remap, Span<const uint32_t> indices, size_t vertex_count);

// Average cache miss ratio: vertices transformed per triangle with a FIFO post-transform cache of
// `cache_size` entries (0.5 is the best possible on large regular meshes, 3.0 the worst).
// Same model as meshopt_analyzeVertexCache(..., cache_size, 0, 0). Cost: O(index_count).
double computeAcmr(Span<const uint32_t> indices, size_t vertex_count, size_t cache_size = 16);

// Reorders one mesh in place: triangles sorted by triangle group (stable) and each group's
// triangles with optimizeVertexCache (triangle_groups follow their triangles, so each group is one
// contiguous range), then every vertex attribute (UV sets, colours, tangents, joints, weights) in
// order of first use by triangles, then edges, then points; indices of triangles, edges, points and
// polygon faces are rewritten. Edges and points keep their order. Vertex count is unchanged. When
// `vertex_remap` is given it receives each old vertex's new index (for arrays kept beside the mesh,
// such as LodLevel::source_vertex). Cost: O(vertices + triangles log triangles); allocates.
void optimizeMeshOrder(Mesh& mesh, std::vector<uint32_t>* vertex_remap = nullptr);

}  // namespace scenelod::scene
