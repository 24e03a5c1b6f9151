// Base-colour texture sampling for the evaluation renders: glTF sampler wrap modes, bilinear
// filtering in linear colour, KHR_texture_transform.
#include "scenelod/eval/material.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace scenelod::eval {

namespace {

// sRGB byte -> linear, once for the 256 values
const std::array<float, 256>& srgbToLinearTable() {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) {
      const float c = static_cast<float>(i) / 255.0f;
      t[i] = c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
    }
    return t;
  }();
  return table;
}

// a texel index wrapped into [0, n)
int wrapIndex(int i, int n, Wrap wrap) {
  switch (wrap) {
    case Wrap::kClampToEdge:
      return i < 0 ? 0 : i >= n ? n - 1 : i;
    case Wrap::kMirroredRepeat: {
      const int period = 2 * n;
      int k = i % period;
      if (k < 0) k += period;
      return k < n ? k : period - 1 - k;
    }
    case Wrap::kRepeat:
      break;
  }
  const int k = i % n;
  return k < 0 ? k + n : k;
}

// texel coordinates far outside the image would overflow int: clamping only needs one texel beyond
// either edge, and the repeating modes repeat every 2n texels, so moving by whole periods changes nothing
float reduceCoordinate(float x, int n, Wrap wrap) {
  if (wrap == Wrap::kClampToEdge) return std::clamp(x, -1.0f, static_cast<float>(n));
  if (std::fabs(x) < 1e6f) return x;
  const float period = 2.0f * static_cast<float>(n);
  return x - period * std::floor(x / period);
}

}  // namespace

Wrap wrapFromGl(int32_t gl_enum) {
  if (gl_enum == 33071) return Wrap::kClampToEdge;
  if (gl_enum == 33648) return Wrap::kMirroredRepeat;
  return Wrap::kRepeat;
}

Error validateTexture(const Texture& t, const std::string& what) {
  if (t.width < 1 || t.height < 1 || t.rgba8.size() != static_cast<size_t>(t.width) * t.height * 4)
    return {Status::kInvalidArgument, what + ": texture of " + std::to_string(t.width) + "x" + std::to_string(t.height) +
                                          " pixels has " + std::to_string(t.rgba8.size()) + " bytes, not width x height x 4"};
  return {};
}

glm::mat3 textureTransform(glm::vec2 offset, float rotation, glm::vec2 scale) {
  const float c = std::cos(rotation), s = std::sin(rotation);
  // glm is column-major: m[col][row]; rows of R are (c, s) and (-s, c)
  glm::mat3 t(1.0f), r(1.0f), sc(1.0f);
  t[2] = glm::vec3(offset, 1.0f);
  r[0] = glm::vec3(c, -s, 0.0f);
  r[1] = glm::vec3(s, c, 0.0f);
  sc[0][0] = scale.x;
  sc[1][1] = scale.y;
  return t * r * sc;
}

namespace {

// bilinear filtering between the four texel centres around uv on a w x h grid; `texel(x, y)` gives
// a texel's linear RGBA
template <class Fetch>
glm::vec4 bilinear(glm::vec2 uv, int w, int h, Wrap wrap_s, Wrap wrap_t, const Fetch& texel) {
  if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) uv = glm::vec2(0.0f);
  // texel centres sit at half-integers
  const float x = reduceCoordinate(uv.x * static_cast<float>(w) - 0.5f, w, wrap_s);
  const float y = reduceCoordinate(uv.y * static_cast<float>(h) - 0.5f, h, wrap_t);
  const float fx = std::floor(x), fy = std::floor(y);
  const float ax = x - fx, ay = y - fy;
  const int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
  const int xs[2] = {wrapIndex(x0, w, wrap_s), wrapIndex(x0 + 1, w, wrap_s)};
  const int ys[2] = {wrapIndex(y0, h, wrap_t), wrapIndex(y0 + 1, h, wrap_t)};
  glm::vec4 out(0.0f);
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) out += (i ? ax : 1.0f - ax) * (j ? ay : 1.0f - ay) * texel(xs[i], ys[j]);
  return out;
}

glm::vec4 linearTexel(const Texture& tex, int x, int y) {
  const auto& lin = srgbToLinearTable();
  const uint8_t* p = tex.rgba8.data() + (static_cast<size_t>(y) * tex.width + x) * 4;
  return glm::vec4(lin[p[0]], lin[p[1]], lin[p[2]], static_cast<float>(p[3]) / 255.0f);
}

}  // namespace

