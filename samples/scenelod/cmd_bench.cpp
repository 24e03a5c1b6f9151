// scenelod bench: our clustering against meshoptimizer (meshopt_simplifySloppy, meshopt_simplify)
// at matched triangle counts, in one process on the same meshes: time (best of several runs) and
// error (eval::measureSurfaceDistance, eval::measureImageError). Writes Markdown, JSON and PNG plots.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include <meshoptimizer.h>
#include <sys/resource.h>

#include "args.h"
#include "bench_textured.h"
#include "command.h"
#include "eval_support.h"
#include "progress.h"
#include "scenelod/eval/metrics.h"
#include "scenelod/eval/plot.h"
#include "scenelod/eval/render.h"
#include "scenelod/lodcore/chain.h"
#include "scenelod/lodcore/cluster.h"

namespace scenelod::tool {
namespace {

namespace fs = std::filesystem;

const char* kUsage =
    "usage: scenelod bench [--models DIR] [--out DIR] [--quick] [--runs N] [--no-bunny]\n"
    "       scenelod bench --textured --models DIR [--only A,B,..] [--out DIR] [--quick] [--samples N]\n"
    "\n"
    "For the Stanford bunny and every model in DIR (each subfolder's .glb or .gltf, or model files\n"
    "directly in DIR; the whole model flattened in world space, exact duplicate positions welded,\n"
    "triangles with a repeated index dropped, attributes dropped), simplifies to 50, 20, 10, 5, 2\n"
    "and 1 % of the triangles with:\n"
    "  floating  scenelod clustering, floating cells (default ClusterParams), cell width found by\n"
    "            findCellWidthForTarget, then one clusterMesh call timed\n"
    "  uniform   scenelod clustering, Rossignac-Borrel uniform grid, same procedure\n"
    "  sloppy    meshopt_simplifySloppy (target_error 1: no error limit)\n"
    "  meshopt   meshopt_simplify (target_error 1, no options)\n"
    "Each is timed as the best of --runs runs in this process, and its error measured: Hausdorff\n"
    "and RMS relative to the diagonal (thick edges as capsules, points as spheres; for our methods\n"
    "also with triangles only), silhouette mismatch and normal deviation over 14 views. Also times\n"
    "an 8-level chain (buildChain). Writes bench.md, bench.json and PNG plots into --out.\n"
    "\n"
    "  --models DIR   folder of models (default: none, bunny only)\n"
    "  --out DIR      output folder (default docs/bench), created when missing\n"
    "  --quick        targets 10 % and 2 % only, 20k samples, 128-pixel views, 2 runs\n"
    "  --runs N       timing runs per method and target (default 5)\n"
    "  --samples N    area samples per surface for the distances (default 100000)\n"
    "  --no-bunny     leave the bunny out\n"
    "\n"
    "With --textured, untimed: for every model in DIR (or those whose file name stem is listed in\n"
    "--only), at 20 and 10 % of the triangles (--quick: 10 %, 128-pixel views, 20k samples), the\n"
    "textured image error of scenelod's floating-cell level, of the same level with its UVs dropped,\n"
    "and of meshopt_simplifySloppy and meshopt_simplify run per material (each output vertex keeps\n"
    "its own UVs), all drawn with the model's materials and textures: the share of co-covered pixels\n"
    "off by more than 16/255, the mean absolute difference, the silhouette mismatch and the\n"
    "Hausdorff distance. Writes textured.md and textured.json into --out.\n";

using Clock = std::chrono::steady_clock;

struct Model {
  std::string name, path;
  Mesh mesh;  // welded, triangles only
  double diagonal = 0.0;
  double chain_ms = 0.0;
  size_t chain_levels = 0;
};

struct Run {
  std::string method;
  double target_pct = 0.0;
  size_t target = 0;
  size_t triangles = 0, edges = 0, points = 0;
  double cell_width = 0.0;  // ours only
  double time_ms = 0.0;
  eval::DistanceResult dist;
  bool has_tri_only = false;
  eval::DistanceResult dist_tri_only;  // ours, edges and points removed (when there are any)
  eval::ImageErrorResult image;
  std::string note;
};

struct Settings {
  std::vector<double> targets_pct{50, 20, 10, 5, 2, 1};
  int runs = 5;
  size_t samples = 100000;
  int resolution = 256;
};

// exact-position weld and removal of triangles with a repeated index: the same input for everyone
Mesh weld(const Mesh& in) {
  struct Key {
    uint32_t x, y, z;
    bool operator==(const Key& o) const { return x == o.x && y == o.y && z == o.z; }
  };
  struct Hash {
    size_t operator()(const Key& k) const { return (k.x * 73856093u) ^ (k.y * 19349663u) ^ (k.z * 83492791u); }
  };
  std::unordered_map<Key, uint32_t, Hash> ids;
  std::vector<uint32_t> remap(in.vertexCount());
  Mesh out;
  for (size_t i = 0; i < in.vertexCount(); ++i) {
    Key k;
    std::memcpy(&k.x, &in.positions[i].x, 4);
    std::memcpy(&k.y, &in.positions[i].y, 4);
    std::memcpy(&k.z, &in.positions[i].z, 4);
    auto it = ids.find(k);
    if (it == ids.end()) {
      it = ids.emplace(k, static_cast<uint32_t>(out.positions.size())).first;
      out.positions.push_back(in.positions[i]);
    }
    remap[i] = it->second;
  }
  for (size_t t = 0; t < in.triangleCount(); ++t) {
    const uint32_t a = remap[in.triangles[3 * t]], b = remap[in.triangles[3 * t + 1]], c = remap[in.triangles[3 * t + 2]];
    if (a == b || b == c || a == c) continue;
    out.triangles.insert(out.triangles.end(), {a, b, c});
  }
  // drop vertices no triangle uses (from dropped triangles, or points/lines in the file)
  std::vector<uint32_t> used(out.positions.size(), UINT32_MAX);
  Mesh packed;
  for (uint32_t& i : out.triangles) {
    if (used[i] == UINT32_MAX) {
      used[i] = static_cast<uint32_t>(packed.positions.size());
      packed.positions.push_back(out.positions[i]);
    }
    packed.triangles.push_back(used[i]);
  }
  return packed;
}

double bestOf(int runs, const std::function<void()>& fn) {
  double best = 1e300;
  for (int r = 0; r < runs; ++r) {
    const auto t0 = Clock::now();
    fn();
    best = std::min(best, std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
  }
  return best;
}

Mesh trianglesOnly(const Mesh& m) {
  Mesh out;
  out.positions = m.positions;
  out.triangles = m.triangles;
  return out;
}

Error measure(const Model& model, const Mesh& simplified, const Settings& s, Run& run) {
  run.triangles = simplified.triangleCount();
  run.edges = simplified.edgeCount();
  run.points = simplified.pointCount();
  if (simplified.empty()) {
    run.note = "empty result";
    return {};
  }
  eval::DistanceParams dp;
  dp.area_sample_count = s.samples;
  if (Error e = eval::measureSurfaceDistance(model.mesh, simplified, dp, run.dist); !e.ok()) return e;
  eval::ImageErrorParams ip;
  ip.resolution = s.resolution;
  if (Error e = eval::measureImageError(model.mesh, simplified, ip, run.image); !e.ok()) return e;
  if ((run.edges || run.points) && run.triangles) {
    run.has_tri_only = true;
    if (Error e = eval::measureSurfaceDistance(model.mesh, trianglesOnly(simplified), dp, run.dist_tri_only); !e.ok()) return e;
  }
  return {};
}

Error runOurs(const Model& model, LodMethod method, const Settings& s, double pct, Run& run) {
  ClusterParams cp;
  cp.method = method;
  float w = 0.0f;
  const size_t target = std::max<size_t>(1, static_cast<size_t>(std::llround(model.mesh.triangleCount() * pct / 100.0)));
  if (Error e = findCellWidthForTarget(model.mesh, cp, target, w); !e.ok()) return e;
  cp.cell_width = w;
  Mesh out;
  Error err;
  run.time_ms = bestOf(s.runs, [&] { err = clusterMesh(model.mesh, cp, out); });
  if (!err.ok()) return err;
  run.cell_width = w;
  return measure(model, out, s, run);
}

Error runMeshopt(const Model& model, bool sloppy, const Settings& s, double pct, Run& run) {
  const Mesh& m = model.mesh;
  const size_t target = std::max<size_t>(1, static_cast<size_t>(std::llround(m.triangleCount() * pct / 100.0)));
  std::vector<unsigned> dst(m.triangles.size());
  size_t count = 0;
  float result_error = 0.0f;
  run.time_ms = bestOf(s.runs, [&] {
    if (sloppy)
      count = meshopt_simplifySloppy(dst.data(), m.triangles.data(), m.triangles.size(), &m.positions[0].x,
                                     m.vertexCount(), sizeof(glm::vec3), 3 * target, 1.0f, &result_error);
    else
      count = meshopt_simplify(dst.data(), m.triangles.data(), m.triangles.size(), &m.positions[0].x, m.vertexCount(),
                               sizeof(glm::vec3), 3 * target, 1.0f, 0, &result_error);
  });
  Mesh out;
  out.positions = m.positions;
  out.triangles.assign(dst.begin(), dst.begin() + count);
  return measure(model, out, s, run);
}

std::vector<std::string> findModels(const std::string& dir, std::string& error) {
  std::vector<std::string> out;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    error = dir + ": no such folder";
    return out;
  }
  auto isModel = [](const fs::path& p) {
    const std::string e = p.extension().string();
    return e == ".glb" || e == ".gltf" || e == ".obj";
  };
  std::vector<fs::path> entries;
  for (const auto& e : fs::directory_iterator(dir, ec)) entries.push_back(e.path());
  std::sort(entries.begin(), entries.end());
  for (const auto& p : entries) {
    if (fs::is_regular_file(p) && isModel(p)) {
      out.push_back(p.string());
    } else if (fs::is_directory(p)) {
      std::vector<fs::path> files;
      for (const auto& f : fs::directory_iterator(p, ec))
        if (fs::is_regular_file(f.path()) && isModel(f.path())) files.push_back(f.path());
      std::sort(files.begin(), files.end(), [](const fs::path& a, const fs::path& b) {
        // one file per folder: .glb before .gltf before .obj
        auto rank = [](const fs::path& x) { return x.extension() == ".glb" ? 0 : x.extension() == ".gltf" ? 1 : 2; };
        return rank(a) != rank(b) ? rank(a) < rank(b) : a < b;
      });
      if (!files.empty()) out.push_back(files.front().string());
    }
  }
  if (out.empty()) error = dir + ": no .glb, .gltf or .obj model in the folder or its subfolders";
  return out;
}

std::string pct(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3f", 100.0 * v);
  return b;
}

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

struct Machine {
  std::string cpu, load_start, load_end;
  unsigned threads = 0;
  double cpu_s = 0.0;  // user + system time of this process
};

double processCpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

void writeMarkdown(const std::string& path, const std::vector<Model>& models, const std::vector<std::vector<Run>>& runs,
                   const Settings& s, const std::string& command, const std::string& date, double total_s,
                   const Machine& mc) {
  std::ofstream f(path);
  f << "# scenelod bench: clustering vs meshoptimizer\n\n";
  f << "Command: `" << command << "`  \nDate: " << date << "  \nMachine: " << mc.cpu << ", " << mc.threads
    << " hardware threads; 1-minute load average " << mc.load_start << " at the start, " << mc.load_end
    << " at the end  \nTotal wall-clock time: " << fmt("%.1f", total_s) << " s, process CPU time (user + system) "
    << fmt("%.1f", mc.cpu_s) << " s; meshoptimizer "
    << MESHOPTIMIZER_VERSION / 1000 << "." << (MESHOPTIMIZER_VERSION % 1000) / 10 << "\n\n";
  f << "Times are the best of " << s.runs << " runs of one call (ours: one `clusterMesh` at the cell width "
    << "`findCellWidthForTarget` found; the search is not timed). Errors: Hausdorff and RMS in % of the "
    << "original's bounding-box diagonal (" << s.samples << " area samples per surface plus all vertices; "
    << "thick edges are capsules, points spheres of radius 0), silhouette mismatch in % and mean normal "
    << "deviation in degrees over 14 orthographic views of " << s.resolution << "x" << s.resolution
    << " pixels. `H tri` is the Hausdorff distance of our result with its edges and points removed.\n\n";
  for (size_t i = 0; i < models.size(); ++i) {
    const Model& m = models[i];
    f << "## " << m.name << "\n\n`" << m.path << "`: " << m.mesh.triangleCount() << " triangles, "
      << m.mesh.vertexCount() << " vertices after welding, diagonal " << fmt("%.4g", m.diagonal)
      << ". 8-level chain (buildChain): " << fmt("%.2f", m.chain_ms) << " ms.\n\n";
    f << "| target | method | triangles | edges | points | time ms | Hausdorff % | RMS % | H tri % | silhouette % | normal ° |\n";
    f << "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const Run& r : runs[i]) {
      f << "| " << fmt("%g", r.target_pct) << " % | " << r.method << " | " << r.triangles << " | " << r.edges << " | "
        << r.points << " | " << fmt("%.3f", r.time_ms) << " | ";
      if (!r.note.empty()) {
        f << r.note << " | | | | |\n";
        continue;
      }
      f << pct(r.dist.hausdorff) << " | " << pct(r.dist.rms) << " | "
        << (r.has_tri_only ? pct(r.dist_tri_only.hausdorff) : std::string("")) << " | " << pct(r.image.silhouette)
        << " | " << fmt("%.2f", r.image.normal_deg) << " |\n";
    }
    f << "\n![" << m.name << " Hausdorff](" << m.name << "_hausdorff.png) ![" << m.name << " RMS](" << m.name
      << "_rms.png) ![" << m.name << " time](" << m.name << "_time.png)\n\n";
  }
}

void writeJson(const std::string& path, const std::vector<Model>& models, const std::vector<std::vector<Run>>& runs,
               const Settings& s, const std::string& command, const std::string& date, double total_s,
               const Machine& mc) {
  std::ofstream f(path);
  f << "{\n  \"command\": " << jsonString(command) << ",\n  \"date\": " << jsonString(date)
    << ",\n  \"cpu\": " << jsonString(mc.cpu) << ",\n  \"hardware_threads\": " << mc.threads
    << ",\n  \"load_average_start\": " << jsonString(mc.load_start)
    << ",\n  \"load_average_end\": " << jsonString(mc.load_end) << ",\n  \"total_s\": " << jsonNumber(total_s)
    << ",\n  \"cpu_s\": " << jsonNumber(mc.cpu_s)
    << ",\n  \"runs\": " << s.runs << ",\n  \"samples\": " << s.samples << ",\n  \"resolution\": " << s.resolution
    << ",\n  \"meshoptimizer_version\": " << MESHOPTIMIZER_VERSION << ",\n  \"models\": [\n";
  for (size_t i = 0; i < models.size(); ++i) {
    const Model& m = models[i];
    f << "    {\"name\": " << jsonString(m.name) << ", \"path\": " << jsonString(m.path)
      << ", \"triangles\": " << m.mesh.triangleCount() << ", \"vertices\": " << m.mesh.vertexCount()
      << ", \"diagonal\": " << jsonNumber(m.diagonal) << ", \"chain_ms\": " << jsonNumber(m.chain_ms)
      << ", \"chain_levels\": " << m.chain_levels << ",\n     \"results\": [\n";
    for (size_t k = 0; k < runs[i].size(); ++k) {
      const Run& r = runs[i][k];
      f << "       {\"method\": " << jsonString(r.method) << ", \"target_pct\": " << jsonNumber(r.target_pct)
        << ", \"target\": " << r.target << ", \"triangles\": " << r.triangles << ", \"edges\": " << r.edges
        << ", \"points\": " << r.points << ", \"time_ms\": " << jsonNumber(r.time_ms);
      if (r.cell_width > 0.0) f << ", \"cell_width\": " << jsonNumber(r.cell_width);
      if (r.note.empty()) {
        f << ", \"hausdorff\": " << jsonNumber(r.dist.hausdorff) << ", \"rms\": " << jsonNumber(r.dist.rms)
          << ", \"silhouette\": " << jsonNumber(r.image.silhouette)
          << ", \"normal_deg\": " << jsonNumber(r.image.normal_deg);
        if (r.has_tri_only)
          f << ", \"hausdorff_triangles_only\": " << jsonNumber(r.dist_tri_only.hausdorff)
            << ", \"rms_triangles_only\": " << jsonNumber(r.dist_tri_only.rms);
      } else {
        f << ", \"note\": " << jsonString(r.note);
      }
      f << "}" << (k + 1 < runs[i].size() ? "," : "") << "\n";
    }
    f << "     ]}" << (i + 1 < models.size() ? "," : "") << "\n";
  }
  f << "  ]\n}\n";
}

Error writePlots(const std::string& dir, const Model& m, const std::vector<Run>& runs,
                 const std::vector<std::string>& methods) {
  struct Spec {
    const char* suffix;
    const char* title;
    const char* y;
    bool log_y;
    std::function<double(const Run&)> value;
  };
  const Spec specs[] = {
      {"hausdorff", "Hausdorff distance", "hausdorff, % of diagonal", true,
       [](const Run& r) { return r.note.empty() ? 100.0 * r.dist.hausdorff : NAN; }},
      {"rms", "RMS distance", "rms, % of diagonal", true,
       [](const Run& r) { return r.note.empty() ? 100.0 * r.dist.rms : NAN; }},
      {"time", "Time per level", "time, ms (best of runs)", true, [](const Run& r) { return r.time_ms; }},
  };
  for (const Spec& sp : specs) {
    std::vector<eval::PlotSeries> series;
    for (size_t k = 0; k < methods.size(); ++k) {
      eval::PlotSeries ps;
      ps.name = methods[k];
      ps.color = eval::seriesColor(static_cast<int>(k));
      for (const Run& r : runs)
        if (r.method == methods[k]) {
          ps.x.push_back(static_cast<double>(r.triangles));
          ps.y.push_back(sp.value(r));
        }
      series.push_back(ps);
    }
    eval::PlotParams pp;
    pp.title = m.name + ": " + sp.title;
    pp.x_label = "triangles in the result";
    pp.y_label = sp.y;
    pp.log_x = true;
    pp.log_y = sp.log_y;
    if (Error e = eval::writePlotPng(dir + "/" + m.name + "_" + sp.suffix + ".png", series, pp); !e.ok()) return e;
  }
  return {};
}

// the CPU model from /proc/cpuinfo and the 1-minute load average (other work on the machine
// slows the wall-clock times; the report says how busy it was)
std::string cpuModel() {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("model name", 0) == 0) {
      const size_t c = line.find(':');
      return c == std::string::npos ? line : line.substr(c + 2);
    }
  return "unknown CPU";
}

