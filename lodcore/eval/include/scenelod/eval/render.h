#pragma once
// Orthographic ray-cast pictures of meshes (Embree), and the image error between two meshes over a
// fixed set of 14 views: silhouette mismatch, normal deviation and colour difference (textured when
// materials are given), and popping along a LOD chain.
//
// Conventions: triangles are two-sided with their geometric (face) normals; an edge of thickness t is
// a capsule of radius t/2 shaded with its dynamic normal (Low & Tan 1997 §3.3.2), a point a sphere
// facing the viewer. Hairline edges (t = 0) and points would cover no pixel, so every capsule and
// sphere is drawn with a radius of at least `min_radius_px` pixels, as a renderer draws lines and
// points at least one pixel wide.
//
// Colour: without materials, vertex colours when the mesh has them, else grey triangles, blue edges
// and red points. With materials (material.h), a triangle's base colour is its material's factor x
// texture(uv) x COLOR_0 (white when the mesh has no colours), uv interpolated over the triangle from
// the material's set; a textured material on a mesh without that set shows its texture's mean
// colour. Edges and points keep the colours above.
#include <cstddef>
#include <vector>

#include <glm/vec3.hpp>

#include "scenelod/eval/image.h"
#include "scenelod/eval/material.h"
#include "scenelod/lodcore/lod_chain.h"
#include "scenelod/lodcore/mesh.h"
#include "scenelod/lodcore/status.h"

namespace scenelod::eval {

// The 14 fixed views: 0..5 seen from +x, -x, +y, -y, +z, -z; 6..13 seen from the diagonals
// (+-1, +-1, +-1) in the order x-, y-, z-sign bits of (index - 6), with bit set meaning negative.
constexpr int kStandardViewCount = 14;

struct View {
  glm::vec3 from{0.0f, 0.0f, 1.0f};  // unit direction from the object's centre towards the camera
  glm::vec3 up{0.0f, 1.0f, 0.0f};    // not parallel to `from`
};

// The standard view `index` in [0, 14); other indices give view 0.
View standardView(int index);

// Smallest sphere about the bounding-box centre holding every vertex (radius 0 for an empty mesh).
Sphere boundingSphere(const Mesh& mesh);

struct RenderParams {
  int width = 512;
  int height = 512;
  View view = standardView(6);
  Sphere frame;                  // the orthographic window fits this sphere; radius 0 = the mesh's own
  float min_radius_px = 0.75f;   // capsules and spheres at least this radius, in pixels
  glm::vec3 background{1.0f};    // linear RGB
  float ambient = 0.25f;         // ambient share of the headlight Lambert shading
  bool smooth = true;            // interpolate vertex normals when the mesh has them
  Span<const Material> materials;  // per triangle group; empty = vertex colours (see above)
};

// Renders `mesh` seen from `params.view`, orthographic, headlight Lambert + ambient shading of the
// colours above. Output is sRGB.
// Errors: width/height not in [1, 16384], an empty mesh with no frame given, a material whose
// texture's pixel buffer does not match its size.
// Cost: one Embree BVH build, one ray per pixel, TBB-parallel over rows; allocates the image.
Error renderMesh(const Mesh& mesh, const RenderParams& params, Image& out);

struct ImageErrorParams {
  int resolution = 256;        // square images, one per view
  Sphere frame;                // radius 0 = the original's bounding sphere
  float min_radius_px = 0.5f;  // hairline edges and points are about one pixel wide
  // colours as renderMesh draws them with its default shading; empty = vertex colours
  Span<const Material> original_materials;
  Span<const Material> simplified_materials;
};

// Two 8-bit sRGB pixels count as different when a channel differs by more than this.
constexpr int kColorTolerance = 16;

struct ImageErrorResult {
  double silhouette = 0.0;  // pixels hit by exactly one mesh / pixels hit by either, all views pooled
  double normal_deg = 0.0;  // mean angle between the two normals over pixels hit by both, degrees
  size_t either_px = 0;     // pixels hit by at least one mesh, all views
  size_t one_px = 0;        // pixels hit by exactly one
  size_t both_px = 0;       // pixels hit by both
  // colour over the pixels hit by both, as drawn (shaded, 8-bit sRGB)
  double color_off = 0.0;   // share of them differing by more than kColorTolerance in any channel
  double color_mad = 0.0;   // mean absolute difference per channel, in 8-bit levels (0..255)
  size_t color_off_px = 0;  // how many differ
};

// Ray casts `original` and `simplified` from the 14 standard views and compares them pixel by pixel.
// When neither mesh covers a pixel in any view the silhouette mismatch is 0; with no pixel hit by
// both the normal deviation and the colour errors are 0. Errors: resolution not in [1, 8192], an
// empty frame (empty original and no frame given), invalid meshes, invalid textures.
// Cost: 2 BVH builds, 2 * 14 * resolution^2 rays.
Error measureImageError(const Mesh& original, const Mesh& simplified, const ImageErrorParams& params,
                        ImageErrorResult& out);

// The image size at which a level of cell width `cell_width` is seen where the selector switches to
// it: one pixel is cell_width / X object units (X = `pixels_per_cell`), so an orthographic window
// fitted to `frame` (radius r) is 2 r X / cell_width pixels across; rounded and clamped to
// [min_resolution, max_resolution]. A perspective camera at distance D (pixel size 2 D tan(fov/2) / H)
// shows the object at the same size when D is the switch distance.
int switchResolution(const Sphere& frame, float cell_width, float pixels_per_cell, int min_resolution,
                     int max_resolution);

struct PoppingParams {
  float pixels_per_cell = 1.0f;  // X: a level with cell width w is used while w <= X * pixel size
  int min_resolution = 8;        // clamp of the image size at the switch distance
  int max_resolution = 1024;
  float min_radius_px = 0.5f;
};

struct PoppingTransition {
  size_t from_level = 0;      // the finer level, shown before the switch
  size_t to_level = 0;        // from_level + 1
  float cell_width = 0.0f;    // the coarser level's cell width
  int resolution = 0;         // pixels across the chain's bounding sphere at the switch distance
  ImageErrorResult error;     // from_level as reference, to_level compared
};

// Popping along a chain: for each consecutive pair (k, k+1) the image error at the distance where
// the selector switches to k+1, i.e. where one pixel is cell_width(k+1) / X object units. With an
// orthographic window fitted to level 0's bounding sphere (radius r) that is an image of
// 2 r X / cell_width(k+1) pixels across (clamped). One result per transition, in order.
// Errors: a chain with fewer than 2 levels, a level without a positive cell width, invalid meshes.
// Cost: per transition as measureImageError at its resolution.
Error measurePopping(const LodChain& chain, const PoppingParams& params, std::vector<PoppingTransition>& out);

}  // namespace scenelod::eval
