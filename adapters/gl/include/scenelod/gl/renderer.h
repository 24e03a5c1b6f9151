#pragma once
// An OpenGL 3.3 core renderer for LOD chains, headless through EGL (Mesa's surfaceless platform or
// the default display with a pbuffer; software rendering works, no GPU or display needed).
//
// Uploads every level of every chain to GPU buffers once, then draws per frame the level the
// selector chose for each object under its world matrix (geomorphed toward the next level and
// cross-faded from the previous one by screen-door dithering when asked): triangles with a
// headlight; thick edges expanded to camera-facing quads in the vertex shader, shaded with Low &
// Tan 1997 §3.3's dynamic normal ((V1 - C) x (V2 - C)) x (V2 - V1) and as wide as their thickness
// in world units (at least one pixel); points as GL_POINTS. drawFrame returns the measured frame time (CPU time of issuing
// the draws plus glFinish), which the caller hands to selection::reportFrameTime so the cost model
// is fitted to real rendering.
//
// Threads: one thread owns a Renderer (its GL context is current on the thread that called init).
// No GL or EGL type appears in this header.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <glm/mat4x4.hpp>

#include "scenelod/eval/image.h"
#include "scenelod/lodcore/lod_chain.h"
#include "scenelod/lodcore/span.h"
#include "scenelod/lodcore/status.h"
#include "scenelod/selection/camera.h"

namespace scenelod::gl {

struct RendererConfig {
  uint32_t width_px = 1280;    // the offscreen render target, 1..8192
  uint32_t height_px = 720;
  float background[3] = {0.08f, 0.09f, 0.11f};  // linear RGB clear colour
  float point_size_px = 3.0f;  // size of point primitives
  uint32_t shadow_map_px = 2048;  // side of the shadow map (depth texture), 16..8192, made on first use
};

// A material as the renderer draws it: base colour factor x base colour texture (8-bit RGBA rows,
// top row first, drawn as stored: no sRGB decoding) at the vertices' first texture coordinate set,
// transformed by `uv_transform` (KHR_texture_transform as a 3x3 matrix, column-major) x the
// vertex colour. The pixels are copied at upload.
struct MaterialDesc {
  float base_color[4] = {1.0f, 1.0f, 1.0f, 1.0f};
  const uint8_t* rgba8 = nullptr;  // null: no texture
  int32_t width = 0, height = 0;
  int32_t wrap_s = 10497, wrap_t = 10497;  // GL wrap enums: REPEAT, CLAMP_TO_EDGE, MIRRORED_REPEAT
  float uv_transform[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
};

struct FrameInput {
  const selection::Camera* camera = nullptr;  // its viewport should match the render target
  Span<const glm::mat4> object_world;         // per object: object-to-world matrix
  Span<const uint32_t> object_chain;          // per object: chain index (< uploaded chain count)
  Span<const int8_t> levels;                  // per object: level to draw, -1 = not drawn
  // optional shadow pass: the scene is first drawn (depth only) from `shadow_camera` (orthographic,
  // a directional light looking from its eye to its target) with `shadow_levels` (per object, -1 =
  // casts no shadow), then the frame is lit by that light and shadowed by that map
  const selection::Camera* shadow_camera = nullptr;
  Span<const int8_t> shadow_levels;
  // level transitions (docs/GL.md, "Level transitions"); each span empty or one value per object.
  // Geomorph factor in [0, 1] (empty = 0 for every object): the level is drawn with every vertex's
  // position, normal (renormalised), texture coordinates and colour mixed toward its target in the
  // next level (LodLevel::morph) as (1 - f) x own + f x target; thick edges and points move their
  // vertices' positions likewise. Levels without morph data are drawn unmoved at any factor.
  Span<const float> morph;
  // Cross-fade by screen-door dithering: `fade` in [0, 1] (empty = 1: fully the new level) is the
  // share of the object's pixels drawn with `levels`; the complementary share is drawn with
  // `previous_levels` (empty or -1: nothing), unmorphed, no blending. A 4x4 Bayer threshold of the
  // pixel position decides, so each pixel shows exactly one of the two. Only objects with fade < 1
  // and a previous level other than the new one are drawn twice; with fade < 1 and no previous
  // level (-1) the new level covers only its `fade` share (an object appearing), with level -1 the
  // previous one covers its 1 - fade share (an object leaving). The shadow pass draws only
  // `shadow_levels`, undithered, morphed by `morph` where its level is the object's `levels` entry.
  Span<const int8_t> previous_levels;
  Span<const float> fade;
};

struct FrameResult {
  double measured_ms = 0.0;    // CPU time from the first GL call of the frame to glFinish returning
  uint64_t triangles = 0;      // drawn this frame
  uint64_t edges = 0;
  uint64_t points = 0;
  uint32_t draw_calls = 0;
  uint64_t shadow_triangles = 0;  // drawn into the shadow map (part of measured_ms)
  uint32_t shadow_draw_calls = 0;
  // the previous levels drawn by fading objects (FrameInput::fade < 1); already counted in the
  // totals above, which hold both levels of a fading object
  uint32_t fading_objects = 0;  // objects with fade < 1 (drawn with one or both of their levels)
  uint64_t fade_triangles = 0;
  uint64_t fade_edges = 0;
  uint64_t fade_points = 0;
  uint32_t fade_draw_calls = 0;
};

// Near and far planes for a perspective `camera` drawing what lies inside `bounds`: the planes
// tightest around the sphere along the view direction (with a 1 % margin), the near plane at least
// `min_near` x the radius (the eye inside or close to the sphere). The 24-bit depth buffer resolves
// about (distance^2 / near) / 2^24 at a distance: a near plane fixed at a thousandth of the radius
// leaves a far scene's front and back surfaces in one depth step (both sides are lit: the colour
// flickers as the geometry moves by a hair). Orthographic cameras get the same planes.
void fitDepthPlanes(selection::Camera& camera, const Sphere& bounds, float min_near = 1e-3f);

class Renderer {
 public:
  Renderer();
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Starts EGL, creates an OpenGL 3.3 core context (current on this thread), an RGBA8 + depth FBO of
  // the configured size, and compiles the shaders. On failure returns an error; `*unavailable` (when
  // not null) is set true when the failure is that EGL or an OpenGL 3.3 context cannot start on this
  // machine (the caller may skip), false when it is anything else. Cost: context creation, ~10s of ms.
  Error init(const RendererConfig& config, bool* unavailable = nullptr);

