// loadLevelScene on arbitrary bytes: a scene or an error, never a crash.
#include "fuzz_input.h"
#include "scenelod/selection/replay_scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string path = scenelod::fuzz::writeScratchFile("input.json", data, size);
  scenelod::selection::ReplayScene scene;
  (void)scenelod::selection::loadLevelScene(path, scene);
  return 0;
}
