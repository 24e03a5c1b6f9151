#pragma once
// Private: the colour of a ray hit on one mesh, as renderMesh draws it (render.h): vertex colours,
// or the hit triangle's material with its texture filtered to the pixel's footprint.
#include <cstdint>
#include <map>
#include <memory>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "embree_scene.h"
#include "scenelod/eval/material.h"
#include "scenelod/lodcore/mesh.h"
#include "scenelod/lodcore/span.h"

namespace scenelod::eval::detail {

// One pixel of an orthographic view: the ray direction and the world-space steps from the pixel to
// its neighbours across and down the image.
struct PixelFootprint {
  glm::vec3 dir{0.0f, 0.0f, -1.0f};
  glm::vec3 dx{0.0f}, dy{0.0f};
};

// linear [0, 1] -> 8-bit sRGB
uint8_t toSrgb8(float c);

class Shader {
 public:
  // Prepares the materials' textures for filtering (a mip chain per distinct texture). `mesh` and
  // the materials' textures must outlive the shader.
  Shader(const Mesh& mesh, Span<const Material> materials);

  // Linear base colour of the hit: factor x texture x COLOR_0 with materials, else the hit's colour.
  glm::vec3 baseColor(const RayHit& h, const PixelFootprint& fp) const;

  // Headlight Lambert + ambient of the base colour, as 8-bit sRGB into px[0..2]. Thread-safe.
  void shade(const RayHit& h, const PixelFootprint& fp, float ambient, bool smooth, uint8_t* px) const;

 private:
  const Mesh& mesh_;
  Span<const Material> materials_;
  bool has_colors_ = false;
  std::vector<const std::vector<glm::vec2>*> uvs_;  // per material: its texture coordinates, or null
  std::vector<glm::vec3> fallback_;                 // per material: the texture's mean when uvs_ is null
  std::vector<const FilteredTexture*> filtered_;    // per material: its texture's mip chain, or null
  std::map<const Texture*, std::unique_ptr<FilteredTexture>> chains_;
};

// log2 of a pixel's footprint in texels on triangle (p, t) (t: its corners' texture coordinates):
// the pixel steps moved onto the triangle's plane along the ray, expressed in texture coordinates
// and scaled by the texture's size; the larger of the two axes, as OpenGL's level of detail.
// A triangle seen edge-on gives a large value (the coarsest level), a degenerate one 0.
float footprintLod(const glm::vec3 p[3], const glm::vec2 t[3], const PixelFootprint& fp, int width, int height);

}  // namespace scenelod::eval::detail