std::string loadAverage() {
  std::ifstream f("/proc/loadavg");
  std::string one;
  f >> one;
  return one.empty() ? "unknown" : one;
}

std::string nowUtc() {
  const std::time_t t = std::time(nullptr);
  char b[64];
  std::strftime(b, sizeof b, "%Y-%m-%d %H:%M UTC", std::gmtime(&t));
  return b;
}

// --textured: the untimed textured comparison of bench_textured.h over the chosen models
int runTexturedBench(const std::vector<std::string>& paths, const std::string& only, bool quick, size_t samples,
                     const std::string& out_dir, const std::string& command) {
  TexturedSettings ts;
  ts.samples = samples;
  if (quick) {
    ts.targets_pct = {10};
    ts.resolution = 128;
  }
  std::vector<TexturedModel> models;
  for (const std::string& path : paths) {
    const std::string stem = fs::path(path).stem().string();
    if (!only.empty() && ("," + only + ",").find("," + stem + ",") == std::string::npos) continue;
    std::fprintf(stderr, "textured: %s\n", stem.c_str());
    TexturedModel m;
    if (Error e = benchTexturedModel(path, ts, m); !e.ok()) return runError("bench", e.message);
    models.push_back(std::move(m));
  }
  if (models.empty()) return runError("bench", "--only '" + only + "' names none of the models found");
  const std::string date = nowUtc();
  for (const auto& [name, text] : {std::make_pair(std::string("textured.md"), texturedMarkdown(models, ts, command, date)),
                                   std::make_pair(std::string("textured.json"), texturedJson(models, ts, command, date))}) {
    std::ofstream f(out_dir + "/" + name);
    f << text;
    if (!f) return runError("bench", out_dir + "/" + name + ": cannot write");
  }
  std::printf("wrote %s/textured.md and %s/textured.json (%zu models)\n", out_dir.c_str(), out_dir.c_str(),
              models.size());
  return 0;
}

