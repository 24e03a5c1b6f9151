// scenelod eval: geometric and image error between an original and a simplified model.
#include <cstdio>
#include <string>
#include <vector>

#include "args.h"
#include "command.h"
#include "eval_animated.h"
#include "eval_materials.h"
#include "eval_support.h"
#include "scenelod/eval/metrics.h"
#include "scenelod/eval/render.h"
#include "scenelod/lodcore/chain.h"

namespace scenelod::tool {
namespace {

const char* kUsage =
    "usage: scenelod eval ORIGINAL SIMPLIFIED [--image] [--json] [--samples N] [--resolution N] [--force]\n"
    "       scenelod eval MODEL --chain [--image [--at-switch K|all]] [--levels N] [--pixels X] [--json]\n"
    "                                   [--nested | --independent]\n"
    "                                   [--samples N] [--resolution N]\n"
    "       scenelod eval MODEL --animated [LEVEL...] [--levels N] [--json] [--samples N]\n"
    "\n"
    "Measures how far SIMPLIFIED is from ORIGINAL (OBJ, glTF or GLB; each flattened to one\n"
    "world-space mesh):\n"
    "  hausdorff   symmetric Hausdorff distance, relative to the original's bounding-box diagonal\n"
    "  rms         symmetric RMS distance (the larger of the two one-sided RMS), same unit\n"
    "  silhouette  pixels covered by exactly one model over pixels covered by either, 14 views\n"
    "  normal_deg  mean angle between the normals where both are hit, degrees\n"
    "Edges of thickness t count as capsules of radius t/2, points as spheres of radius 0.\n"
    "\n"
    "  --json           print one JSON object instead of the table\n"
    "  --samples N      area samples per surface (default 100000; all vertices are added)\n"
    "  --resolution N   pixels across each of the 14 orthographic views (default 256)\n"
    "  --force          measure even when the bounding boxes differ by more than 10x\n"
    "  --image          textured image error: both drawn with their materials (base colour factor x\n"
    "                   texture x COLOR_0, headlight shading, as `scenelod render`), and over the\n"
    "                   pixels both cover, the share off by more than 16/255 in any channel and the\n"
    "                   mean absolute difference (8-bit levels); the silhouette mismatch stays apart\n"
    "  --stored-level K SIMPLIFIED is a file with LOD levels (MSFT_lod, as `scenelod lods` writes):\n"
    "                   measure its level K (every mesh at level K, or its last), with its materials\n"
    "\n"
    "With --chain, builds MODEL's LOD chain (buildChain, default settings, --levels simplified levels,\n"
    "default 8; --nested or --independent: how its clustering levels are built) and prints per level\n"
    "its counts, cell width, Hausdorff and RMS against level 0, and\n"
    "per transition the popping: the image error between levels k and k+1 at the distance where the\n"
    "selector switches (cell width of k+1 = X pixels, --pixels X, default 1). With --image, also per\n"
    "level the textured image error against level 0, each level framed at --resolution; with\n"
    "--at-switch K (or all), level K (every level) is seen instead where the selector switches to\n"
    "it: one pixel is cell width / X, so the window around level 0's bounding sphere (radius r) is\n"
    "2 r X / cell width pixels across (clamped to [8, 1024]), as a perspective camera at that\n"
    "distance shows it.\n"
    "\n"
    "With --animated, builds the chain of every mesh MODEL draws with a skin (as --chain does) and\n"
    "poses the original and each level (the LEVEL indices given, else all) at 16 evenly spaced times\n"
    "of every animation; prints per level the bind-pose Hausdorff and the worst posed one. A level\n"
    "without joints and weights is reported as carrying no skin and is not posed.\n";

struct ChainOptions {
  long levels = 8;
  double pixels = 1.0;
  size_t samples = 100000;
  int resolution = 256;
  bool json = false;
  bool image = false;
  int nesting = -1;  // -1: the default; 0 independent; 1 nested
  long at_switch = -1;  // -1: frame every level at `resolution`; 0: every level at its switch; K: level K only
};

// the textured image error of one level against level 0
struct LevelImage {
  bool measured = false;
  int resolution = 0;
  eval::ImageErrorResult error;
};

Error measureLevelImages(const LodChain& chain, const EvalMaterials& materials, const ChainOptions& o,
                         std::vector<LevelImage>& out) {
  out.assign(chain.levelCount(), LevelImage{});
  const Sphere frame = eval::boundingSphere(chain.levels[0].mesh);
  for (size_t k = 1; k < chain.levelCount(); ++k) {
    const LodLevel& lv = chain.levels[k];
    if (lv.mesh.empty() || (o.at_switch > 0 && static_cast<size_t>(o.at_switch) != k)) continue;
    eval::ImageErrorParams ip;
    ip.frame = frame;
    ip.resolution = o.at_switch < 0 ? o.resolution
                                    : eval::switchResolution(frame, lv.cell_width, static_cast<float>(o.pixels), 8, 1024);
    ip.original_materials = materials.materials;
    ip.simplified_materials = materials.materials;
    if (Error e = eval::measureImageError(chain.levels[0].mesh, lv.mesh, ip, out[k].error); !e.ok()) {
      e.message = "level " + std::to_string(k) + ": " + e.message;
      return e;
    }
    out[k].measured = true;
    out[k].resolution = ip.resolution;
  }
  return {};
}

void printChainJson(const std::string& path, const LodChain& chain, const ChainOptions& o,
                    const std::vector<eval::DistanceResult>& dist, const std::vector<LevelImage>& images,
                    const std::vector<eval::PoppingTransition>& pops) {
  std::printf("{\"model\": %s, \"pixels_per_cell\": %s, \"levels\": [", jsonString(path).c_str(),
              jsonNumber(o.pixels).c_str());
  for (size_t k = 0; k < chain.levelCount(); ++k) {
    const LodLevel& lv = chain.levels[k];
    std::printf("%s{\"level\": %zu, \"cell_width\": %s, \"triangles\": %zu, \"edges\": %zu, \"points\": %zu, "
                "\"hausdorff\": %s, \"rms\": %s",
                k ? ", " : "", k, jsonNumber(lv.cell_width).c_str(), lv.mesh.triangleCount(), lv.mesh.edgeCount(),
                lv.mesh.pointCount(), jsonNumber(dist[k].hausdorff).c_str(), jsonNumber(dist[k].rms).c_str());
    if (images[k].measured) {
      const eval::ImageErrorResult& im = images[k].error;
      std::printf(", \"image_resolution\": %d, \"silhouette\": %s, \"color_off\": %s, \"color_mad\": %s",
                  images[k].resolution, jsonNumber(im.silhouette).c_str(), jsonNumber(im.color_off).c_str(),
                  jsonNumber(im.color_mad).c_str());
    }
    std::printf("}");
  }
  std::printf("], \"popping\": [");
  for (size_t i = 0; i < pops.size(); ++i)
    std::printf("%s{\"from\": %zu, \"to\": %zu, \"resolution\": %d, \"silhouette\": %s, \"normal_deg\": %s}",
                i ? ", " : "", pops[i].from_level, pops[i].to_level, pops[i].resolution,
                jsonNumber(pops[i].error.silhouette).c_str(), jsonNumber(pops[i].error.normal_deg).c_str());
  std::printf("]}\n");
}

void printChainTable(const std::string& path, const LodChain& chain, const ChainOptions& o,
                     const std::vector<eval::DistanceResult>& dist, const std::vector<LevelImage>& images,
                     const std::vector<eval::PoppingTransition>& pops) {
  std::printf("%s: chain of %zu levels; errors in %% of level 0's diagonal\n", path.c_str(), chain.levelCount());
  std::printf("%6s %12s %10s %9s %9s %11s %9s", "level", "cell width", "triangles", "edges", "points", "hausdorff",
              "rms");
  if (o.image) std::printf(" %9s %11s %11s %10s", "image px", "silhouette", "colour off", "colour MAD");
  std::printf("\n");
  for (size_t k = 0; k < chain.levelCount(); ++k) {
    const LodLevel& lv = chain.levels[k];
    std::printf("%6zu %12.5g %10zu %9zu %9zu %10.4f%% %8.4f%%", k, lv.cell_width, lv.mesh.triangleCount(),
                lv.mesh.edgeCount(), lv.mesh.pointCount(), 100.0 * dist[k].hausdorff, 100.0 * dist[k].rms);
    if (images[k].measured) {
      const eval::ImageErrorResult& im = images[k].error;
      std::printf(" %9d %10.4f%% %10.4f%% %10.3f", images[k].resolution, 100.0 * im.silhouette, 100.0 * im.color_off,
                  im.color_mad);
    }
    std::printf("\n");
  }
  if (o.image)
    std::printf("\nimage columns: level k against level 0, textured, %d views, %s; colour off = share of the\n"
                "pixels both cover differing by more than %d/255 in a channel, colour MAD in 8-bit levels\n",
                eval::kStandardViewCount, o.at_switch < 0 ? "framed like level 0" : "at the level's switch distance",
                eval::kColorTolerance);
  std::printf("\npopping at the switch distance (cell width = %g pixels), 14 views:\n", o.pixels);
  std::printf("%10s %12s %12s %12s\n", "switch", "image px", "silhouette", "normal deg");
  for (const auto& p : pops)
    std::printf("%5zu->%-4zu %12d %11.4f%% %12.3f\n", p.from_level, p.to_level, p.resolution,
                100.0 * p.error.silhouette, p.error.normal_deg);
}

int runChain(const std::string& path, const ChainOptions& o) {
  Mesh mesh;
  EvalMaterials materials;
  if (Error e = loadFlatModel(path, mesh, materials); !e.ok()) return runError("eval", e.message);
  if (mesh.triangleCount() == 0)
    return runError("eval", path + ": the model has no triangles; the error is measured against its surface");
  LodChain chain;
  ChainParams cp;
  cp.level_count = static_cast<size_t>(o.levels);
  if (o.nesting >= 0) cp.nested = o.nesting == 1;
  if (Error e = buildChain(mesh, cp, chain); !e.ok()) return runError("eval", path + ": " + e.message);
  if (o.at_switch > 0 && static_cast<size_t>(o.at_switch) >= chain.levelCount())
    return runError("eval", path + ": --at-switch " + std::to_string(o.at_switch) + ", but the chain has levels 0.." +
                                std::to_string(chain.levelCount() - 1));
  std::vector<eval::DistanceResult> dist(chain.levelCount());
  eval::DistanceParams dp;
  dp.area_sample_count = o.samples;
  for (size_t k = 1; k < chain.levelCount(); ++k) {
    if (chain.levels[k].mesh.empty()) continue;
    if (Error e = eval::measureSurfaceDistance(chain.levels[0].mesh, chain.levels[k].mesh, dp, dist[k]); !e.ok())
      return runError("eval", path + ", level " + std::to_string(k) + ": " + e.message);
  }
  std::vector<LevelImage> images(chain.levelCount());
  if (o.image)
    if (Error e = measureLevelImages(chain, materials, o, images); !e.ok()) return runError("eval", path + ", " + e.message);
  eval::PoppingParams pp;
  pp.pixels_per_cell = static_cast<float>(o.pixels);
  std::vector<eval::PoppingTransition> pops;
  if (chain.levelCount() >= 2)
    if (Error e = eval::measurePopping(chain, pp, pops); !e.ok()) return runError("eval", path + ": " + e.message);
  if (o.json) printChainJson(path, chain, o, dist, images, pops);
  else printChainTable(path, chain, o, dist, images, pops);
  return 0;
}

int runEval(const std::vector<std::string>& argv) {
  Args args(argv, {"--json", "--force", "--chain", "--image", "--animated", "--nested", "--independent"},
            {"--samples", "--resolution", "--levels", "--pixels", "--at-switch", "--stored-level"});
  long samples = 100000, resolution = 256, levels = 8;
  double pixels = 1.0;
  args.getInt("--samples", samples);
  args.getInt("--resolution", resolution);
  args.getInt("--levels", levels);
  args.getDouble("--pixels", pixels);
  if (!args.ok()) return usageError("eval", args.error());
  const bool image = args.has("--image");
  if (samples < 1 || samples > 100000000) return usageError("eval", "--samples must be in [1, 1e8]");
  if (resolution < 1 || resolution > 8192) return usageError("eval", "--resolution must be in [1, 8192]");
  if (args.has("--at-switch") && !(args.has("--chain") && image))
    return usageError("eval", "--at-switch needs --chain and --image (only a built chain's levels have a cell width)");
  if ((args.has("--nested") || args.has("--independent")) && !args.has("--chain"))
    return usageError("eval", "--nested and --independent go with --chain");
  if (args.has("--animated")) {
    if (args.has("--chain") || image) return usageError("eval", "--animated takes neither --chain nor --image");
    if (args.positional().empty()) return usageError("eval", "--animated needs MODEL");
    if (levels < 1 || levels > 32) return usageError("eval", "--levels must be in [1, 32]");
    const std::vector<std::string> level_args(args.positional().begin() + 1, args.positional().end());
    return runAnimatedEval(args.positional()[0], level_args, levels, samples, args.has("--json"));
  }
  if (args.has("--chain")) {
    if (args.positional().size() != 1) return usageError("eval", "--chain needs exactly one MODEL");
    if (levels < 1 || levels > 32) return usageError("eval", "--levels must be in [1, 32]");
    if (!(pixels > 0.0)) return usageError("eval", "--pixels must be > 0");
    ChainOptions o;
    o.levels = levels;
    o.pixels = pixels;
    o.samples = static_cast<size_t>(samples);
    o.resolution = static_cast<int>(resolution);
    o.json = args.has("--json");
    o.image = image;
    if (args.has("--nested") && args.has("--independent")) return usageError("eval", "give only one of --nested, --independent");
    if (args.has("--nested") || args.has("--independent")) o.nesting = args.has("--nested") ? 1 : 0;
    if (args.has("--at-switch")) {
      const std::string k = args.get("--at-switch");
      if (k == "all") o.at_switch = 0;
      else if (!args.getInt("--at-switch", o.at_switch) || o.at_switch < 1)
        return usageError("eval", "--at-switch needs a level K >= 1 or 'all', got '" + k + "'");
    }
    return runChain(args.positional()[0], o);
  }
  if (args.positional().size() != 2) return usageError("eval", "needs ORIGINAL and SIMPLIFIED");
  const std::string& a_path = args.positional()[0];
  const std::string& b_path = args.positional()[1];

  Mesh original, simplified;
  EvalMaterials a_materials, b_materials;
  if (Error e = loadFlatModel(a_path, original, a_materials); !e.ok()) return runError("eval", e.message);
  if (args.has("--stored-level")) {
    long k = -1;
    if (!args.getInt("--stored-level", k) || k < 0) return usageError("eval", "--stored-level needs a level K >= 0");
    LodChain stored;
    if (Error e = loadStoredLevels(b_path, stored, b_materials); !e.ok()) return runError("eval", e.message);
    if (static_cast<size_t>(k) >= stored.levelCount())
      return runError("eval", b_path + ": holds levels 0.." + std::to_string(stored.levelCount() - 1) + ", no level " + std::to_string(k));
    simplified = std::move(stored.levels[static_cast<size_t>(k)].mesh);
  } else if (Error e = loadFlatModel(b_path, simplified, b_materials); !e.ok()) {
    return runError("eval", e.message);
  }
  if (original.triangleCount() == 0)
    return runError("eval", a_path + ": the original has no triangles; the error is measured against its surface");
  if (simplified.empty()) return runError("eval", b_path + ": the simplified model has no triangles, edges or points");
  if (Error e = eval::checkComparableScales(original, a_path, simplified, b_path); !e.ok()) {
    if (!args.has("--force")) return runError("eval", e.message + " (use --force to measure anyway)");
    std::fprintf(stderr, "scenelod eval: warning: %s\n", e.message.c_str());
  }

  eval::DistanceParams dp;
  dp.area_sample_count = static_cast<size_t>(samples);
  eval::DistanceResult d;
  if (Error e = eval::measureSurfaceDistance(original, simplified, dp, d); !e.ok()) return runError("eval", e.message);
  eval::ImageErrorParams ip;
  ip.resolution = static_cast<int>(resolution);
  if (image) {
    ip.original_materials = a_materials.materials;
    ip.simplified_materials = b_materials.materials;
  }
  eval::ImageErrorResult im;
  if (Error e = eval::measureImageError(original, simplified, ip, im); !e.ok()) return runError("eval", e.message);

  if (args.has("--json")) {
    std::printf(
        "{\"original\": %s, \"simplified\": %s, \"hausdorff\": %s, \"rms\": %s, \"mean\": %s, "
        "\"hausdorff_forward\": %s, \"hausdorff_backward\": %s, \"rms_forward\": %s, \"rms_backward\": %s, "
        "\"silhouette\": %s, \"normal_deg\": %s, \"diagonal\": %s, \"samples_forward\": %zu, "
        "\"samples_backward\": %zu, \"resolution\": %ld, \"views\": %d, \"original_triangles\": %zu, "
        "\"simplified_triangles\": %zu, \"simplified_edges\": %zu, \"simplified_points\": %zu%s}\n",
        jsonString(a_path).c_str(), jsonString(b_path).c_str(), jsonNumber(d.hausdorff).c_str(),
        jsonNumber(d.rms).c_str(), jsonNumber(d.mean).c_str(), jsonNumber(d.forward.max / d.diagonal).c_str(),
        jsonNumber(d.backward.max / d.diagonal).c_str(), jsonNumber(d.forward.rms / d.diagonal).c_str(),
        jsonNumber(d.backward.rms / d.diagonal).c_str(), jsonNumber(im.silhouette).c_str(),
        jsonNumber(im.normal_deg).c_str(), jsonNumber(d.diagonal).c_str(), d.forward.sample_count,
        d.backward.sample_count, resolution, eval::kStandardViewCount, original.triangleCount(),
        simplified.triangleCount(), simplified.edgeCount(), simplified.pointCount(),
        image ? (", \"color_off\": " + jsonNumber(im.color_off) + ", \"color_mad\": " + jsonNumber(im.color_mad) +
                 ", \"textured\": " + (a_materials.textured() || b_materials.textured() ? "true" : "false"))
                    .c_str()
              : "");
    return 0;
  }
  std::printf("original    %s: %zu triangles, %zu edges, %zu points, bounding-box diagonal %g\n", a_path.c_str(),
              original.triangleCount(), original.edgeCount(), original.pointCount(), d.diagonal);
  std::printf("simplified  %s: %zu triangles, %zu edges, %zu points\n", b_path.c_str(), simplified.triangleCount(),
              simplified.edgeCount(), simplified.pointCount());
  std::printf("\ngeometric error, %% of the original's diagonal (%zu + %zu samples):\n", d.forward.sample_count,
              d.backward.sample_count);
  std::printf("  %-10s %9s %12s %12s\n", "", "symmetric", "orig->simp", "simp->orig");
  std::printf("  %-10s %8.4f%% %11.4f%% %11.4f%%\n", "hausdorff", 100.0 * d.hausdorff,
              100.0 * d.forward.max / d.diagonal, 100.0 * d.backward.max / d.diagonal);
  std::printf("  %-10s %8.4f%% %11.4f%% %11.4f%%\n", "rms", 100.0 * d.rms, 100.0 * d.forward.rms / d.diagonal,
              100.0 * d.backward.rms / d.diagonal);
  std::printf("  %-10s %8.4f%% %11.4f%% %11.4f%%\n", "mean", 100.0 * d.mean, 100.0 * d.forward.mean / d.diagonal,
              100.0 * d.backward.mean / d.diagonal);
  std::printf("\nimage error, %d orthographic views of %ldx%ld pixels:\n", eval::kStandardViewCount, resolution,
              resolution);
  std::printf("  silhouette mismatch  %.4f%%  (%zu of %zu covered pixels)\n", 100.0 * im.silhouette, im.one_px,
              im.either_px);
  std::printf("  normal deviation     %.3f deg  (mean over %zu pixels hit by both)\n", im.normal_deg, im.both_px);
  if (image) {
    std::printf("  colour off > %d/255  %.4f%%  (%zu of the %zu pixels hit by both; %s)\n", eval::kColorTolerance,
                100.0 * im.color_off, im.color_off_px, im.both_px,
                a_materials.textured() || b_materials.textured() ? "textured" : "no textures");
    std::printf("  colour MAD           %.3f  (mean absolute difference per channel, 8-bit levels)\n", im.color_mad);
  }
  return 0;
}

CommandRegistration reg({"eval", "geometric and image error between an original and a simplified model", kUsage,
                         runEval});

}  // namespace
}  // namespace scenelod::tool
