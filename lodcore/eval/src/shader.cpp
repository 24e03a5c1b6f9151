// Hit colours for the evaluation renders: materials, textures filtered like a GPU's trilinear
// mipmapping (OpenGL 4.6 §8.14, level of detail from the pixel's footprint in texels).
#include "shader.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>

namespace scenelod::eval::detail {

uint8_t toSrgb8(float c) {
  c = std::clamp(c, 0.0f, 1.0f);
  const float s = c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
  return static_cast<uint8_t>(std::lround(s * 255.0f));
}

float footprintLod(const glm::vec3 p[3], const glm::vec2 t[3], const PixelFootprint& fp, int width, int height) {
  constexpr float kEdgeOn = 64.0f;  // beyond any texture's level count
  const glm::vec3 e1 = p[1] - p[0], e2 = p[2] - p[0], n = glm::cross(e1, e2);
  const float g11 = glm::dot(e1, e1), g12 = glm::dot(e1, e2), g22 = glm::dot(e2, e2);
  const float det = g11 * g22 - g12 * g12;
  if (!(det > 0.0f)) return 0.0f;
  const float dn = glm::dot(fp.dir, n);
  if (std::fabs(dn) <= 1e-6f * std::sqrt(det)) return kEdgeOn;
  const glm::vec2 t1 = t[1] - t[0], t2 = t[2] - t[0];
  auto texels = [&](const glm::vec3& step) {
    // the step slid along the ray onto the plane, then in the triangle's edge coordinates
    const glm::vec3 v = step - fp.dir * (glm::dot(step, n) / dn);
    const float b1 = glm::dot(v, e1), b2 = glm::dot(v, e2);
    const float a = (g22 * b1 - g12 * b2) / det, b = (g11 * b2 - g12 * b1) / det;
    const glm::vec2 d = a * t1 + b * t2;
    return glm::length(glm::vec2(d.x * static_cast<float>(width), d.y * static_cast<float>(height)));
  };
  const float rho = std::max(texels(fp.dx), texels(fp.dy));
  return rho > 0.0f && std::isfinite(rho) ? std::min(std::log2(rho), kEdgeOn) : 0.0f;
}

Shader::Shader(const Mesh& mesh, Span<const Material> materials) : mesh_(mesh), materials_(materials) {
  has_colors_ = mesh.colors.size() == mesh.vertexCount();
  for (const Material& m : materials) {
    const std::vector<glm::vec2>* uvs = m.texture ? materialUvs(mesh, m) : nullptr;
    uvs_.push_back(uvs);
    // without its coordinates a textured material shows what it looks like from afar
    fallback_.push_back(m.texture && !uvs ? meanTextureColor(*m.texture) : glm::vec3(1.0f));
    const FilteredTexture* f = nullptr;
    if (uvs) {
      auto& chain = chains_[m.texture];
      if (!chain) chain = std::make_unique<FilteredTexture>(*m.texture);
      f = chain.get();
    }
    filtered_.push_back(f);
  }
}

glm::vec3 Shader::baseColor(const RayHit& h, const PixelFootprint& fp) const {
  if (h.kind != 0 || materials_.empty()) return h.color;
  const glm::vec3 color0 = has_colors_ ? h.color : glm::vec3(1.0f);
  const uint32_t group = mesh_.triangleGroup(h.prim);
  if (group >= materials_.size()) return color0;  // no material: white
  const Material& m = materials_[group];
  const glm::vec3 c = glm::vec3(m.base_color) * color0;
  if (!m.texture) return c;
  const std::vector<glm::vec2>* uvs = uvs_[group];
  if (!uvs) return c * fallback_[group];
  const uint32_t* tri = mesh_.triangles.data() + 3 * static_cast<size_t>(h.prim);
  glm::vec3 p[3];
  glm::vec2 t[3];
  for (int k = 0; k < 3; ++k) {
    p[k] = mesh_.positions[tri[k]];
    t[k] = glm::vec2(m.uv_transform * glm::vec3((*uvs)[tri[k]], 1.0f));
  }
  const glm::vec2 uv = (1.0f - h.u - h.v) * t[0] + h.u * t[1] + h.v * t[2];
  const float lod = footprintLod(p, t, fp, m.texture->width, m.texture->height);
  return c * glm::vec3(filtered_[group]->sample(uv, lod, m.wrap_s, m.wrap_t));
}

void Shader::shade(const RayHit& h, const PixelFootprint& fp, float ambient, bool smooth, uint8_t* px) const {
  const glm::vec3 n = smooth ? h.shading : h.normal;
  const float lambert = std::max(0.0f, glm::dot(n, -fp.dir));
  const glm::vec3 c = baseColor(h, fp) * (ambient + (1.0f - ambient) * lambert);
  px[0] = toSrgb8(c.x);
  px[1] = toSrgb8(c.y);
  px[2] = toSrgb8(c.z);
}

}  // namespace scenelod::eval::detail
