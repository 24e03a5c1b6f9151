#pragma once
// Small helpers shared by the glTF tests: scratch folders, message checks, the JSON of a file, and
// writing a model's LOD levels the way `scenelod lods` does.
#include <sys/stat.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "scenelod/scene/gltf_io.h"
#include "scenelod/scene/lod_build.h"
#include "test_support.h"

namespace scenelod::test {

inline bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

// a folder `name` inside the test scratch folder (created when missing)
inline std::string makeDir(const std::string& name) {
  const std::string d = scratchDir() + "/" + name;
  ::mkdir(d.c_str(), 0755);
  return d;
}

inline std::vector<unsigned char> readFileBytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::vector<unsigned char>(std::istreambuf_iterator<char>(f), {});
}

// the JSON of a .gltf, or of a GLB's first chunk (null when unreadable)
inline nlohmann::json readGltfJson(const std::string& path) {
  const std::vector<unsigned char> b = readFileBytes(path);
  if (b.size() >= 20 && std::memcmp(b.data(), "glTF", 4) == 0) {
    uint32_t n = 0;
    std::memcpy(&n, &b[12], 4);
    if (n > b.size() - 20) return nullptr;
    return nlohmann::json::parse(b.begin() + 20, b.begin() + 20 + n, nullptr, false);
  }
  return nlohmann::json::parse(b.begin(), b.end(), nullptr, false);
}

// the shared models' glTF files, relative to sharedModelsDir()
inline std::vector<std::string> sharedGltfModels() {
  return {"Duck/Duck.glb",         "DamagedHelmet/DamagedHelmet.glb", "Fox/Fox.glb",     "BrainStem/BrainStem.glb",
          "SheenChair/SheenChair.gltf", "SheenCloth/SheenCloth.gltf", "VC/VC.glb", "2CylinderEngine/2CylinderEngine.glb"};
}

// `levels` levels of every mesh of the glTF `in` (buildLods, as `scenelod lods` builds them) written
// to `out` with exportGltfLods; `lods` receives the chains
inline Error writeLods(const std::string& in, const std::string& out, size_t levels, scene::SceneLods& lods,
                       scene::ThickEdges thick_edges = scene::ThickEdges::kPrisms) {
  scene::SceneData s;
  if (Error e = scene::importGltf(in, s); !e.ok()) return e;
  scene::LodBuildParams params;
  params.chain.level_count = levels;
  if (Error e = scene::buildLods(s, params, lods, nullptr, in); !e.ok()) return e;
  std::vector<const LodChain*> chains;
  for (const LodChain& c : lods.chains) chains.push_back(&c);
  return scene::exportGltfLods(in, out, s, chains, nullptr, thick_edges);
}

}  // namespace scenelod::test
