#pragma once
// What the fuzz targets share: the libFuzzer entry point's declaration, a per-process scratch folder
// for the readers that take a path, and a cursor that decodes the input bytes into values.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

namespace scenelod::fuzz {

// Writes the bytes to `name` inside a folder made once per process (removed at exit) and returns
// the file's path. Aborts when the file cannot be written: a broken harness must not look like a
// clean run.
std::string writeScratchFile(const std::string& name, const uint8_t* data, size_t size);

// Reads values off the input in order; once it runs out every read gives zeros, so any input
// decodes to a whole call sequence.
class Cursor {
 public:
  Cursor(const uint8_t* data, size_t size) : data_(data), left_(size) {}
  bool empty() const { return left_ == 0; }
  uint8_t byte() {
    uint8_t b = 0;
    take(&b, 1);
    return b;
  }
  uint32_t u32() {
    uint32_t v = 0;
    take(&v, sizeof v);
    return v;
  }
  uint64_t u64() {
    uint64_t v = 0;
    take(&v, sizeof v);
    return v;
  }
  // raw bits: NaN, infinities, denormals and huge values come out as often as the input has them
  float f32() {
    float v = 0.0f;
    take(&v, sizeof v);
    return v;
  }

 private:
  void take(void* out, size_t n) {
    size_t k = n < left_ ? n : left_;
    std::memcpy(out, data_, k);
    data_ += k;
    left_ -= k;
  }
  const uint8_t* data_;
  size_t left_;
};

}  // namespace scenelod::fuzz
