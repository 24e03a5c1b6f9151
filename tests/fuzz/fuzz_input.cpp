#include "fuzz_input.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <system_error>
#include <unistd.h>

namespace scenelod::fuzz {
namespace {

std::string g_folder;

void removeFolder() {
  std::error_code ec;
  std::filesystem::remove_all(g_folder, ec);
}

const std::string& scratchFolder() {
  if (g_folder.empty()) {
    std::error_code ec;
    std::string base = std::filesystem::temp_directory_path(ec).string();
    if (ec) base = "/tmp";
    std::string pattern = base + "/scenelod-fuzz-XXXXXX";
    if (!mkdtemp(pattern.data())) {
      std::perror("scenelod fuzz: cannot make a scratch folder");
      std::abort();
    }
    g_folder = pattern;
    std::atexit(removeFolder);
  }
  return g_folder;
}

}  // namespace

std::string writeScratchFile(const std::string& name, const uint8_t* data, size_t size) {
  std::string path = scratchFolder() + "/" + name;
  std::FILE* f = std::fopen(path.c_str(), "wb");
  bool ok = f && (size == 0 || std::fwrite(data, 1, size, f) == size);
  if (f && std::fclose(f) != 0) ok = false;
  if (!ok) {
    std::perror(("scenelod fuzz: cannot write " + path).c_str());
    std::abort();
  }
  return path;
}

}  // namespace scenelod::fuzz
