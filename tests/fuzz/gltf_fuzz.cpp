// The glTF importer on arbitrary bytes, named .glb when they start with the GLB magic and .gltf
// otherwise. Even-sized inputs go through loadScene (the path every command takes), odd-sized ones
// through importGltfLods (MSFT_lod chains read back as well).
#include <cstring>
#include <vector>

#include "fuzz_input.h"
#include "scenelod/scene/gltf_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  bool glb = size >= 4 && std::memcmp(data, "glTF", 4) == 0;
  std::string path = scenelod::fuzz::writeScratchFile(glb ? "input.glb" : "input.gltf", data, size);
  scenelod::scene::SceneData scene;
  if (size % 2 == 0) {
    (void)scenelod::scene::loadScene(path, scene);
  } else {
    std::vector<scenelod::LodChain> chains;
    (void)scenelod::scene::importGltfLods(path, scene, chains);
  }
  return 0;
}
