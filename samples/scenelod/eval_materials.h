#pragma once
// A model's materials and textures for the evaluation renders (eval::Material), converted from
// scene::SceneData, and loading a model as one world-space mesh with them.
#include <memory>
#include <string>
#include <vector>

#include "scenelod/eval/material.h"
#include "scenelod/lodcore/lod_chain.h"
#include "scenelod/lodcore/mesh.h"
#include "scenelod/lodcore/status.h"
#include "scenelod/scene/scene_data.h"

namespace scenelod::tool {

// One eval::Material per SceneData material, in order, so that the material index a flattened mesh
// keeps per triangle (scene::flattenScene) selects it. Textures are held here; the materials point
// at them, so a move keeps them valid and a copy is not allowed.
struct EvalMaterials {
  std::vector<std::unique_ptr<eval::Texture>> textures;  // one per decoded SceneData image (or null)
  std::vector<eval::Material> materials;
  size_t undecoded = 0;  // textured materials drawn untextured: their image was not decoded

  EvalMaterials() = default;
  EvalMaterials(EvalMaterials&&) = default;
  EvalMaterials& operator=(EvalMaterials&&) = default;
  EvalMaterials(const EvalMaterials&) = delete;
  EvalMaterials& operator=(const EvalMaterials&) = delete;

  bool textured() const;  // any material draws a texture
};

// Converts the scene's materials: base colour factor, the base colour texture (its image decoded to
// RGBA8, its sampler's wrap modes), texCoord (KHR_texture_transform's texCoord overrides it) and
// KHR_texture_transform. A texture whose image has no decoded pixels is left out (the material
// draws its factor; `undecoded` counts them). Errors: texture or image indices out of range, an
// image whose pixel buffer does not match its size, naming `what` and the material.
Error evalMaterials(const scene::SceneData& scene, EvalMaterials& out, const std::string& what);

// The materials of one scene mesh's triangle groups (its primitives): entry g draws primitive g
// (MeshData::primitive_materials[g]; a primitive without a material gets the white default).
std::vector<eval::Material> primitiveMaterials(const EvalMaterials& all, const scene::MeshData& mesh);

// Loads OBJ, glTF or GLB as one world-space mesh (like loadFlatMesh) and its materials.
Error loadFlatModel(const std::string& path, Mesh& mesh, EvalMaterials& materials);

// The levels a glTF file holds (MSFT_lod, as `scenelod lods` writes them), each as one world-space
// mesh in `out.levels`: level k draws every mesh at its level k (its last level when it has fewer),
// triangle groups as material indices, with the file's materials. A file without levels is an error.
Error loadStoredLevels(const std::string& path, LodChain& out, EvalMaterials& materials);

}  // namespace scenelod::tool
