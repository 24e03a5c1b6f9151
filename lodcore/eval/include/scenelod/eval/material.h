#pragma once
// Base-colour materials and textures for the evaluation renders: just what a picture needs to show
// a textured model (factor x texture(uv) x COLOR_0), with glTF's conventions for texture
// coordinates (u right, v down, (0, 0) the top-left corner of the image), sampler wrap modes and
// KHR_texture_transform. The tool converts scene::SceneData materials into these, so the
// evaluation library does not depend on the scene library.
//
// A triangle's material is `materials[mesh.triangleGroup(t)]`; a group with no entry (such as
// scene::kNoMaterial, 0xffffffff) is drawn with the default material: white, untextured.
#include <cstdint>
#include <string>
#include <vector>

#include <glm/mat3x3.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "scenelod/lodcore/mesh.h"
#include "scenelod/lodcore/span.h"
#include "scenelod/lodcore/status.h"

namespace scenelod::eval {

// Sampler wrap modes (glTF / OpenGL: REPEAT 10497, CLAMP_TO_EDGE 33071, MIRRORED_REPEAT 33648).
enum class Wrap : uint8_t { kRepeat, kClampToEdge, kMirroredRepeat };

// The wrap mode of an OpenGL enum; any other value gives kRepeat, glTF's default.
Wrap wrapFromGl(int32_t gl_enum);

// An 8-bit RGBA image as decoded from a file: rows top to bottom, sRGB colour (alpha linear).
struct Texture {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgba8;  // width * height * 4 bytes
};

// Checks the pixel buffer matches the size (both at least 1). `what` names the texture in the message.
Error validateTexture(const Texture& texture, const std::string& what);

// KHR_texture_transform as a matrix: uv' = (M * (u, v, 1)).xy with M = T(offset) R(rotation)
// S(scale), the rotation turning UVs counter-clockwise in the image (which v points down in), so
// offset (0, 1), rotation pi/2, scale 0.5 maps the unit square onto the image's lower-left quadrant
// as the extension's example says.
glm::mat3 textureTransform(glm::vec2 offset, float rotation, glm::vec2 scale);

// Linear RGBA of the texture at `uv`, bilinear between the four nearest texel centres, texel
// indices outside the image wrapped per axis. sRGB texels are made linear before filtering.
// Precondition: validateTexture(texture) passes. Cost: 4 texel reads, no allocation.
glm::vec4 sampleTexture(const Texture& texture, glm::vec2 uv, Wrap wrap_s, Wrap wrap_t);

// A texture filtered for minification (trilinear, as a GPU does with mipmaps): the texture and its
// mip levels, each half the size of the one before (at least 1 texel), box-filtered in linear colour.
// Keeps a pointer to `texture`, which must outlive it. Cost of building: one pass over the texels,
// a third of the texture's size again in floats (16 bytes per texel).
class FilteredTexture {
 public:
  explicit FilteredTexture(const Texture& texture);

  // Linear RGBA at `uv` for a pixel whose footprint is 2^lod texels of the full-size texture:
  // lod <= 0 samples the texture bilinearly (sampleTexture), larger values blend the two nearest
  // levels, beyond the last level its single texel. Thread-safe.
  glm::vec4 sample(glm::vec2 uv, float lod, Wrap wrap_s, Wrap wrap_t) const;

  int levelCount() const { return static_cast<int>(levels_.size()) + 1; }

 private:
  struct Level {
    int width = 0, height = 0;
    std::vector<glm::vec4> texels;  // linear RGBA
  };
  glm::vec4 sampleLevel(glm::vec2 uv, int level, Wrap wrap_s, Wrap wrap_t) const;

  const Texture* base_;
  std::vector<Level> levels_;  // levels 1, 2, ... (level 0 is the texture itself)
};

// Mean linear RGB of all texels (what a model shows from afar, and what a textured material is
// drawn with on a mesh that lacks its texture coordinates). Cost: one pass over the texels.
glm::vec3 meanTextureColor(const Texture& texture);

struct Material {
  glm::vec4 base_color{1.0f};        // linear RGBA factor (alpha is not drawn)
  const Texture* texture = nullptr;  // base colour texture, null for none; must outlive the render
  uint32_t texcoord = 0;             // the set it reads: 0 = Mesh::uvs, k = Mesh::extra_uvs[k - 1]
  glm::mat3 uv_transform{1.0f};      // applied to the set's coordinates (textureTransform)
  Wrap wrap_s = Wrap::kRepeat;
  Wrap wrap_t = Wrap::kRepeat;
};

// The texture coordinates `material` reads on `mesh`, or null when the mesh lacks that set.
const std::vector<glm::vec2>* materialUvs(const Mesh& mesh, const Material& material);

// Checks every textured material's texture (validateTexture). `what` names the material list.
Error validateMaterials(Span<const Material> materials, const std::string& what);

}  // namespace scenelod::eval
