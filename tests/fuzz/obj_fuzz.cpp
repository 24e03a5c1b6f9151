// readObj on arbitrary bytes: a mesh or an error, never a crash.
#include "fuzz_input.h"
#include "scenelod/lodcore/obj_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string path = scenelod::fuzz::writeScratchFile("input.obj", data, size);
  scenelod::Mesh mesh;
  (void)scenelod::readObj(path, mesh);
  return 0;
}
