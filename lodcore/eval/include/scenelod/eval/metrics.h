#pragma once
// Geometric error between an original mesh and a simplified one, measured like Metro (Cignoni,
// Rocchini & Scopigno 1998): points sampled on each surface, distance to the nearest point of the
// other surface, one-sided maxima and RMS both ways, reported relative to the original's
// bounding-box diagonal (0.01 = 1 %).
//
// Geometry conventions (both for sampling and for closest points):
// - triangles are surfaces;
// - an edge of thickness t is a solid capsule of radius t/2 around its segment (t = 0: the segment);
// - a point is a sphere of radius 0 (the point itself); points carry no thickness in a Mesh;
// - the distance to a capsule or sphere is the distance to the solid: 0 inside it.
#include <cstddef>
#include <cstdint>
#include <string>

#include "scenelod/lodcore/mesh.h"
#include "scenelod/lodcore/status.h"

namespace scenelod::eval {

struct DistanceParams {
  size_t area_sample_count = 100000;  // random samples per surface, distributed by triangle area
  bool include_vertices = true;       // also every vertex referenced by a primitive
  uint64_t seed = 1;                  // fixed: the same meshes always give the same numbers
};

// One-sided distances from the samples of one mesh to the other mesh, in object units.
struct OneSidedDistance {
  double max = 0.0;
  double mean = 0.0;
  double rms = 0.0;
  size_t sample_count = 0;
};

struct DistanceResult {
  double hausdorff = 0.0;  // max(forward.max, backward.max) / diagonal
  double rms = 0.0;        // max(forward.rms, backward.rms) / diagonal
  double mean = 0.0;       // max(forward.mean, backward.mean) / diagonal
  double diagonal = 0.0;   // the original's bounding-box diagonal, object units
  OneSidedDistance forward;   // samples of the original -> simplified geometry
  OneSidedDistance backward;  // samples of the simplified geometry -> original surface
};

// Measures the symmetric Hausdorff and RMS distances between `original` and `simplified`.
// Samples: `area_sample_count` points on each mesh's triangles by area (a simplified level without
// triangles puts them on its capsules by length), the sample spacing carried over to its edges
// (points on the capsule surfaces) and every point, plus all referenced vertices.
// Preconditions: both meshes valid (validateMesh); `original` has at least one triangle with
// positive area; `simplified` may hold only edges and points but not nothing at all.
// Errors: kInvalidMesh (invalid mesh, original without triangles, empty simplified mesh).
// Cost: builds two Embree BVHs, one point query per sample; TBB-parallel and deterministic.
Error measureSurfaceDistance(const Mesh& original, const Mesh& simplified, const DistanceParams& params,
                             DistanceResult& out);

// Checks two meshes describe the same object at the same scale: an error when either bounding-box
// diagonal is more than `max_ratio` times the other (a unit mismatch, a wrong file). `what_a` and
// `what_b` name the meshes in the message. Cost: one pass over the positions.
Error checkComparableScales(const Mesh& a, const std::string& what_a, const Mesh& b, const std::string& what_b,
                            double max_ratio = 10.0);

}  // namespace scenelod::eval
