// scenelod render: pictures of a model or of its LOD chain (Embree ray casts).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "args.h"
#include "command.h"
#include "eval_materials.h"
#include "eval_support.h"
#include "progress.h"
#include "scenelod/eval/image.h"
#include "scenelod/eval/render.h"
#include "scenelod/eval/text.h"
#include "scenelod/lodcore/chain.h"

namespace scenelod::tool {
namespace {

const char* kUsage =
    "usage: scenelod render IN -o OUT.png [--view axis|diag N] [--size W H] [--level K | --grid]\n"
    "                       [--show LIST] [--levels N] [--plain] [--stored]\n"
    "\n"
    "Draws IN (OBJ, glTF or GLB, flattened to one world-space mesh) with an orthographic Embree ray\n"
    "cast: headlight Lambert + ambient shading. Triangles of a model with materials show their\n"
    "material's base colour factor x base colour texture (its texCoord set, KHR_texture_transform,\n"
    "the sampler's wrap modes, bilinear) x COLOR_0; a level without that texture coordinate set\n"
    "shows the texture's mean colour. Without materials: vertex colours when present, otherwise grey\n"
    "triangles. Edges are blue capsules of their thickness (at least one pixel), points red.\n"
    "\n"
    "  --view axis N   N in 0..5: seen from +x, -x, +y, -y, +z, -z\n"
    "  --view diag N   N in 0..7: seen from (+-1, +-1, +-1), bits of N = negative x, y, z\n"
    "                  (default: diag 0, seen from (1, 1, 1))\n"
    "  --size W H      image size in pixels (default 512 512; per level with --grid: 256 256)\n"
    "  --level K       build the LOD chain (floating cells, default settings) and draw level K\n"
    "  --grid          build the chain and lay out all its levels side by side, each labelled with\n"
    "                  its triangle, edge and point counts; every level framed like level 0\n"
    "  --show LIST     like --grid, only the listed levels (e.g. 0,2,4,6; each at most 32)\n"
    "  --levels N      simplified levels in the chain (default 8)\n"
    "  --plain         ignore materials and textures: vertex colours (material colours baked in) or\n"
    "                  grey, as without materials\n"
    "  --stored        with --level, --grid or --show: draw the levels IN holds (glTF with MSFT_lod,\n"
    "                  as 'scenelod lods' writes them; every mesh at its level K, or its last level)\n"
    "                  instead of building a chain\n";

// "--view axis 3" and "--size 640 480" take two words: join them so Args sees one value
std::vector<std::string> joinTwoWordOptions(const std::vector<std::string>& in) {
  std::vector<std::string> out;
  for (size_t i = 0; i < in.size(); ++i) {
    if ((in[i] == "--view" || in[i] == "--size") && i + 2 < in.size() && in[i + 2].rfind("-", 0) != 0) {
      out.push_back(in[i]);
      out.push_back(in[i + 1] + " " + in[i + 2]);
      i += 2;
      continue;
    }
    out.push_back(in[i]);
  }
  return out;
}

bool parseView(const std::string& s, eval::View& view, std::string& error) {
  char kind[16] = {0};
  int n = -1;
  if (std::sscanf(s.c_str(), "%15s %d", kind, &n) != 2) {
    error = "--view needs 'axis N' or 'diag N', got '" + s + "'";
    return false;
  }
  const std::string k = kind;
  if (k == "axis" && n >= 0 && n < 6) {
    view = eval::standardView(n);
    return true;
  }
  if (k == "diag" && n >= 0 && n < 8) {
    view = eval::standardView(6 + n);
    return true;
  }
  error = "--view: '" + s + "' is not 'axis 0..5' or 'diag 0..7'";
  return false;
}

void drawLabel(eval::Image& img, int x, int y, const std::string& text) {
  eval::drawText(img, x, y, text, eval::Rgb8{0, 0, 0}, 1);
}

// the levels `shown` side by side, at most 5 per row, each labelled with its level, method, counts
// and cell width
Error drawGrid(const LodChain& chain, const std::vector<int>& shown, const eval::RenderParams& rp, eval::Image& sheet) {
  const int n = static_cast<int>(shown.size());
  const int cols = std::min(n, 5), rows = (n + cols - 1) / cols;
  const int label_h = 3 * (eval::kTextHeight + 3) + 4;
  sheet = eval::Image(cols * rp.width, rows * (rp.height + label_h));
  for (int i = 0; i < n; ++i) {
    const int k = shown[i];
    const LodLevel& lv = chain.levels[k];
    eval::Image tile;
    if (lv.mesh.empty()) {
      tile = eval::Image(rp.width, rp.height);
    } else if (Error e = eval::renderMesh(lv.mesh, rp, tile); !e.ok()) {
      e.message = "level " + std::to_string(k) + ": " + e.message;
      return e;
    }
    const int x = (i % cols) * rp.width, y = (i / cols) * (rp.height + label_h);
    eval::blit(sheet, tile, x, y);
    char line1[96], line2[96], line3[96];
    std::snprintf(line1, sizeof line1, "L%d %s", k, k == 0 ? "original" : lodMethodName(lv.method));
    std::snprintf(line2, sizeof line2, "%zu tris %zu edges %zu pts", lv.mesh.triangleCount(), lv.mesh.edgeCount(),
                  lv.mesh.pointCount());
    std::snprintf(line3, sizeof line3, "cell %.4g", lv.cell_width);
    drawLabel(sheet, x + 4, y + rp.height + 2, line1);
    drawLabel(sheet, x + 4, y + rp.height + 2 + eval::kTextHeight + 3, line2);
    drawLabel(sheet, x + 4, y + rp.height + 2 + 2 * (eval::kTextHeight + 3), line3);
  }
  return {};
}

// "0,2,4,6" as level numbers; false on anything else
bool parseLevelList(const std::string& text, std::vector<int>& out) {
  out.clear();
  size_t pos = 0;
  while (pos <= text.size()) {
    const size_t comma = std::min(text.find(',', pos), text.size());
    const std::string item = text.substr(pos, comma - pos);
    char* end = nullptr;
    const long v = std::strtol(item.c_str(), &end, 10);
    if (item.empty() || *end != '\0' || v < 0 || v > 32) return false;
    out.push_back(static_cast<int>(v));
    pos = comma + 1;
  }
  return !out.empty();
}

int runRender(const std::vector<std::string>& argv) {
  Args args(joinTwoWordOptions(argv), {"--grid", "--plain", "--stored"}, {"--out", "--view", "--size", "--level", "--levels", "--show"});
  long level = -1, levels = 8;
  args.getInt("--level", level);
  args.getInt("--levels", levels);
  if (!args.ok()) return usageError("render", args.error());
  if (args.positional().size() != 1) return usageError("render", "needs one input model");
  if (!args.has("--out")) return usageError("render", "needs -o OUT.png");
  std::vector<int> show;
  if (args.has("--show") && !parseLevelList(args.get("--show"), show))
    return usageError("render", "--show needs levels such as 0,2,4,6, got '" + args.get("--show") + "'");
  const bool grid = args.has("--grid") || !show.empty();
  if (grid && args.has("--level")) return usageError("render", "--grid/--show and --level exclude each other");
  if (args.has("--level") && level < 0) return usageError("render", "--level must be >= 0");
  const bool stored = args.has("--stored");
  if (stored && !grid && !args.has("--level")) return usageError("render", "--stored needs --level, --grid or --show");
  if (stored && (args.has("--plain") || args.has("--levels")))
    return usageError("render", "--stored draws the file's own levels: no --plain or --levels");
  if (levels < 1 || levels > 32) return usageError("render", "--levels must be in [1, 32]");
  eval::RenderParams rp;
  rp.width = rp.height = grid ? 256 : 512;
  if (args.has("--size")) {
    int w = 0, h = 0;
    if (std::sscanf(args.get("--size").c_str(), "%d %d", &w, &h) != 2 || w < 16 || h < 16 || w > 8192 || h > 8192)
      return usageError("render", "--size needs W H in [16, 8192], got '" + args.get("--size") + "'");
    rp.width = w;
    rp.height = h;
  }
  if (args.has("--view")) {
    std::string err;
    if (!parseView(args.get("--view"), rp.view, err)) return usageError("render", err);
  }
  const std::string in = args.positional()[0], out = args.get("--out");

  Mesh mesh;
  EvalMaterials materials;
  LodChain chain;
  if (stored) {
    if (Error e = loadStoredLevels(in, chain, materials); !e.ok()) return runError("render", e.message);
    mesh = chain.levels[0].mesh;
  }
  // --plain: the material colours baked into the vertex colours, as the other tools draw
  const Error load = stored ? Error() : args.has("--plain") ? loadFlatMesh(in, mesh) : loadFlatModel(in, mesh, materials);
  if (!load.ok()) return runError("render", load.message);
  if (mesh.empty()) return runError("render", in + ": the model has no triangles, edges or points");
  rp.materials = materials.materials;
  if (materials.undecoded)
    std::fprintf(stderr, "scenelod render: %s: %zu textured materials drawn untextured (image not decoded)\n",
                 in.c_str(), materials.undecoded);
  if (!grid && !args.has("--level")) {
    eval::Image img;
    if (Error e = eval::renderMesh(mesh, rp, img); !e.ok()) return runError("render", in + ": " + e.message);
    if (Error e = eval::writePng(out, img); !e.ok()) return runError("render", e.message);
    std::printf("wrote %s (%dx%d, %zu triangles, %zu edges, %zu points)\n", out.c_str(), img.width, img.height,
                mesh.triangleCount(), mesh.edgeCount(), mesh.pointCount());
    return 0;
  }

  if (!stored) {
    ChainParams cp;
    long deepest = grid ? levels : std::max<long>(levels, level);
    for (int k : show) deepest = std::max<long>(deepest, k);
    cp.level_count = static_cast<size_t>(deepest);
    ProgressBar bar("building chain");
    cp.progress = bar.callback();
    if (Error e = buildChain(mesh, cp, chain); !e.ok()) return runError("render", in + ": " + e.message);
    bar.finish();
  }
  rp.frame = eval::boundingSphere(chain.levels[0].mesh);  // every level framed like the original
  if (!grid) {
    if (static_cast<size_t>(level) >= chain.levelCount())
      return runError("render", "the chain has " + std::to_string(chain.levelCount()) + " levels, no level " +
                                    std::to_string(level));
    eval::Image img;
    if (Error e = eval::renderMesh(chain.levels[level].mesh, rp, img); !e.ok()) return runError("render", e.message);
    if (Error e = eval::writePng(out, img); !e.ok()) return runError("render", e.message);
    const Mesh& m = chain.levels[level].mesh;
    std::printf("wrote %s: level %ld, cell width %g, %zu triangles, %zu edges, %zu points\n", out.c_str(), level,
                chain.levels[level].cell_width, m.triangleCount(), m.edgeCount(), m.pointCount());
    return 0;
  }
  std::vector<int> shown;
  for (int k = 0; k < static_cast<int>(chain.levelCount()); ++k)
    if (show.empty() || std::find(show.begin(), show.end(), k) != show.end()) shown.push_back(k);
  for (int k : show)
    if (k >= static_cast<int>(chain.levelCount()))
      return runError("render", "--show " + std::to_string(k) + ": the chain has levels 0.." +
                                    std::to_string(chain.levelCount() - 1));
  eval::Image sheet;
  if (Error e = drawGrid(chain, shown, rp, sheet); !e.ok()) return runError("render", e.message);
  if (Error e = eval::writePng(out, sheet); !e.ok()) return runError("render", e.message);
  std::printf("wrote %s: %zu levels\n", out.c_str(), shown.size());
  for (int k : shown)
    std::printf("  level %d: cell width %-10.4g %8zu triangles %8zu edges %8zu points\n", k,
                chain.levels[k].cell_width, chain.levels[k].mesh.triangleCount(), chain.levels[k].mesh.edgeCount(),
                chain.levels[k].mesh.pointCount());
  return 0;
}

CommandRegistration reg({"render", "draw a model or its LOD levels to PNG (Embree ray cast)", kUsage, runRender});

}  // namespace
}  // namespace scenelod::tool
