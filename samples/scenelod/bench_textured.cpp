// The textured comparison of `scenelod bench --textured`: scenelod's floating-cell level against
// meshoptimizer 0.18 (which has no simplifyWithAttributes: its outputs keep each vertex's own
// attributes) at matched triangle counts, all drawn with the model's materials.
#include "bench_textured.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

#include <meshoptimizer.h>

#include "eval_materials.h"
#include "eval_support.h"
#include "scenelod/lodcore/chain.h"
#include "scenelod/lodcore/cluster.h"
#include "scenelod/lodcore/mesh_attributes.h"

namespace scenelod::tool {

namespace {

const char* const kMethods[] = {"scenelod", "scenelod-nouv", "sloppy", "meshopt"};

size_t targetCount(size_t triangles, double pct) {
  return std::max<size_t>(1, static_cast<size_t>(std::llround(static_cast<double>(triangles) * pct / 100.0)));
}

// meshoptimizer on each triangle group apart (an engine simplifies each primitive), every group
// asked for its share of `target`; the result keeps all input vertices and their attributes
Mesh simplifyPerGroup(const Mesh& in, size_t target, bool sloppy) {
  std::map<uint32_t, std::vector<uint32_t>> groups;
  for (size_t t = 0; t < in.triangleCount(); ++t) {
    auto& idx = groups[in.triangleGroup(t)];
    idx.insert(idx.end(), in.triangles.begin() + 3 * t, in.triangles.begin() + 3 * t + 3);
  }
  Mesh out = in;
  out.triangles.clear();
  out.triangle_groups.clear();
  const bool grouped = !in.triangle_groups.empty();
  std::vector<uint32_t> dst;
  for (const auto& [group, idx] : groups) {
    const size_t share = std::max<size_t>(1, static_cast<size_t>(std::llround(
                                                 static_cast<double>(target) * (idx.size() / 3) / in.triangleCount())));
    dst.resize(idx.size());
    float err = 0.0f;
    const size_t n =
        sloppy ? meshopt_simplifySloppy(dst.data(), idx.data(), idx.size(), &in.positions[0].x, in.vertexCount(),
                                        sizeof(glm::vec3), 3 * share, 1.0f, &err)
               : meshopt_simplify(dst.data(), idx.data(), idx.size(), &in.positions[0].x, in.vertexCount(),
                                  sizeof(glm::vec3), 3 * share, 1.0f, 0, &err);
    out.triangles.insert(out.triangles.end(), dst.begin(), dst.begin() + static_cast<long>(n));
    if (grouped) out.triangle_groups.insert(out.triangle_groups.end(), n / 3, group);
  }
  return out;
}

Error measureRun(const Mesh& original, const Mesh& level, const EvalMaterials& mats, const TexturedSettings& s,
                 TexturedRun& run) {
  run.triangles = level.triangleCount();
  run.edges = level.edgeCount();
  run.points = level.pointCount();
  if (level.empty()) {
    run.note = "empty result";
    return {};
  }
  eval::DistanceParams dp;
  dp.area_sample_count = s.samples;
  if (Error e = eval::measureSurfaceDistance(original, level, dp, run.dist); !e.ok()) return e;
  eval::ImageErrorParams ip;
  ip.resolution = s.resolution;
  ip.original_materials = mats.materials;
  ip.simplified_materials = mats.materials;
  return eval::measureImageError(original, level, ip, run.image);
}

std::string pct(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.2f", 100.0 * v);
  return b;
}

std::string ratio(double a, double b) {
  if (!(b > 0.0)) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", a / b);
  return buf;
}

const TexturedRun* findRun(const TexturedModel& m, const std::string& method, double target_pct) {
  for (const TexturedRun& r : m.runs)
    if (r.method == method && r.target_pct == target_pct && r.note.empty()) return &r;
  return nullptr;
}

}  // namespace

Error benchTexturedModel(const std::string& path, const TexturedSettings& s, TexturedModel& out) {
  out = TexturedModel{};
  out.path = path;
  out.name = std::filesystem::path(path).stem().string();
  Mesh mesh;
  EvalMaterials mats;
  if (Error e = loadFlatModel(path, mesh, mats); !e.ok()) return e;
  // meshoptimizer's outputs and ours draw triangles only: the comparison is over the surface
  mesh.edges.clear();
  mesh.edge_thickness.clear();
  mesh.points.clear();
  mesh.face_offsets.clear();
  mesh.face_corners.clear();
  weldVertices(mesh);
  out.triangles = mesh.triangleCount();
  out.vertices = mesh.vertexCount();
  out.materials = mats.materials.size();
  for (const eval::Material& m : mats.materials) out.textured_materials += m.texture != nullptr;
  out.has_uvs = !mesh.uvs.empty();
  if (mesh.triangleCount() < 100) return {Status::kInvalidMesh, path + ": fewer than 100 triangles to simplify"};
  for (double p : s.targets_pct) {
    const size_t target = targetCount(mesh.triangleCount(), p);
    ClusterParams cp;
    float w = 0.0f;
    if (Error e = findCellWidthForTarget(mesh, cp, target, w); !e.ok()) return {e.status, path + ": " + e.message};
    cp.cell_width = w;
    Mesh ours;
    if (Error e = clusterMesh(mesh, cp, ours); !e.ok()) return {e.status, path + ", scenelod: " + e.message};
    Mesh no_uv = ours;
    no_uv.uvs.clear();
    no_uv.extra_uvs.clear();
    const Mesh levels[4] = {ours, no_uv, simplifyPerGroup(mesh, target, true), simplifyPerGroup(mesh, target, false)};
    for (int k = 0; k < 4; ++k) {
      TexturedRun run;
      run.method = kMethods[k];
      run.target_pct = p;
      run.target = target;
      if (Error e = measureRun(mesh, levels[k], mats, s, run); !e.ok())
        return {e.status, path + ", " + run.method + " at " + std::to_string(p) + " %: " + e.message};
      out.runs.push_back(std::move(run));
    }
  }
  return {};
}

std::string texturedMarkdown(const std::vector<TexturedModel>& models, const TexturedSettings& s,
                             const std::string& command, const std::string& date) {
  std::string f = "# scenelod bench --textured: textured image error at matched triangle counts\n\n";
  f += "Command: `" + command + "`  \nDate: " + date + "  \nmeshoptimizer " +
       std::to_string(MESHOPTIMIZER_VERSION / 1000) + "." + std::to_string((MESHOPTIMIZER_VERSION % 1000) / 10) +
       "\n\nEach model is flattened to world space and its equal vertices welded. `scenelod` is the floating-cell "
       "level at the cell width `findCellWidthForTarget` finds, `scenelod-nouv` the same level with its texture "
       "coordinates dropped (each texture drawn as its mean colour), `sloppy` and `meshopt` are "
       "`meshopt_simplifySloppy` and `meshopt_simplify` (target error 1) run per material, every output vertex "
       "keeping its own attributes. All are drawn with the model's materials (base colour factor x texture x "
       "COLOR_0, headlight shading) from 14 orthographic views of " +
       std::to_string(s.resolution) + " x " + std::to_string(s.resolution) +
       " pixels. `colour off` is the share of the pixels both the original and the result cover whose colour "
       "differs by more than 16/255 in a channel, `MAD` the mean absolute difference in 8-bit levels; the "
       "silhouette mismatch is apart. Hausdorff in % of the diagonal (" + std::to_string(s.samples) +
       " area samples per surface).\n\n";
  for (const TexturedModel& m : models) {
    f += "## " + m.name + "\n\n`" + m.path + "`: " + std::to_string(m.triangles) + " triangles, " +
         std::to_string(m.vertices) + " vertices after welding, " + std::to_string(m.materials) + " materials (" +
         std::to_string(m.textured_materials) + " textured)" + (m.has_uvs ? "" : ", no texture coordinates") +
         (m.textured_materials ? "" : ": no textures, so the colour columns measure shading and vertex colours only") +
         ".\n\n| target | method | triangles | Hausdorff % | silhouette % | colour off % | MAD |\n"
         "|---:|---|---:|---:|---:|---:|---:|\n";
    for (const TexturedRun& r : m.runs) {
      char head[64];
      std::snprintf(head, sizeof head, "| %g %% | %s | %zu | ", r.target_pct, r.method.c_str(), r.triangles);
      f += head;
      if (!r.note.empty()) {
        f += r.note + " | | | |\n";
        continue;
      }
      char mad[32];
      std::snprintf(mad, sizeof mad, "%.2f", r.image.color_mad);
      f += pct(r.dist.hausdorff) + " | " + pct(r.image.silhouette) + " | " + pct(r.image.color_off) + " | " + mad +
           " |\n";
    }
    f += "\n";
  }
  f += "## Targets (#37)\n\nColour off of `scenelod` divided by that of the others: aim <= 1 against `sloppy`, "
       "<= 1.5 against `meshopt`, <= 0.25 against `scenelod-nouv`.\n\n"
       "| model | target | / sloppy | / meshopt | / scenelod-nouv |\n|---|---:|---:|---:|---:|\n";
  for (const TexturedModel& m : models)
    for (double p : s.targets_pct) {
      const TexturedRun* ours = findRun(m, "scenelod", p);
      if (!ours) continue;
      auto other = [&](const char* method) {
        const TexturedRun* r = findRun(m, method, p);
        if (!r) return std::string("-");
        // a method that stopped well above the target was not compared at a matched count
        const bool above = static_cast<double>(r->triangles) > 1.1 * static_cast<double>(r->target);
        return ratio(ours->image.color_off, r->image.color_off) + (above ? " *" : "");
      };
      char head[96];
      std::snprintf(head, sizeof head, "| %s | %g %% | ", m.name.c_str(), p);
      f += head + other("sloppy") + " | " + other("meshopt") + " | " + other("scenelod-nouv") + " |\n";
    }
  return f + "\n\\* that method stopped more than 10 % above the target triangle count (meshopt_simplify keeps "
             "UV seams and borders), so the counts are not matched there.\n";
}

std::string texturedJson(const std::vector<TexturedModel>& models, const TexturedSettings& s,
                         const std::string& command, const std::string& date) {
  std::string f = "{\n  \"command\": " + jsonString(command) + ",\n  \"date\": " + jsonString(date) +
                  ",\n  \"resolution\": " + std::to_string(s.resolution) + ",\n  \"samples\": " +
                  std::to_string(s.samples) + ",\n  \"color_tolerance\": " + std::to_string(eval::kColorTolerance) +
                  ",\n  \"models\": [\n";
  for (size_t i = 0; i < models.size(); ++i) {
    const TexturedModel& m = models[i];
    f += "    {\"name\": " + jsonString(m.name) + ", \"path\": " + jsonString(m.path) +
         ", \"triangles\": " + std::to_string(m.triangles) + ", \"vertices\": " + std::to_string(m.vertices) +
         ", \"materials\": " + std::to_string(m.materials) + ", \"textured_materials\": " +
         std::to_string(m.textured_materials) + ", \"has_uvs\": " + (m.has_uvs ? "true" : "false") +
         ",\n     \"results\": [\n";
    for (size_t k = 0; k < m.runs.size(); ++k) {
      const TexturedRun& r = m.runs[k];
      f += "       {\"method\": " + jsonString(r.method) + ", \"target_pct\": " + jsonNumber(r.target_pct) +
           ", \"target\": " + std::to_string(r.target) + ", \"triangles\": " + std::to_string(r.triangles);
      if (r.note.empty())
        f += ", \"hausdorff\": " + jsonNumber(r.dist.hausdorff) + ", \"silhouette\": " + jsonNumber(r.image.silhouette) +
             ", \"color_off\": " + jsonNumber(r.image.color_off) + ", \"color_mad\": " + jsonNumber(r.image.color_mad);
      else
        f += ", \"note\": " + jsonString(r.note);
      f += std::string("}") + (k + 1 < m.runs.size() ? "," : "") + "\n";
    }
    f += std::string("     ]}") + (i + 1 < models.size() ? "," : "") + "\n";
  }
  return f + "  ]\n}\n";
}

}  // namespace scenelod::tool
