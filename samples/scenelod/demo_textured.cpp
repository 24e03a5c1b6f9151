#include "demo_textured.h"

#include <algorithm>
#include <cstdio>

#include "eval_materials.h"
#include "scenelod/eval/image.h"
#include "scenelod/eval/render.h"
#include "scenelod/eval/text.h"

namespace scenelod::tool {

namespace {

constexpr int kTile = 192;         // picture tile size, pixels
constexpr size_t kColumns = 5;     // levels 0..4 in the picture

std::string fmt(const char* f, double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

// the meshes shown in the picture: a few kinds of part and the organic mesh (the last one)
std::vector<size_t> pictureMeshes(const scene::SceneData& data) {
  std::vector<size_t> out;
  for (const char* name : {"gear_24", "bracket", "bolt"})
    for (size_t m = 0; m < data.meshes.size(); ++m)
      if (data.meshes[m].name == name) out.push_back(m);
  if (!data.meshes.empty() && std::find(out.begin(), out.end(), data.meshes.size() - 1) == out.end())
    out.push_back(data.meshes.size() - 1);
  return out;
}

Error drawPicture(const scene::SceneData& data, const scene::SceneLods& lods, const EvalMaterials& all,
                  const std::string& path) {
  const std::vector<size_t> meshes = pictureMeshes(data);
  const int label_h = eval::kTextHeight + 6;
  eval::Image sheet(static_cast<int>(kColumns) * kTile, static_cast<int>(meshes.size()) * (kTile + label_h));
  for (size_t row = 0; row < meshes.size(); ++row) {
    const LodChain& chain = lods.chains[meshes[row]];
    const std::vector<eval::Material> mats = primitiveMaterials(all, data.meshes[meshes[row]]);
    eval::RenderParams rp;
    rp.width = rp.height = kTile;
    rp.materials = mats;
    rp.frame = eval::boundingSphere(chain.levels[0].mesh);
    for (size_t k = 0; k < std::min(kColumns, chain.levelCount()); ++k) {
      const Mesh& level = chain.levels[k].mesh;
      eval::Image tile(kTile, kTile);
      if (!level.empty())
        if (Error e = eval::renderMesh(level, rp, tile); !e.ok()) return e;
      const int x = static_cast<int>(k) * kTile, y = static_cast<int>(row) * (kTile + label_h);
      eval::blit(sheet, tile, x, y);
      const std::string label = data.meshes[meshes[row]].name + " L" + std::to_string(k) + ": " +
                                std::to_string(level.triangleCount()) + " tris";
      eval::drawText(sheet, x + 4, y + kTile + 3, label, eval::Rgb8{0, 0, 0}, 1);
    }
  }
  return eval::writePng(path, sheet);
}

}  // namespace

Error writeTexturedLevels(const scene::SceneData& data, const scene::SceneLods& lods, const std::string& out_dir,
                          int resolution, TexturedLevelsResult& out) {
  EvalMaterials all;
  if (Error e = evalMaterials(data, all, "demo scene"); !e.ok()) return e;
  size_t max_levels = 0;
  for (const LodChain& c : lods.chains) max_levels = std::max(max_levels, c.levelCount());
  std::string header = "| mesh |", rule = "|---|";
  for (size_t k = 1; k < max_levels; ++k) {
    header += " L" + std::to_string(k) + " |";
    rule += "---:|";
  }
  std::string off_table = header + "\n" + rule + "\n", sil_table = off_table;
  double worst_l1 = 0.0;
  size_t measured = 0;
  for (size_t m = 0; m < lods.chains.size(); ++m) {
    const LodChain& chain = lods.chains[m];
    const std::vector<eval::Material> mats = primitiveMaterials(all, data.meshes[m]);
    off_table += "| " + data.meshes[m].name + " |";
    sil_table += "| " + data.meshes[m].name + " |";
    for (size_t k = 1; k < max_levels; ++k) {
      if (k >= chain.levelCount() || chain.levels[k].mesh.empty()) {
        off_table += " |";
        sil_table += " |";
        continue;
      }
      eval::ImageErrorParams ip;
      ip.resolution = resolution;
      ip.original_materials = mats;
      ip.simplified_materials = mats;
      eval::ImageErrorResult r;
      if (Error e = eval::measureImageError(chain.levels[0].mesh, chain.levels[k].mesh, ip, r); !e.ok()) {
        e.message = "demo scene, mesh " + data.meshes[m].name + ", level " + std::to_string(k) + ": " + e.message;
        return e;
      }
      // no pixel covered by both (the level fell apart into a few edges or points): no colour to compare
      off_table += r.both_px ? " " + fmt("%.1f", 100.0 * r.color_off) + " (" + fmt("%.1f", r.color_mad) + ") |" : " - |";
      sil_table += " " + fmt("%.1f", 100.0 * r.silhouette) + " |";
      if (k == 1) worst_l1 = std::max(worst_l1, r.color_off);
      ++measured;
    }
    off_table += "\n";
    sil_table += "\n";
  }
  if (Error e = drawPicture(data, lods, all, out_dir + "/textured_levels.png"); !e.ok()) return e;
  out.markdown =
      "\n## Textured levels\n\nThe parts carry texture coordinates and a texture made in code (a checker, and a "
      "\"SCENELOD\" label through KHR_texture_transform), tinted by their vertex colours; the shafts, pipes and rods "
      "stay untextured (texture coordinates would have their repeated seam vertices welded and change their chains). "
      "Each level is drawn with its "
      "material (`scenelod render`'s Embree ray cast: base colour factor x texture x COLOR_0, headlight shading) "
      "from the 14 standard views at " + std::to_string(resolution) + " x " + std::to_string(resolution) +
      " pixels, framed like level 0, and compared with level 0 (`scenelod eval --image`).\n\n"
      "![textured levels](textured_levels.png)\n\n"
      "Colour error per level: the share of the pixels both cover whose colour differs by more than " +
      std::to_string(eval::kColorTolerance) + "/255 in a channel, in %, and in brackets the mean absolute "
      "difference in 8-bit levels; - where no pixel is covered by both.\n\n" + off_table +
      "\nSilhouette mismatch per level (pixels covered by one of the two over pixels covered by either), %:\n\n" +
      sil_table;
  out.summary_line = "textured image error: " + std::to_string(measured) + " levels measured, level 1 at most " +
                     fmt("%.1f", 100.0 * worst_l1) + " % of pixels off by > 16/255 (textured_levels.png)";
  return {};
}

}  // namespace scenelod::tool
