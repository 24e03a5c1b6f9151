#pragma once
// Area-weighted colour blending (Reddy 1996, SCROOGE §7.3): below the visual threshold the eye
// integrates colour over area, so a merged or clustered piece of surface takes the area-weighted mean
// of the colours it replaces. Textured surfaces follow the same rule once their texture's mean texel
// colour is in the vertex colours (the glTF importer bakes it in: scene_data.h MeshData).
//
// For the clustering generator: give every input vertex the cluster it joins; each cluster's colour is
// sum_v A_v c_v / sum_v A_v with A_v a third of the area of the triangles around v (its barycentric
// area). That equals the exact mean colour of the surface of those triangles under linear colour
// interpolation, so clusters of big triangles outweigh clusters of slivers.
#include <cstddef>
#include <cstdint>

#include <glm/vec3.hpp>

#include "scenelod/lodcore/mesh.h"
#include "scenelod/lodcore/span.h"

namespace scenelod {

constexpr uint32_t kNoGroup = 0xffffffffu;

// Fills group_colors[g] with the area-weighted mean colour of the vertices v with vertex_group[v] == g.
// Vertices with kNoGroup are skipped. A group whose vertices touch no triangle of positive area gets
// the plain mean of its vertices' colours, and a group with no vertex gets black.
// Preconditions: mesh.colors is one per vertex (else every group gets white, the glTF default);
// vertex_group.size() == mesh.vertexCount(); every group below group_colors.size().
// Cost: one pass over the triangles and the vertices, no allocation beyond a group_colors-sized array.
void areaWeightedColors(const Mesh& mesh, Span<const uint32_t> vertex_group, Span<glm::vec3> group_colors);

// Area-weighted mean colour of one polygon whose corners have the given positions and colours
// (fan-triangulated from corner 0, each fan triangle weighting its corners' mean by its area).
// Returns the plain mean of the corner colours when the polygon has no area, black when count is 0.
glm::vec3 polygonMeanColor(const glm::vec3* positions, const glm::vec3* colors, size_t count);

}  // namespace scenelod
