#include "cluster_options.h"

#include <cstdio>

#include "scenelod/lodcore/obj_io.h"
#include "scenelod/scene/gltf_io.h"

namespace scenelod::tool {

const char kClusterOptionsHelp[] =
    "  --method M        floating (default: floating cells with the best measured grading, synthesis\n"
    "                    and variant), floating-heaviest (Low & Tan 3.2), floating-nearest (3.2.3),\n"
    "                    uniform (Rossignac & Borrel grid over the bounding box), zhang (edge\n"
    "                    collapse by vision characteristic, Zhang, Shu & Luo 2003; see below)\n"
    "  --grading G       lowtan (cos(theta/2) x longest edge) or rossignac (1/theta x longest edge)\n"
    "  --synthesis S     mean (weighted mean), heaviest (the cell centre) or quadric (Lindstrom)\n"
    "  --cell-shape C    cube or sphere (diameter = cell width); floating methods only\n";

bool parseClusterOptions(const Args& args, ClusterParams& p, std::string& error) {
  p = ClusterParams();
  const std::string method = args.get("--method", "floating");
  if (method == "floating") {
  } else if (method == "floating-heaviest") {
    p.method = LodMethod::kFloatingHeaviest;
  } else if (method == "floating-nearest") {
    p.method = LodMethod::kFloatingNearest;
  } else if (method == "uniform") {
    p.method = LodMethod::kUniform;
  } else if (method == "zhang") {
    p.method = LodMethod::kZhang;
  } else {
    error = "unknown --method '" + method + "' (floating, floating-heaviest, floating-nearest, uniform, zhang)";
    return false;
  }
  if (args.has("--grading")) {
    const std::string g = args.get("--grading");
    if (g == "lowtan") p.grading = Grading::kLowTan;
    else if (g == "rossignac") p.grading = Grading::kRossignac;
    else {
      error = "unknown --grading '" + g + "' (lowtan, rossignac)";
      return false;
    }
  }
  if (args.has("--synthesis")) {
    const std::string s = args.get("--synthesis");
    if (s == "mean") p.synthesis = Synthesis::kMean;
    else if (s == "heaviest") p.synthesis = Synthesis::kHeaviest;
    else if (s == "quadric") p.synthesis = Synthesis::kQuadric;
    else {
      error = "unknown --synthesis '" + s + "' (mean, heaviest, quadric)";
      return false;
    }
  }
  if (args.has("--cell-shape")) {
    const std::string c = args.get("--cell-shape");
    if (c == "cube") p.cell_shape = CellShape::kCube;
    else if (c == "sphere") p.cell_shape = CellShape::kSphere;
    else {
      error = "unknown --cell-shape '" + c + "' (cube, sphere)";
      return false;
    }
  }
  return true;
}

bool parseNesting(const Args& args, ChainParams& cp, std::string& error) {
  const bool nested = args.has("--nested"), independent = args.has("--independent");
  if (!nested && !independent) return true;
  if (nested && independent) return error = "give only one of --nested, --independent", false;
  const LodMethod m = cp.cluster.method;
  if (m != LodMethod::kUniform && m != LodMethod::kFloatingHeaviest && m != LodMethod::kFloatingNearest)
    return error = std::string(nested ? "--nested" : "--independent") + " applies to the clustering methods, not " +
                   lodMethodName(m),
           false;
  cp.nested = nested;
  return true;
}

Error loadWorldMesh(const std::string& path, Mesh& out) {
  scene::SceneData s;
  if (Error e = scene::loadScene(path, s); !e.ok()) return e;
  scene::bakeMaterialColors(s);  // levels written as meshes alone carry the material colours
  out = scene::flattenScene(s);
  return validateMesh(out, path);
}

Error writeMeshFile(const std::string& path, const Mesh& mesh, const std::string& name) {
  const std::string ext = scene::lowerExtension(path);
  if (ext == ".obj") return writeObj(path, mesh);
  if (ext != ".glb") return {Status::kInvalidArgument, "cannot write '" + path + "': the output must end in .obj or .glb"};
  scene::SceneData s;
  scene::MeshData md;
  md.name = name;
  md.mesh = mesh;
  s.meshes.push_back(std::move(md));
  scene::NodeData node;
  node.name = name;
  node.mesh = 0;
  s.nodes.push_back(node);
  s.roots.push_back(0);
  return scene::exportGlb(path, s);
}

void printLevelTable(const LodChain& chain, const ChainStats* stats) {
  std::printf("%5s %12s %10s %10s %8s %8s %12s %9s\n", "level", "cell width", "vertices", "triangles", "edges",
              "points", "max error", "time ms");
  for (size_t k = 0; k < chain.levelCount(); ++k) {
    const LodLevel& l = chain.levels[k];
    char time[32] = "-";
    if (stats && k >= 1 && k - 1 < stats->level_seconds.size())
      std::snprintf(time, sizeof time, "%.1f", stats->level_seconds[k - 1] * 1e3);
    std::printf("%5zu %12.6g %10zu %10zu %8zu %8zu %12.6g %9s\n", k, double(l.cell_width), l.mesh.vertexCount(),
                l.mesh.triangleCount(), l.mesh.edgeCount(), l.mesh.pointCount(), double(l.max_error), time);
  }
}

}  // namespace scenelod::tool
