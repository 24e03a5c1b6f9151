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

// A mesh made ready for attribute levels once (a chain's levels share it): welded (a non-indexed
// input would otherwise be one UV chart per triangle) and split into UV charts.
struct AttributeMesh {
  const Mesh* input = nullptr;
  Mesh welded;                         // used only where welding removed a vertex
  bool did_weld = false;
  std::vector<uint32_t> input_vertex;  // per welded vertex: its first vertex in the input
  std::vector<uint32_t> chart;         // per triangle: its UV chart (computeUvCharts)
  std::vector<uint32_t> chart_group;   // per chart: its triangle group

  // the mesh the levels cluster: the welded copy, or the input where nothing welded
  const Mesh& mesh() const { return did_weld ? welded : *input; }
};

// Welds a copy of `in` (kept only where a vertex was removed) and computes its charts. Keeps a
// pointer to `in`, which must outlive `out`. Precondition: validateMesh(in) passes.
void makeAttributeMesh(const Mesh& in, AttributeMesh& out);

// One level at params.cell_width from `p`, prepared from am.mesh(): assignment, synthesis,
// elimination of edges and points, then the attribute output pass. `source_vertex` (optional)
// receives per output vertex one vertex of the input (am.input) it stands for.
// Errors: those of the assignment (cell width, method).
Error clusterAttributeLevel(const PreparedMesh& p, const AttributeMesh& am, const ClusterParams& params, Mesh& out,
                            std::vector<uint32_t>* source_vertex, ClusterStats* stats);

// clusterPrepared and clusterMesh for a mesh with attributes: weld, charts, and (where welding
// removed vertices) a preparation of the welded mesh with `prepared`'s grading
Error clusterAttributeMesh(const PreparedMesh& prepared, const ClusterParams& params, Mesh& out,
                           std::vector<uint32_t>* source_vertex, ClusterStats* stats);

}  // namespace scenelod::detail
