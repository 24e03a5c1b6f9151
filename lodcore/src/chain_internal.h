#pragma once
// What a chain knows about its levels while it builds them, for geomorphs (morph.cpp) and nested
// levels (nested_level.cpp): which cluster of each level every original vertex joined.
#include <cstdint>
#include <mutex>
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
// cluster of `b` holding the largest area (`area`, sourceAreas) of its original vertices (ties: the
// lower id); per vertex of `a`, the vertex of that cluster in `b` that its triangles become: each
// triangle of `a` whose corners go to three distinct clusters is matched to the triangle of `b` on
// them (same triangle group and orientation first, then the nearest texture coordinates) and votes
// with its area for the corners' vertices there. A vertex no matched triangle uses (edges, points,
// triangles that collapse, independent levels where no triangle of `b` matches) takes the vertex of
// its cluster in `b` with the same triangle group, then the nearest texture coordinates, then the
// nearest normal (ties: the lower index). A cluster of `a` none of whose vertices is in a cluster of
// `b` (its part vanished) keeps its vertices where they are. `a` null: `ma` is the chain's level 0,
// every vertex its own cluster (`area` is then not read and may be null). Normal targets exist where
// `b` has normals (for `a` without normals, vertices that stay keep computeVertexNormals' normal).
// Cost: O(V0 + Va + Vb) memory, O(Ta log Tb) time.
void computeMorph(const std::vector<float>* area, const LevelMap* a, const Mesh& ma, const LevelMap& b,
                  const Mesh& mb, LevelMorph& out);

// A chain's geomorphs made while its levels are built, each pair of adjacent levels' as soon as both
// exist, in two steps on the threads that build the levels: the clusters' targets as soon as both
// levels' assignments are made (levelClustered), the vertices' as soon as both levels' meshes are
// (levelBuilt). Each level's arrays are freed as soon as no step left reads them, so that a chain
// holds few of its levels' assignments (4 bytes per original vertex each) at once. Level 0 is
// `original` (its map the identity, never stored); levels 1..level_count come in any order, from any
// threads, levelClustered(k) before levelBuilt(k). `levels` is the chain's vector (sized by the time
// a level is built; levels[k].morph receives the pair (k, k + 1)).
class MorphPairs {
 public:
  MorphPairs(const Mesh& original, std::vector<LodLevel>& levels, size_t level_count);
  // level k's assignment (1 <= k <= level_count): the cluster of every original vertex (kNone for
  // none), in the ids of its vertex_cluster below. Thread-safe.
  void levelClustered(size_t k, std::vector<uint32_t> cluster_of);
  // level k's mesh is final, `vertex_cluster` the cluster of each of its vertices. Thread-safe.
  void levelBuilt(size_t k, std::vector<uint32_t> vertex_cluster);
  // forgets every level given so far (and their pairs' targets): levels dropped before the others
  // are built; not to be called while a level is being given
  void reset();

 private:
  bool pairReady(size_t a) const;  // (under the lock) the pair (a, a + 1)'s second step can run
  void firstStep(size_t a);
  void secondStep(size_t a);

  const Mesh& original_;
  std::vector<LodLevel>& levels_;
  const size_t n_;
  std::mutex mutex_;
  // per level (level 0's flags always set, its arrays never stored)
  std::vector<uint8_t> clustered_, built_;
  std::vector<std::vector<uint32_t>> cluster_of_, vertex_cluster_;  // until their last step
  std::vector<uint8_t> cluster_uses_, vertex_uses_;                 // steps left that read them
  // per pair (a, a + 1), a >= 1: the first step's result, per cluster of level a
  std::vector<std::vector<uint32_t>> best_;
  std::vector<uint8_t> best_done_;
  std::once_flag area_once_;
  std::vector<float> area_;  // sourceAreas(original), until the last first step
  size_t first_steps_ = 0;   // first steps still to be made
};

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
