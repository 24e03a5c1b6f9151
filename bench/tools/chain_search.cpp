// The w_1 search of default chains, per mesh: probes (ChainStats::first_width_probes), the search's
// and the whole chain's time (minima over 3 builds) and level 1's share of the triangles, on the
// bunny, a 100 x 137 bumpy sphere ("sphere") and every mesh of 1,000 triangles or more of the glTF
// files named. Built and run by scripts/chain-search against a build's libraries. Not a unit test.
// Usage: chain_search MESH...   (MESH: an .obj or .glb path, or "sphere")
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "lodcore/generated_meshes.h"
#include "scenelod/lodcore/chain.h"
#include "scenelod/lodcore/obj_io.h"
#include "scenelod/scene/gltf_io.h"
#include "scenelod/scene/scene_data.h"

using namespace scenelod;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: chain_search MESH...   (an .obj or .glb path, or \"sphere\")\n");
    return 2;
  }
  size_t probes = 0, meshes = 0;
  double search = 0.0, total = 0.0;
  int bad = 0;
  for (int i = 1; i < argc; ++i) {
    std::vector<Mesh> ms;
    std::vector<std::string> names;
    const std::string path = argv[i];
    if (path == "sphere") {
      ms.push_back(test::makeBumpySphere(100, 137));
      names.push_back(path);
    } else if (path.size() > 4 && (path.compare(path.size() - 4, 4, ".glb") == 0 || path.compare(path.size() - 5, 5, ".gltf") == 0)) {
      scene::SceneData sd;
      if (Error e = scene::importGltf(path, sd); !e.ok()) {
        std::fprintf(stderr, "chain_search: %s\n", e.message.c_str());
        ++bad;
        continue;
      }
      const std::string base = path.substr(path.find_last_of('/') + 1);
      for (size_t k = 0; k < sd.meshes.size(); ++k)
        if (sd.meshes[k].mesh.triangleCount() >= 1000) {
          ms.push_back(sd.meshes[k].mesh);
          names.push_back(base + "#" + std::to_string(k));
        }
    } else {
      Mesh m;
      if (Error e = readObj(path, m); !e.ok()) {
        std::fprintf(stderr, "chain_search: %s\n", e.message.c_str());
        ++bad;
        continue;
      }
      ms.push_back(std::move(m));
      names.push_back(path.substr(path.find_last_of('/') + 1));
    }
    for (size_t k = 0; k < ms.size(); ++k) {
      ChainParams cp;
      LodChain chain;
      ChainStats st;
      double best_search = 1e30, best_total = 1e30;
      for (int r = 0; r < 3; ++r) {
        if (Error e = buildChain(ms[k], cp, chain, &st); !e.ok()) {
          std::fprintf(stderr, "chain_search: %s: %s\n", names[k].c_str(), e.message.c_str());
          ++bad;
          break;
        }
        best_search = std::min(best_search, st.first_width_seconds);
        best_total = std::min(best_total, st.total_seconds);
      }
      if (chain.levelCount() < 2) continue;
      const double share = double(chain.levels[1].mesh.triangleCount()) / double(ms[k].triangleCount());
      std::printf("%-30s %8zu triangles  probes %2zu  search %8.2f ms  chain %8.2f ms  level 1 %.3f\n",
                  names[k].c_str(), ms[k].triangleCount(), st.first_width_probes, best_search * 1e3,
                  best_total * 1e3, share);
      probes += st.first_width_probes, search += best_search, total += best_total, ++meshes;
    }
  }
  std::printf("%zu meshes: %zu probes, searches %.1f ms, chains %.1f ms (sums of minima over 3)\n", meshes, probes,
              search * 1e3, total * 1e3);
  return bad ? 1 : 0;
}
