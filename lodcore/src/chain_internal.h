#pragma once
// What a chain knows about its levels while it builds them, for geomorphs (morph.cpp) and nested
// levels (nested_level.cpp): which cluster of each level every original vertex joined.
#include <cstdint>
#include <vector>

#include <glm/vec4.hpp>

#include "attribute_level.h"
#include "cluster_internal.h"
#include "scenelod/lodcore/lod_chain.h"

namespace scenelod::detail {

// One level's vertex -> cluster maps. Cluster ids are the level's own (any numbering); only
// equality matters.
struct LevelMap {
  std::vector<uint32_t> cluster_of;      // per vertex of the chain's level 0: its cluster here, kNone when none
  std::vector<uint32_t> vertex_cluster;  // per vertex of the level's mesh: its cluster
  bool empty() const { return vertex_cluster.empty(); }
};

// level 0's map: every vertex its own cluster
void identityMap(size_t vertex_count, LevelMap& out);

// Per vertex of `original`: a third of the area of its triangles, plus a floor (1e-6 of the mean
// vertex's, or 1 without triangles) so that vertices of edges and points count too.
std::vector<float> sourceAreas(const Mesh& original);

// The geomorph of level `a` toward level `b` (LevelMorph in lod_chain.h): per cluster of `a`, the
// cluster of `b` holding the largest area of its original vertices (ties: the lower id); per vertex
// of `a`, the vertex of that cluster in `b` with the same triangle group, then the nearest texture
// coordinates, then the nearest normal (ties: the lower index). A cluster of `a` none of whose
// vertices is in a cluster of `b` (its part vanished) keeps its vertices where they are.
// Cost: O(V0 + Va + Vb) time and memory.
void computeMorph(const std::vector<float>& area, const LevelMap& a, const Mesh& ma, const LevelMap& b,
                  const Mesh& mb, LevelMorph& out);

// What each vertex of a level carries into the nested level after it: the heaviest weight of its
// cluster and the face sums of its cluster's original vertices (on the cluster's first vertex only,
// so that crease and seam copies do not count them twice).
struct Carried {
  std::vector<float> weight;
  std::vector<VertexFaceSums> sums;
  std::vector<glm::vec4> colors;  // empty where the mesh has no colours
};

// A level's mesh made ready for clustering the next nested level: welded and split into charts when
// it has attributes, prepared (graded and sorted), its weights and face sums replaced by the
// carried ones when given.
struct NestedInput {
  bool attributes = false;
  AttributeMesh am;
  PreparedMesh p;
};
Error prepareNested(const Mesh& prev, const Carried* carried, const ClusterParams& params, NestedInput& in);

// Clusters `in` (prepared from `prev`, a level of the chain whose level 0 is `original`) at
// params.cell_width into `out`: its mesh, source vertices (in `original`'s indices, through
// `prev_source`; null: prev is the original), max_error (measured on `original`'s vertices when
// `prev_map` is given, else prev_error + the step's own displacement, a bound), cell width and
// method. `out_map` (optional, needs `prev_map`) gets the level's map, `out_carried` (optional)
// what its vertices carry on. Errors: those of the assignment (cell width, method).
Error nestedLevel(NestedInput& in, const Mesh& prev, const LevelMap* prev_map, const std::vector<uint32_t>* prev_source,
                  float prev_error, const Mesh& original, const ClusterParams& params, LodLevel& out, LevelMap* out_map,
                  Carried* out_carried);

}  // namespace scenelod::detail
