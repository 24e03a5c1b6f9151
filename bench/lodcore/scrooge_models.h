#pragma once
// The models the SCROOGE benchmarks run on: the shared glTF models and the Stanford bunny, each
// flattened into one world-space mesh (scene::flattenScene), loaded once and cached.
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "scenelod/lodcore/mesh.h"
#include "scenelod/scene/gltf_io.h"

namespace scenelod::bench {

// smallest first, so a run that is cut short still covers the small models
inline const std::vector<std::string>& scroogeModelNames() {
  static const std::vector<std::string> names = {"Fox",       "Duck",      "VC",         "DamagedHelmet", "SheenChair",
                                                 "BrainStem", "bunny",     "SheenCloth", "2CylinderEngine"};
  return names;
}

// ../shared/models beside the checkout, or $SCENELOD_SHARED_MODELS
inline std::string sharedModelsDir() {
  if (const char* env = std::getenv("SCENELOD_SHARED_MODELS")) return env;
  std::string here = __FILE__;  // <checkout>/bench/lodcore/scrooge_models.h
  for (int i = 0; i < 3; ++i) here = here.substr(0, here.find_last_of('/'));
  return here + "/../shared/models";
}

inline std::string modelPath(const std::string& name) {
  if (name == "bunny") return SCENELOD_BUNNY_PATH;
  const std::string dir = sharedModelsDir() + "/" + name + "/" + name;
  const std::string glb = dir + ".glb";
  if (FILE* f = std::fopen(glb.c_str(), "rb")) {
    std::fclose(f);
    return glb;
  }
  return dir + ".gltf";
}

// the flattened mesh of a model, or null with `error` set when it cannot be read
inline const Mesh* loadModel(const std::string& name, std::string& error) {
  static std::map<std::string, Mesh> cache;
  auto it = cache.find(name);
  if (it != cache.end()) return &it->second;
  scene::SceneData sd;
  if (Error e = scene::loadScene(modelPath(name), sd); !e.ok()) {
    error = e.message;
    return nullptr;
  }
  scene::bakeMaterialColors(sd);  // SCROOGE averages the material colours
  return &(cache[name] = scene::flattenScene(sd));
}

}  // namespace scenelod::bench
