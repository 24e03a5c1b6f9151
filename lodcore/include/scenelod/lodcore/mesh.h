#pragma once
// Owned meshes and non-owning views over caller memory.
//
// A Mesh holds positions with optional per-vertex normals, colours and texture coordinates, and
// three kinds of primitives: triangles, edges (with a thickness, Low & Tan 1997 §3.3) and points.
// When the input had polygons (OBJ faces with more than three corners), the original faces are kept
// as offsets into a corner list next to their triangulation, because SCROOGE works on polygons.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>
#include <glm/ext/vector_uint4_sized.hpp>

#include "scenelod/lodcore/span.h"
#include "scenelod/lodcore/status.h"

namespace scenelod {

struct Aabb {
  glm::vec3 min{0.0f};
  glm::vec3 max{0.0f};

  glm::vec3 center() const { return (min + max) * 0.5f; }
  glm::vec3 extent() const { return max - min; }
  float diagonal() const;  // length of max - min
};

struct Mesh {
  // vertex attributes: positions always; the others empty or one per vertex
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;
  std::vector<glm::vec3> colors;  // linear RGB (sRGB inputs are converted before any averaging)
  std::vector<glm::vec2> uvs;                     // texture coordinates, set 0 (glTF TEXCOORD_0)
  std::vector<std::vector<glm::vec2>> extra_uvs;  // sets 1, 2, ... (TEXCOORD_1, ...), each one per vertex
  std::vector<glm::vec4> tangents;                // xyz a unit tangent, w = +1 or -1 (the bitangent's sign)
  // skinning (glTF JOINTS_0 / WEIGHTS_0): four joints per vertex and their weights (non-negative,
  // summing to more than 0; unused slots weight 0); both empty or both one per vertex
  std::vector<glm::u16vec4> joints;
  std::vector<glm::vec4> weights;
  // the skeleton, optional: the parent of each joint (-1 for a root), carried into levels, packs and
  // the C API for engines; when given, every joint index is below its size
  std::vector<int32_t> joint_parents;

  // primitives, as indices into the vertex arrays
  std::vector<uint32_t> triangles;       // 3 per triangle, counter-clockwise front faces
  std::vector<uint32_t> edges;           // 2 per edge
  std::vector<float> edge_thickness;     // one per edge (object space, 0 = hairline); empty = all 0
  std::vector<uint32_t> points;          // 1 per point
  // the primitive (material) each triangle belongs to, one per triangle; empty = all in group 0.
  // Triangles of different groups never merge and a group border is a seam between UV charts.
  std::vector<uint32_t> triangle_groups;
  // the same for edges and points (a thin part collapsed into a thick edge keeps its material):
  // empty = all in group 0, else one per edge / point
  std::vector<uint32_t> edge_groups;
  std::vector<uint32_t> point_groups;

  // original polygon faces (optional): face f has corners face_corners[face_offsets[f] ..
  // face_offsets[f+1]); face_offsets is empty or face_count + 1 long, starting at 0
  std::vector<uint32_t> face_offsets;
  std::vector<uint32_t> face_corners;

  size_t vertexCount() const { return positions.size(); }
  size_t triangleCount() const { return triangles.size() / 3; }
  size_t edgeCount() const { return edges.size() / 2; }
  size_t pointCount() const { return points.size(); }
  size_t faceCount() const { return face_offsets.empty() ? 0 : face_offsets.size() - 1; }
  bool empty() const { return triangles.empty() && edges.empty() && points.empty(); }

  float edgeThickness(size_t e) const { return edge_thickness.empty() ? 0.0f : edge_thickness[e]; }
  uint32_t triangleGroup(size_t t) const { return triangle_groups.empty() ? 0u : triangle_groups[t]; }
  uint32_t edgeGroup(size_t e) const { return edge_groups.empty() ? 0u : edge_groups[e]; }
  uint32_t pointGroup(size_t p) const { return point_groups.empty() ? 0u : point_groups[p]; }
  bool skinned() const { return !joints.empty(); }
};

// Non-owning view of a triangle mesh in caller memory; strides are in bytes, so positions may be
// interleaved with other attributes. normals and colors may be empty.
struct MeshView {
  StridedSpan<const glm::vec3> positions;
  StridedSpan<const glm::vec3> normals;
  StridedSpan<const glm::vec3> colors;
  Span<const uint32_t> triangles;  // 3 indices per triangle
};

// Checks a mesh: attribute sizes match the vertex count, every index is below the vertex count,
// every coordinate is finite, thickness and face lists are consistent. `what` names the mesh (a file
// path, a mesh name) in the message. Returns an empty Error when valid.
// Cost: one pass over the mesh, no allocation beyond the message.
Error validateMesh(const Mesh& mesh, const std::string& what);

// Copies a view into an owned mesh (validated like validateMesh). Allocates.
Error meshFromView(const MeshView& view, Mesh& out, const std::string& what);

// Axis-aligned bounds of all vertices referenced or not; a zero box for an empty mesh.
Aabb computeBounds(const Mesh& mesh);
Aabb computeBounds(Span<const glm::vec3> positions);

// The first element on a cycle of parent links (each -1 for a root, or an index below the count),
// or the count when the links form a forest (skeletons' joint parents, scene and pack nodes).
// Precondition: every link is -1 or in range. Cost: O(n), one allocation.
size_t firstParentCycle(Span<const int32_t> parent);

// Fan-triangulates polygon faces (face_offsets/face_corners) into mesh.triangles, replacing them.
// Convex faces triangulate exactly; concave faces use ear clipping in the face's best-fit plane.
// Faces with fewer than 3 corners are dropped. Returns the number of triangles written.
size_t triangulateFaces(Mesh& mesh);

// Per-vertex normals from area-weighted face normals (no crease handling: the clustering levels get
// crease-aware normals, ClusterParams::crease_angle_deg in cluster.h). Leaves normals of
// unreferenced vertices at 0,0,1.
void computeVertexNormals(Mesh& mesh);

}  // namespace scenelod
