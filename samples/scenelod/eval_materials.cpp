#include "eval_materials.h"

#include <algorithm>

#include "eval_support.h"
#include "scenelod/scene/gltf_io.h"

namespace scenelod::tool {

bool EvalMaterials::textured() const {
  for (const eval::Material& m : materials)
    if (m.texture) return true;
  return false;
}

Error evalMaterials(const scene::SceneData& scene, EvalMaterials& out, const std::string& what) {
  out = EvalMaterials{};
  for (size_t i = 0; i < scene.images.size(); ++i) {
    const scene::ImageData& img = scene.images[i];
    if (img.rgba8.empty()) {
      out.textures.emplace_back();
      continue;
    }
    auto t = std::make_unique<eval::Texture>();
    t->width = img.width;
    t->height = img.height;
    t->rgba8 = img.rgba8;
    if (Error e = eval::validateTexture(*t, what + ", image " + std::to_string(i) + " '" + img.name + "'"); !e.ok())
      return e;
    out.textures.push_back(std::move(t));
  }
  for (size_t i = 0; i < scene.materials.size(); ++i) {
    const scene::MaterialData& src = scene.materials[i];
    const std::string name = what + ", material " + std::to_string(i) + " '" + src.name + "'";
    eval::Material m;
    m.base_color = src.base_color;
    if (src.base_color_texture >= 0) {
      if (static_cast<size_t>(src.base_color_texture) >= scene.textures.size())
        return {Status::kInvalidArgument, name + ": base colour texture " + std::to_string(src.base_color_texture) +
                                              " is out of range (" + std::to_string(scene.textures.size()) + " textures)"};
      const scene::TextureData& tex = scene.textures[static_cast<size_t>(src.base_color_texture)];
      if (tex.image >= 0 && static_cast<size_t>(tex.image) >= scene.images.size())
        return {Status::kInvalidArgument, name + ": its texture's image " + std::to_string(tex.image) +
                                              " is out of range (" + std::to_string(scene.images.size()) + " images)"};
      m.texture = tex.image >= 0 ? out.textures[static_cast<size_t>(tex.image)].get() : nullptr;
      if (!m.texture) ++out.undecoded;
      m.wrap_s = eval::wrapFromGl(tex.wrap_s);
      m.wrap_t = eval::wrapFromGl(tex.wrap_t);
      const scene::TextureTransform& tt = src.base_color_transform;
      m.texcoord = tt.texcoord >= 0 ? static_cast<uint32_t>(tt.texcoord) : src.base_color_texcoord;
      m.uv_transform = eval::textureTransform(tt.offset, tt.rotation, tt.scale);
    }
    out.materials.push_back(m);
  }
  return {};
}

std::vector<eval::Material> primitiveMaterials(const EvalMaterials& all, const scene::MeshData& mesh) {
  std::vector<eval::Material> out;
  for (int32_t m : mesh.primitive_materials)
    out.push_back(m >= 0 && static_cast<size_t>(m) < all.materials.size() ? all.materials[static_cast<size_t>(m)]
                                                                         : eval::Material{});
  return out;
}

Error loadFlatModel(const std::string& path, Mesh& mesh, EvalMaterials& materials) {
  scene::SceneData scene;
  if (Error e = loadSceneFile(path, scene); !e.ok()) return e;
  mesh = scene::flattenScene(scene);
  if (Error e = validateMesh(mesh, path); !e.ok()) return e;
  return evalMaterials(scene, materials, path);
}

// the levels a glTF file holds (MSFT_lod), each as one world-space mesh: level k draws every mesh
// at its level k (its last level when it has fewer), triangle groups as material indices
Error loadStoredLevels(const std::string& path, LodChain& out, EvalMaterials& materials) {
  scene::SceneData s;
  std::vector<LodChain> chains;
  if (Error e = scene::importGltfLods(path, s, chains); !e.ok()) return e;
  size_t deepest = 1;
  for (const LodChain& c : chains) deepest = std::max(deepest, c.levelCount());
  if (deepest < 2) return {Status::kInvalidArgument, path + ": holds no LOD levels (no MSFT_lod): --stored draws stored levels"};
  out = LodChain{};
  for (size_t k = 0; k < deepest; ++k) {
    scene::SceneData at = s;
    LodLevel level;
    for (size_t m = 0; m < chains.size(); ++m) {
      const LodLevel& l = chains[m].levels[std::min(k, chains[m].levelCount() - 1)];
      at.meshes[m].mesh = l.mesh;
      if (k < chains[m].levelCount() && chains[m].levelCount() > 1) {
        level.method = l.method;
        level.cell_width = std::max(level.cell_width, l.cell_width);
      }
    }
    level.mesh = scene::flattenScene(at);
    out.levels.push_back(std::move(level));
  }
  return evalMaterials(s, materials, path);
}

}  // namespace scenelod::tool
