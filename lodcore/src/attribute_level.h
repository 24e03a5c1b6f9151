#pragma once
// Clustering levels of meshes with attributes (texture coordinates, tangents, skins, several
// triangle groups): the assignment and synthesis of any mesh, then an output pass of their own that
// gives each cluster one vertex per attribute group (docs/CLUSTERING.md, "Attributes"). Meshes
// without attributes never come here: their levels take the optimised pass of normals.cpp.
#include <cstdint>
#include <string>
#include <vector>

#include "cluster_internal.h"

namespace scenelod::detail {

// whether a mesh takes the attribute path: texture coordinates (any set), tangents, a skin, or more
// than one distinct triangle group
bool hasAttributes(const Mesh& m);

// A mesh without attributes whose triangles all carry one group (a material index other than 0,
// as scene::flattenScene writes) keeps it: every triangle of its level `out` gets that group.
void carryUniformGroup(const Mesh& in, Mesh& out);

// A mesh made ready for attribute levels once (a chain's levels share it): welded (a non-indexed
// input would otherwise be one UV chart per triangle) and split into UV charts.
struct AttributeMesh {
  const Mesh* input = nullptr;
  Mesh welded;                         // used only where welding removed a vertex
  bool did_weld = false;
  std::vector<uint32_t> input_vertex;  // per welded vertex: its first vertex in the input
  std::vector<uint32_t> welded_of;     // per input vertex: its welded vertex (empty when none welded)
  std::vector<uint32_t> chart;         // per triangle: its UV chart (computeUvCharts), or its
                                       // triangle group where the mesh has no texture coordinates
  // per triangle: what each corner adds to its group's weight, a third of the area (floored at 1e-6
  // of the mean triangle's, so that a group of degenerate triangles takes the plain mean)
  std::vector<float> corner_weight;

  // the mesh the levels cluster: the welded copy, or the input where nothing welded
  const Mesh& mesh() const { return did_weld ? welded : *input; }
};

// Welds a copy of `in` (made only where a vertex is removed) and computes its charts. Keeps a
// pointer to `in`, which must outlive `out`. Precondition: validateMesh(in) passes.
void makeAttributeMesh(const Mesh& in, AttributeMesh& out);

// One level at params.cell_width from `p`, prepared from am.mesh(): assignment, synthesis,
// elimination of edges and points, then the attribute output pass. `source_vertex` (optional)
// receives per output vertex one vertex of the input (am.input) it stands for.
// Errors: those of the assignment (cell width, method).
Error clusterAttributeLevel(const PreparedMesh& p, const AttributeMesh& am, const ClusterParams& params, Mesh& out,
                            std::vector<uint32_t>* source_vertex, ClusterStats* stats);

// clusterAttributeLevel in two steps, so that a chain can free the prepared mesh's arrays between
// them: the first (assignment with the skin split, synthesis, elimination, the stats) reads them;
// the second (the output pass, which frees `parts`) reads only the attribute mesh.
struct AttributeLevelParts {
  Assignment assignment;
  Representatives representatives;
  Eliminated eliminated;  // its edges and points (its triangles are freed: the output pass makes its own)
};
Error clusterAttributeParts(const PreparedMesh& p, const ClusterParams& params, AttributeLevelParts& parts,
                            ClusterStats* stats);
// `cluster_of` (optional) receives the assignment's cluster of every vertex of am.mesh(), and
// `vertex_cluster` (optional) every output vertex's cluster
void finishAttributeLevel(const AttributeMesh& am, const ClusterParams& params, AttributeLevelParts& parts, Mesh& out,
                          std::vector<uint32_t>* source_vertex, std::vector<uint32_t>* cluster_of = nullptr,
                          std::vector<uint32_t>* vertex_cluster = nullptr);

// clusterPrepared and clusterMesh for a mesh with attributes: weld, charts, and (where welding
// removed vertices) a preparation of the welded mesh with `prepared`'s grading
Error clusterAttributeMesh(const PreparedMesh& prepared, const ClusterParams& params, Mesh& out,
                           std::vector<uint32_t>* source_vertex, ClusterStats* stats);

}  // namespace scenelod::detail
