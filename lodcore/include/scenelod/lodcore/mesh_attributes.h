#pragma once
// What a mesh's vertex attributes say about its surface, before it is simplified: which vertices are
// the same vertex (welding), and which triangles lie in one piece of texture space (UV charts).
//
// Exporters and non-indexed inputs repeat vertices (the glTF Fox has 1,728 vertices for 576
// triangles); clustering must see them as one vertex, or every triangle would be its own chart.
#include <cstdint>
#include <vector>

#include "scenelod/lodcore/mesh.h"

namespace scenelod {

// Merges vertices whose position and every attribute (normal, colour, all texture coordinate sets,
// tangent, skin joints and weights) are equal, keeping each first occurrence in its order, and
// rewrites the triangles, edges, points and face corners. -0 and +0 count as equal. Returns the
// number of vertices removed; `old_to_new` (optional) receives each old vertex's new index.
// Precondition: validateMesh(mesh) passes. Cost: one hash map over the vertices; O(n) expected.
size_t weldVertices(Mesh& mesh, std::vector<uint32_t>* old_to_new = nullptr);

// The same weld into `out`, written only where a vertex is removed (0 returned: `out` untouched), so
// that a mesh with nothing to weld is never copied. Cost: as weldVertices, plus the welded copy.
size_t weldedCopy(const Mesh& mesh, Mesh& out, std::vector<uint32_t>* old_to_new = nullptr);

// UV charts: triangles connected through edges whose two end vertices have the same position and the
// same texture coordinates in every set on both sides, within one triangle group (a material border
// separates charts). Vertices are compared by value, so a mesh need not be welded first. A mesh
// without texture coordinates has one chart per connected piece of each group. Writes one chart id
// per triangle to `triangle_chart`, numbered 0, 1, ... in the order of each chart's first triangle,
// and returns the number of charts.
// Precondition: validateMesh(mesh) passes. Cost: a hash table over the vertices and the triangles
// around each vertex (about 12 bytes a vertex and 20 a triangle); O(n + t x degree) expected.
uint32_t computeUvCharts(const Mesh& mesh, std::vector<uint32_t>& triangle_chart);

}  // namespace scenelod
