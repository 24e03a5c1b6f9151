// The fuzz targets' main in builds without libFuzzer: feeds every file named on the command line,
// and every file inside every folder named there (sorted, recursively), to LLVMFuzzerTestOneInput
// once. A crash or sanitizer report stops it like the fuzzer would; otherwise it prints how many
// inputs ran and exits 0. A missing argument is an error (exit 2): a test pointing at a folder that
// moved must fail, not pass on nothing.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "fuzz_input.h"

namespace fs = std::filesystem;

namespace {

bool runFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    std::fprintf(stderr, "cannot read %s\n", path.string().c_str());
    return false;
  }
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  LLVMFuzzerTestOneInput(bytes.data(), bytes.size());
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  size_t runs = 0;
  for (int i = 1; i < argc; ++i) {
    fs::path arg(argv[i]);
    std::error_code ec;
    if (fs::is_directory(arg, ec)) {
      std::vector<fs::path> files;
      for (const auto& e : fs::recursive_directory_iterator(arg))
        if (e.is_regular_file()) files.push_back(e.path());
      std::sort(files.begin(), files.end());
      for (const auto& f : files) {
        if (!runFile(f)) return 2;
        ++runs;
      }
    } else if (fs::is_regular_file(arg, ec)) {
      if (!runFile(arg)) return 2;
      ++runs;
    } else {
      std::fprintf(stderr, "%s: no such file or folder\n", argv[i]);
      return 2;
    }
  }
  std::printf("%zu inputs ran without a crash\n", runs);
  return 0;
}
