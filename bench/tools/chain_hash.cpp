// Output fingerprint of the clustering chains: one line per chain with an FNV-1a hash of every array
// of every level (positions, normals, colours, uvs, triangles, edges, thicknesses, points, geomorph
// targets and source vertices) and of its
// cell width, maximum error and bounding sphere. Two builds whose lines are equal produce the same
// bits; a speed change that must not move the output is checked by diffing the two outputs.
// With "geometry", the hash is of the primitives as sets instead: each triangle as its three corners
// (position, normal, colour) in its own winding, the least of its three rotations, the triangles
// sorted, and likewise edges (with thickness) and points, so that a change meant to renumber the
// output's vertices, and nothing else, is checked too; "positions" does the same with the corners'
// positions alone (for a change that may also move normals by rounding).
// Built and run by scripts/chain-hash (against a build's libscenelod_core.a). Not a benchmark.
// Usage: chain_hash [big] [geometry|positions]   ("big" adds the 1 M-triangle bumpy sphere's chains)
#include <algorithm>
#include <array>
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

bool g_geometry = false, g_positions_only = false;

// one output corner: position, normal and colour (zero where the level has none), as raw words
using Corner = std::array<uint32_t, 9>;
Corner corner(const Mesh& m, uint32_t v) {
  Corner c{};
  std::memcpy(&c[0], &m.positions[v], sizeof(glm::vec3));
  if (g_positions_only) return c;
  if (!m.normals.empty()) std::memcpy(&c[3], &m.normals[v], sizeof(glm::vec3));
  if (!m.colors.empty()) std::memcpy(&c[6], &m.colors[v], sizeof(glm::vec3));
  return c;
}

// the level's primitives as sorted sets of corner tuples (see the header)
void hashGeometry(const Mesh& m, Fnv& f) {
  std::vector<std::array<Corner, 3>> tris;
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    std::array<Corner, 3> c = {corner(m, m.triangles[3 * t]), corner(m, m.triangles[3 * t + 1]),
                               corner(m, m.triangles[3 * t + 2])};
    // the least of the three rotations (the winding is kept; two equal corners make the least corner
    // alone ambiguous)
    std::array<Corner, 3> best = c;
    for (int r = 1; r < 3; ++r) {
      std::rotate(c.begin(), c.begin() + 1, c.end());
      best = std::min(best, c);
    }
    tris.push_back(best);
  }
  std::sort(tris.begin(), tris.end());
  std::vector<std::pair<std::array<Corner, 2>, float>> edges;
  for (size_t e = 0; e < m.edgeCount(); ++e) {
    std::array<Corner, 2> c = {corner(m, m.edges[2 * e]), corner(m, m.edges[2 * e + 1])};
    if (c[1] < c[0]) std::swap(c[0], c[1]);
    edges.push_back({c, m.edgeThickness(e)});
  }
  std::sort(edges.begin(), edges.end());
  std::vector<Corner> points;
  for (uint32_t v : m.points) points.push_back(corner(m, v));
  std::sort(points.begin(), points.end());
  f.vec(tris), f.vec(edges), f.vec(points);
}

int run(const char* name, const Mesh& m, const ChainParams& cp) {
  LodChain chain;
  if (Error e = buildChain(m, cp, chain); !e.ok()) {
    std::printf("%s error %s\n", name, e.message.c_str());
    return 1;
  }
  Fnv f;
  for (const LodLevel& l : chain.levels) {
    if (g_geometry) {
      hashGeometry(l.mesh, f);
    } else {
      f.vec(l.mesh.positions), f.vec(l.mesh.normals), f.vec(l.mesh.colors), f.vec(l.mesh.uvs);
      f.vec(l.mesh.triangles), f.vec(l.mesh.edges), f.vec(l.mesh.edge_thickness), f.vec(l.mesh.points);
      // the geomorph targets and source vertices, in vertex order like the arrays above
      f.vec(l.morph.positions), f.vec(l.morph.normals), f.vec(l.morph.colors), f.vec(l.morph.uvs);
      f.vec(l.morph.tangents), f.vec(l.source_vertex);
    }
    f.pod(l.cell_width), f.pod(l.max_error), f.pod(l.bounds.center), f.pod(l.bounds.radius);
  }
  std::printf("%-40s levels %zu last %zu tris  %016llx\n", name, chain.levels.size(),
              chain.levels.back().mesh.triangleCount(), static_cast<unsigned long long>(f.h));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  bool big = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "big") == 0) big = true;
    else if (std::strcmp(argv[i], "geometry") == 0) g_geometry = true;
    else if (std::strcmp(argv[i], "positions") == 0) g_geometry = g_positions_only = true;
    else {
      std::fprintf(stderr, "chain_hash: unknown argument '%s' (usage: chain_hash [big] [geometry|positions])\n", argv[i]);
      return 2;
    }
  }
  struct Named { std::string name; Mesh mesh; };
  std::vector<Named> meshes;
  Mesh b;
  if (readObj("/usr/share/glmark2/models/bunny.obj", b).ok()) meshes.push_back({"bunny", b});
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
