// readReplay on arbitrary bytes; a replay it accepts is written back and read again.
#include "fuzz_input.h"
#include "scenelod/selection/replay.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string path = scenelod::fuzz::writeScratchFile("input.jsonl", data, size);
  scenelod::selection::Replay replay;
  if (!scenelod::selection::readReplay(path, replay).ok()) return 0;
  (void)scenelod::selection::resolveReplayScene(path, replay.header.scene);
  std::string again = path + ".out.jsonl";
  if (!scenelod::selection::writeReplay(again, replay).ok()) return 0;
  scenelod::selection::Replay back;
  (void)scenelod::selection::readReplay(again, back);
  return 0;
}