glm::vec4 sampleTexture(const Texture& tex, glm::vec2 uv, Wrap wrap_s, Wrap wrap_t) {
  return bilinear(uv, tex.width, tex.height, wrap_s, wrap_t, [&](int x, int y) { return linearTexel(tex, x, y); });
}

FilteredTexture::FilteredTexture(const Texture& texture) : base_(&texture) {
  int w = texture.width, h = texture.height;
  const std::vector<glm::vec4>* prev = nullptr;
  while (w > 1 || h > 1) {
    const int nw = std::max(1, w / 2), nh = std::max(1, h / 2);
    Level next{nw, nh, std::vector<glm::vec4>(static_cast<size_t>(nw) * nh)};
    for (int y = 0; y < nh; ++y)
      for (int x = 0; x < nw; ++x) {
        // the 2 x 2 texels above (one row or column when that side is already 1)
        glm::vec4 sum(0.0f);
        for (int j = 0; j < 2; ++j)
          for (int i = 0; i < 2; ++i) {
            const int sx = std::min(2 * x + i, w - 1), sy = std::min(2 * y + j, h - 1);
            sum += prev ? (*prev)[static_cast<size_t>(sy) * w + sx] : linearTexel(texture, sx, sy);
          }
        next.texels[static_cast<size_t>(y) * nw + x] = 0.25f * sum;
      }
    levels_.push_back(std::move(next));
    prev = &levels_.back().texels;
    w = nw;
    h = nh;
  }
}

glm::vec4 FilteredTexture::sampleLevel(glm::vec2 uv, int level, Wrap wrap_s, Wrap wrap_t) const {
  if (level <= 0) return sampleTexture(*base_, uv, wrap_s, wrap_t);
  const Level& l = levels_[static_cast<size_t>(level - 1)];
  return bilinear(uv, l.width, l.height, wrap_s, wrap_t,
                  [&](int x, int y) { return l.texels[static_cast<size_t>(y) * l.width + x]; });
}

glm::vec4 FilteredTexture::sample(glm::vec2 uv, float lod, Wrap wrap_s, Wrap wrap_t) const {
  const float top = static_cast<float>(levels_.size());
  if (!(lod > 0.0f)) return sampleTexture(*base_, uv, wrap_s, wrap_t);  // NaN too
  if (lod >= top) return sampleLevel(uv, static_cast<int>(top), wrap_s, wrap_t);
  const int lo = static_cast<int>(lod);
  const float t = lod - static_cast<float>(lo);
  return (1.0f - t) * sampleLevel(uv, lo, wrap_s, wrap_t) + t * sampleLevel(uv, lo + 1, wrap_s, wrap_t);
}

glm::vec3 meanTextureColor(const Texture& tex) {
  const auto& lin = srgbToLinearTable();
  glm::dvec3 sum(0.0);
  const size_t n = static_cast<size_t>(tex.width) * static_cast<size_t>(tex.height);
  for (size_t i = 0; i < n && 4 * i + 3 < tex.rgba8.size(); ++i)
    sum += glm::dvec3(lin[tex.rgba8[4 * i]], lin[tex.rgba8[4 * i + 1]], lin[tex.rgba8[4 * i + 2]]);
  return n ? glm::vec3(sum / static_cast<double>(n)) : glm::vec3(1.0f);
}

const std::vector<glm::vec2>* materialUvs(const Mesh& mesh, const Material& material) {
  const std::vector<glm::vec2>* uvs = nullptr;
  if (material.texcoord == 0) uvs = &mesh.uvs;
  else if (material.texcoord <= mesh.extra_uvs.size()) uvs = &mesh.extra_uvs[material.texcoord - 1];
  return uvs && !uvs->empty() && uvs->size() == mesh.vertexCount() ? uvs : nullptr;
}

Error validateMaterials(Span<const Material> materials, const std::string& what) {
  for (size_t i = 0; i < materials.size(); ++i)
    if (materials[i].texture)
      if (Error e = validateTexture(*materials[i].texture, what + ", material " + std::to_string(i)); !e.ok()) return e;
  return {};
}

}  // namespace scenelod::eval
