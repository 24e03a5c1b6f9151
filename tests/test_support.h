#pragma once
// Paths to real models for tests, and skips with a clear message when they are absent.
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <sys/stat.h>
#include <unistd.h>

#include <gtest/gtest.h>

namespace scenelod::test {

// whether two arrays hold the same bytes (bit-identical results of two code paths; NaN-safe,
// unlike ==)
template <typename T>
bool sameBits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

inline bool fileExists(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

inline std::string bunnyPath() { return SCENELOD_BUNNY_PATH; }
inline std::string sharedModelsDir() { return SCENELOD_SHARED_MODELS_DIR; }
inline std::string testDataDir() { return SCENELOD_TEST_DATA_DIR; }

// A scratch folder for files a test writes (under the build tree's temp folder), created on demand.
inline std::string scratchDir() {
  const char* t = std::getenv("TMPDIR");
  std::string dir = std::string(t ? t : "/tmp") + "/scenelod_tests_" + std::to_string(::getpid());
  ::mkdir(dir.c_str(), 0755);
  return dir;
}

}  // namespace scenelod::test

// Skip the current test when the bunny (Debian glmark2-data) is not installed.
#define SCENELOD_REQUIRE_BUNNY()                                                              \
  do {                                                                                        \
    if (!::scenelod::test::fileExists(::scenelod::test::bunnyPath()))                         \
      GTEST_SKIP() << "the Stanford bunny is not installed at " << ::scenelod::test::bunnyPath() \
                   << " (apt-get install glmark2-data; scripts/test does this)";             \
  } while (0)

// Skip the current test when ../shared/models is absent (a user's clone has no ../shared).
#define SCENELOD_REQUIRE_SHARED_MODELS()                                                           \
  do {                                                                                             \
    if (!::scenelod::test::fileExists(::scenelod::test::sharedModelsDir()))                        \
      GTEST_SKIP() << "shared models folder " << ::scenelod::test::sharedModelsDir()               \
                   << " is absent: these tests run in CI, where ../shared/models is present";      \
  } while (0)
