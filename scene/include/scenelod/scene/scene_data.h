#pragma once
// The raw, mutable description of a scene as it comes from a file or from an engine: nodes with
// local transforms, meshes, materials. Importers fill it, exporters read it, and the runtime scene
// graph (scene.h) is built from it. Plain vectors, easy to fill by hand in tests and tools.
#include <cstdint>
#include <string>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "scenelod/lodcore/mesh.h"
#include "scenelod/lodcore/span.h"
#include "scenelod/lodcore/status.h"

namespace scenelod::scene {

// The material of triangles that have none, in flattenScene's triangle groups (gltf_io.h).
constexpr uint32_t kNoMaterial = 0xffffffffu;

// An image as the file holds it (encoded bytes, kept for export) and decoded to 8-bit RGBA rows
// (top row first; empty when the bytes are not PNG or JPEG or failed to decode).
struct ImageData {
  std::string name;
  std::string mime_type;             // "image/png", "image/jpeg", ...
  std::vector<uint8_t> encoded;      // the file's bytes
  int32_t width = 0, height = 0;
  std::vector<uint8_t> rgba8;        // width x height x 4, sRGB as stored
  // importGltf decodes the images a base colour texture uses; the others keep rgba8 empty
};

// A glTF texture: an image and the sampler's wrap modes (GL enums: 10497 REPEAT, 33071
// CLAMP_TO_EDGE, 33648 MIRRORED_REPEAT).
struct TextureData {
  int32_t image = -1;                // index into SceneData::images, -1 for none
  int32_t wrap_s = 10497, wrap_t = 10497;
};

// KHR_texture_transform of one texture reference: uv' = T(offset) R(rotation) S(scale) uv.
struct TextureTransform {
  glm::vec2 offset{0.0f};
  float rotation = 0.0f;             // radians, counter-clockwise in UV space
  glm::vec2 scale{1.0f};
  int32_t texcoord = -1;             // overrides the reference's set when >= 0
};

struct MaterialData {
  std::string name;
  glm::vec4 base_color{1.0f};             // linear RGBA factor
  bool textured = false;                  // has a base colour texture
  glm::vec3 average_texel_color{1.0f};    // linear RGB mean of the base colour texture (SCROOGE §7.3)
  int32_t base_color_texture = -1;        // index into SceneData::textures, -1 for none
  uint32_t base_color_texcoord = 0;       // which TEXCOORD_n set the texture reads
  TextureTransform base_color_transform;  // identity unless the file has KHR_texture_transform
};

struct MeshData {
  std::string name;
  // every primitive of the glTF mesh merged into one Mesh; mesh.triangle_groups holds each
  // triangle's primitive index (a group per primitive, so that levels keep primitives apart)
  Mesh mesh;
  std::vector<int32_t> primitive_materials;  // material of each source primitive, in order (-1 = none)
};

// A glTF skin: the joint nodes, their inverse bind matrices (identity when the file has none) and
// the optional skeleton root.
struct SkinData {
  std::string name;
  std::vector<int32_t> joints;            // node indices; JOINTS_0 values index this list
  std::vector<glm::mat4> inverse_bind;    // one per joint
  int32_t skeleton = -1;
};

// One animation: samplers (key times and values) and the node properties they drive.
struct AnimationData {
  enum class Path : uint8_t { kTranslation, kRotation, kScale, kWeights };
  enum class Interpolation : uint8_t { kLinear, kStep, kCubicSpline };
  struct Sampler {
    std::vector<float> times;             // seconds, increasing
    std::vector<glm::vec4> values;        // xyz (translation, scale), xyzw (rotation quaternion);
                                          // cubic splines hold in-tangent, value, out-tangent per key;
                                          // morph weights one scalar per element in x (targets per key)
    Interpolation interpolation = Interpolation::kLinear;
  };
  struct Channel {
    int32_t node = -1;
    Path path = Path::kTranslation;
    int32_t sampler = -1;
  };
  std::string name;
  std::vector<Sampler> samplers;
  std::vector<Channel> channels;
};

struct NodeData {
  std::string name;
  int32_t parent = -1;                // -1 for a root
  std::vector<int32_t> children;      // in file order
  glm::mat4 local{1.0f};              // local transform (TRS composed, or the node's matrix)
  int32_t mesh = -1;                  // index into SceneData::meshes, -1 for none
  int32_t skin = -1;                  // index into SceneData::skins, -1 for none
  // a node with a mesh and a skin is drawn by its joints alone: glTF ignores its own transform, so
  // worldTransforms gives it the identity (its bind-pose positions are POSITION as stored)
};

struct SceneData {
  std::vector<NodeData> nodes;
  std::vector<int32_t> roots;         // the default scene's root nodes, in order
  std::vector<MeshData> meshes;
  std::vector<MaterialData> materials;
  std::vector<TextureData> textures;
  std::vector<ImageData> images;
  std::vector<SkinData> skins;
  std::vector<AnimationData> animations;
};

// Checks parent/child links agree, there are no cycles, every node is reachable at most once from the
// roots, mesh, material, texture, image, skin and joint node indices are in range, every mesh is
// valid (validateMesh), the JOINTS_0 of a skinned node's mesh are below its skin's joint count,
// and animation channels target nodes in range. `what` names the source in messages.
Error validateSceneData(const SceneData& scene, const std::string& what);

// The objects of a scene: nodes that have a mesh, numbered depth-first in pre-order from the roots,
// children in order. This numbering is the object numbering of replay files and of `scenelod info`.
std::vector<int32_t> objectNodes(const SceneData& scene);

// World transform of every node (identity parent for roots); nodes not reachable from the roots get
// their chain of parents applied all the same. A node with a mesh and a skin gets the identity
// (glTF 2.0, "Skins": the skinned mesh node's own transform is ignored); its children do not.
std::vector<glm::mat4> worldTransforms(const SceneData& scene);
// The same from the given local transforms, one per node (a pose: skin_pose.h's animatedLocals).
std::vector<glm::mat4> worldTransforms(const SceneData& scene, Span<const glm::mat4> locals);

// The colours the importer baked before materials were kept, for consumers that draw a mesh by
// vertex colour alone (SCROOGE's texture averaging, the GL viewer, OBJ output): per vertex, the
// material's base colour factor x its base colour texture's mean texel (linear, when decoded) x
// COLOR_0 (white when absent), the material being that of a triangle group using the vertex
// (their edge or point group's for vertices of edges and points alone). A mesh gets colours when it has
// COLOR_0 or any primitive a material; the others are returned empty. Cost: linear in the mesh.
std::vector<glm::vec3> bakedMaterialColors(const SceneData& scene, const MeshData& mesh);

// Replaces every mesh's colours by bakedMaterialColors: the scene as the importer gave it before
// materials were kept (the material references stay).
void bakeMaterialColors(SceneData& scene);

}  // namespace scenelod::scene
