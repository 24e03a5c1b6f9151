// Output fingerprint of the clustering chains: one line per chain with an FNV-1a hash of every array
// of every level (positions, normals, colours, uvs, triangles, edges, thicknesses, points) and of its
// cell width, maximum error and bounding sphere. Two builds whose lines are equal produce the same
// bits; a speed change that must not move the output is checked by diffing the two outputs.
// Built and run by scripts/chain-hash (against a build's libscenelod_core.a). Not a benchmark.
// Usage: chain_hash [big]   ("big" adds the 1 M-triangle bumpy sphere's chains)
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "lodcore/generated_meshes.h"
#include "scenelod/lodcore/chain.h"
#include "scenelod/lodcore/obj_io.h"

using namespace scenelod;
using namespace scenelod::test;

namespace {

struct Fnv {
  uint64_t h = 1469598103934665603ull;
  void bytes(const void* p, size_t n) {
    const unsigned char* c = static_cast<const unsigned char*>(p);
    for (size_t i = 0; i < n; ++i) h = (h ^ c[i]) * 1099511628211ull;
  }
  template <class T> void vec(const std::vector<T>& v) {
    const uint64_t n = v.size();
    bytes(&n, sizeof n);
    if (!v.empty()) bytes(v.data(), v.size() * sizeof(T));
  }
  template <class T> void pod(const T& v) { bytes(&v, sizeof v); }
};

Mesh coloured(Mesh m) {
  m.colors.resize(m.positions.size());
  for (size_t i = 0; i < m.positions.size(); ++i) {
    const glm::vec3& p = m.positions[i];
    m.colors[i] = glm::vec3(0.5f + 0.5f * std::sin(7.0f * p.x), 0.5f + 0.5f * std::cos(5.0f * p.y), float(i % 7) / 7.0f);
  }
  return m;
}

int run(const char* name, const Mesh& m, const ChainParams& cp) {
  LodChain chain;
  if (Error e = buildChain(m, cp, chain)) {
    std::printf("%s error %s\n", name, e.message.c_str());
    return 1;
  }
  Fnv f;
  for (const LodLevel& l : chain.levels) {
    f.vec(l.mesh.positions), f.vec(l.mesh.normals), f.vec(l.mesh.colors), f.vec(l.mesh.uvs);
    f.vec(l.mesh.triangles), f.vec(l.mesh.edges), f.vec(l.mesh.edge_thickness), f.vec(l.mesh.points);
    f.pod(l.cell_width), f.pod(l.max_error), f.pod(l.bounds.center), f.pod(l.bounds.radius);
  }
  std::printf("%-40s levels %zu last %zu tris  %016llx\n", name, chain.levels.size(),
              chain.levels.back().mesh.triangleCount(), static_cast<unsigned long long>(f.h));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const bool big = argc > 1 && std::strcmp(argv[1], "big") == 0;
  struct Named { std::string name; Mesh mesh; };
  std::vector<Named> meshes;
  Mesh b;
  if (!readObj("/usr/share/glmark2/models/bunny.obj", b)) meshes.push_back({"bunny", b});
  else std::fprintf(stderr, "chain_hash: no bunny (apt-get install glmark2-data), skipped\n");
  meshes.push_back({"cad", makeCadPart()});
  meshes.push_back({"sphere-col", coloured(makeSphere(glm::vec3(0.0f), 1.0f, 60, 90))});
  if (big) meshes.push_back({"sphere1M", makeBumpySphere(720, 720)});
  const LodMethod methods[] = {LodMethod::kFloatingNearest, LodMethod::kFloatingHeaviest, LodMethod::kUniform};
  const Synthesis syntheses[] = {Synthesis::kQuadric, Synthesis::kMean, Synthesis::kHeaviest};
  const CellShape shapes[] = {CellShape::kCube, CellShape::kSphere};
  int bad = 0;
  for (const Named& n : meshes)
    for (LodMethod m : methods)
      for (Synthesis s : syntheses)
        for (CellShape c : shapes) {
          if (n.name == "sphere1M" && (s != Synthesis::kQuadric || c != CellShape::kCube)) continue;
          ChainParams cp;
          cp.cluster.method = m, cp.cluster.synthesis = s, cp.cluster.cell_shape = c;
          const std::string name = n.name + "/" + lodMethodName(m) + "/" + synthesisName(s) + "/" +
                                   cellShapeName(c);
          bad += run(name.c_str(), n.mesh, cp);
        }
  return bad ? 1 : 0;
}