int runBench(const std::vector<std::string>& argv) {
  Args args(argv, {"--quick", "--no-bunny", "--textured"}, {"--models", "--out", "--runs", "--samples", "--only"});
  Settings s;
  const bool quick = args.has("--quick");
  if (quick) {
    s.targets_pct = {10, 2};
    s.runs = 2;
    s.samples = 20000;
    s.resolution = 128;
  }
  long runs = s.runs, samples = static_cast<long>(s.samples);
  args.getInt("--runs", runs);
  args.getInt("--samples", samples);
  if (!args.ok()) return usageError("bench", args.error());
  if (!args.positional().empty()) return usageError("bench", "takes no positional arguments");
  if (runs < 1 || runs > 100) return usageError("bench", "--runs must be in [1, 100]");
  if (samples < 100) return usageError("bench", "--samples must be at least 100");
  const bool textured = args.has("--textured");
  if (textured && !args.has("--models")) return usageError("bench", "--textured needs --models DIR");
  if (args.has("--only") && !textured) return usageError("bench", "--only goes with --textured");
  s.runs = static_cast<int>(runs);
  s.samples = static_cast<size_t>(samples);
  const std::string out_dir = args.get("--out", "docs/bench");

  std::vector<std::string> paths;
  if (!args.has("--no-bunny") && !textured) paths.push_back(SCENELOD_DEFAULT_MODEL);
  if (args.has("--models")) {
    std::string err;
    auto found = findModels(args.get("--models"), err);
    if (!err.empty()) return runError("bench", err);
    paths.insert(paths.end(), found.begin(), found.end());
  }
  if (paths.empty()) return usageError("bench", "no models: --no-bunny without --models");
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (!fs::is_directory(out_dir)) return runError("bench", out_dir + ": cannot create the output folder");

  std::string command = "scenelod bench";
  for (const auto& a : argv) command += " " + a;
  if (textured) return runTexturedBench(paths, args.get("--only"), quick, s.samples, out_dir, command);
  const std::string date = nowUtc();
  Machine machine;
  machine.cpu = cpuModel();
  machine.threads = std::thread::hardware_concurrency();
  machine.load_start = loadAverage();
  const auto t_start = Clock::now();
  const std::vector<std::string> methods = {"floating", "uniform", "sloppy", "meshopt"};

  std::vector<Model> models;
  std::vector<std::vector<Run>> results;
  for (size_t mi = 0; mi < paths.size(); ++mi) {
    Model model;
    model.path = paths[mi];
    model.name = fs::path(paths[mi]).stem().string();
    Mesh raw;
    if (Error e = loadFlatMesh(model.path, raw); !e.ok()) return runError("bench", e.message);
    model.mesh = weld(raw);
    if (model.mesh.triangleCount() < 100) {
      std::fprintf(stderr, "scenelod bench: %s: skipped, only %zu triangles\n", model.path.c_str(),
                   model.mesh.triangleCount());
      continue;
    }
    model.diagonal = computeBounds(model.mesh).diagonal();
    std::fprintf(stderr, "[%zu/%zu] %s: %zu triangles, %zu vertices\n", mi + 1, paths.size(), model.name.c_str(),
                 model.mesh.triangleCount(), model.mesh.vertexCount());
    {
      LodChain chain;
      ChainParams cp;
      Error err;
      model.chain_ms = bestOf(s.runs, [&] { err = buildChain(model.mesh, cp, chain); });
      if (!err.ok()) return runError("bench", model.path + ": " + err.message);
      model.chain_levels = chain.levelCount();
    }
    ProgressBar bar(model.name);
    std::vector<Run> model_runs;
    const size_t steps = s.targets_pct.size() * methods.size();
    size_t step = 0;
    for (double p : s.targets_pct) {
      for (const std::string& method : methods) {
        bar.update(static_cast<double>(step) / steps, (method + " " + fmt("%g", p) + " %").c_str());
        Run run;
        run.method = method;
        run.target_pct = p;
        run.target = std::max<size_t>(1, static_cast<size_t>(std::llround(model.mesh.triangleCount() * p / 100.0)));
        Error e;
        if (method == "floating") e = runOurs(model, LodMethod::kFloatingNearest, s, p, run);
        else if (method == "uniform") e = runOurs(model, LodMethod::kUniform, s, p, run);
        else e = runMeshopt(model, method == "sloppy", s, p, run);
        if (!e.ok()) return runError("bench", model.path + ", " + method + " at " + fmt("%g", p) + " %: " + e.message);
        model_runs.push_back(run);
        ++step;
      }
    }
    bar.update(1.0, "plots");
    bar.finish();
    if (Error e = writePlots(out_dir, model, model_runs, methods); !e.ok()) return runError("bench", e.message);
    models.push_back(std::move(model));
    results.push_back(std::move(model_runs));
    std::fprintf(stderr, "    done (%.1f s so far)\n", std::chrono::duration<double>(Clock::now() - t_start).count());
  }
  const double total_s = std::chrono::duration<double>(Clock::now() - t_start).count();
  machine.load_end = loadAverage();
  machine.cpu_s = processCpuSeconds();
  writeMarkdown(out_dir + "/bench.md", models, results, s, command, date, total_s, machine);
  writeJson(out_dir + "/bench.json", models, results, s, command, date, total_s, machine);
  std::printf("wrote %s/bench.md, %s/bench.json and %zu plots in %.1f s\n", out_dir.c_str(), out_dir.c_str(),
              3 * models.size(), total_s);
  return 0;
}

CommandRegistration reg({"bench", "compare our clustering with meshoptimizer: time and error, tables and plots",
                         kUsage, runBench});

}  // namespace
}  // namespace scenelod::tool
