// Reads a mesh with the installed scenelod, writes it as GLB, reads that back, prints the counts.
#include <cstdio>

#include <scenelod/scene/gltf_io.h>

namespace {
void print(const char* tag, const scenelod::scene::SceneData& s) {
  size_t v = 0, t = 0, e = 0, p = 0;
  for (const auto& m : s.meshes) {
    v += m.mesh.vertexCount();
    t += m.mesh.triangleCount();
    e += m.mesh.edgeCount();
    p += m.mesh.pointCount();
  }
  std::printf("%s: nodes=%zu meshes=%zu vertices=%zu triangles=%zu edges=%zu points=%zu\n", tag, s.nodes.size(), s.meshes.size(),
              v, t, e, p);
}
}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: consumer IN.obj OUT.glb\n");
    return 2;
  }
  scenelod::scene::SceneData s;
  if (scenelod::Error e = scenelod::scene::loadScene(argv[1], s); !e.ok()) {
    std::fprintf(stderr, "%s\n", e.message.c_str());
    return 1;
  }
  print("obj", s);
  if (scenelod::Error e = scenelod::scene::exportGlb(argv[2], s); !e.ok()) {
    std::fprintf(stderr, "%s\n", e.message.c_str());
    return 1;
  }
  scenelod::scene::SceneData r;
  if (scenelod::Error e = scenelod::scene::importGltf(argv[2], r); !e.ok()) {
    std::fprintf(stderr, "%s\n", e.message.c_str());
    return 1;
  }
  print("glb", r);
  return 0;
}