  // A description of the context ("OpenGL 4.5 (Core Profile) Mesa ..., llvmpipe ...") after init.
  std::string description() const;

  // Uploads every level of every chain (one vertex and index buffer per level and primitive kind).
  // Meshes without normals get area-weighted vertex normals. A level with morph targets
  // (LodLevel::morph) gets them beside its vertices (positions, normals, texture coordinate set 0,
  // colours; a missing target array means the vertex's own value, except normals of a level without
  // normals: the normal of the next-level vertex at the target position), doubling its vertex bytes; a
  // level without keeps its own vertex size. Replaces earlier uploads. With
  // `group_materials` (one list per chain, or empty), chain c's triangle group g (edge group, point
  // group) is drawn with material group_materials[c][g] of the last uploadMaterials (-1 or past the
  // list: white), its triangles one draw per group; without, every chain has its own flat colour.
  // Errors: init not done, a level whose indices are out of range, morph target arrays neither empty
  // nor one per vertex, a group material out of range, a GL error (out of memory). Allocates.
  Error uploadChains(const std::vector<LodChain>& chains,
                     const std::vector<std::vector<int32_t>>& group_materials = {});
  // Uploads the materials (textures with mipmaps) that uploadChains' group materials refer to;
  // call before uploadChains. Errors: init not done, a texture without pixels or of a bad size or
  // wrap mode. Allocates.
  Error uploadMaterials(Span<const MaterialDesc> materials);
  size_t chainCount() const;
  size_t gpuBytes() const;  // buffer bytes uploaded

  // Clears and draws the frame into the offscreen target and waits for it (glFinish). Objects with
  // level -1, an out-of-range chain or level are skipped (so is an out-of-range previous level).
  // With a shadow camera, draws the shadow map first (the first such frame creates it). Allocates
  // nothing after that. Returns false (result untouched) before init, on mismatched span sizes
  // (morph, previous_levels and fade must each be empty or as long as levels), a morph factor or
  // fade outside [0, 1] or NaN, a null camera or a shadow camera that is not orthographic, or when
  // the shadow map cannot be made.
  bool drawFrame(const FrameInput& input, FrameResult* result);

  // Reads the last frame back into `out` (rows top to bottom). Errors: init not done.
  Error readPixels(eval::Image& out);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace scenelod::gl
