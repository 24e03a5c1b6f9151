// Readers scenelod does not control accept what it writes: the Khronos glTF Validator (npm
// gltf-validator, pinned and installed by scripts/deps) on every file `scenelod lods` and `convert`
// write from the shared models. Each must have 0 errors and no warning code its input does not
// already have (inputs can warn, e.g. a normal map without tangents). Without the validator the
// tests skip, except in CI (CI=true), where they fail.
#include <cstdio>
#include <cstdlib>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "gltf_test_support.h"
#include "scenelod/scene/gltf_io.h"

using namespace scenelod;
using namespace scenelod::scene;

namespace {

// keep in step with scripts/deps
constexpr const char* kValidatorVersion = "2.0.0-dev.3.10";

std::string validatorDir() {
  if (const char* d = std::getenv("SCENELOD_GLTF_VALIDATOR_DIR")) return d;
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  const char* home = std::getenv("HOME");
  const std::string cache = xdg && *xdg ? xdg : std::string(home ? home : "/root") + "/.cache";
  return cache + "/scenelod/gltf-validator-" + kValidatorVersion;
}

bool inCi() {
  const char* ci = std::getenv("CI");
  return ci && (std::string(ci) == "true" || std::string(ci) == "1");
}

bool validatorPresent() {
  return test::fileExists(validatorDir() + "/node_modules/gltf-validator/package.json") &&
         std::system("node --version > /dev/null 2>&1") == 0;
}

#define SCENELOD_REQUIRE_VALIDATOR()                                                                       \
  do {                                                                                                     \
    if (!validatorPresent()) {                                                                             \
      if (inCi()) FAIL() << "the glTF validator is missing from " << validatorDir() << ": run scripts/deps"; \
      GTEST_SKIP() << "the glTF validator is missing from " << validatorDir() << ": run scripts/deps";     \
    }                                                                                                      \
  } while (0)

struct Report {
  bool ran = false;
  size_t errors = 0;
  std::set<std::string> warnings;  // codes of severity 1
  std::string error_text;          // the first errors, for the failure message
};

std::string quoted(const std::string& s) { return "'" + s + "'"; }

Report validate(const std::string& file) {
  Report r;
  const std::string script = test::testDataDir() + "/../scene/gltf_validate.js";
  const std::string cmd = "node " + quoted(script) + " " + quoted(validatorDir()) + " " + quoted(file) + " 2>&1";
  std::FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return r;
  std::string out;
  char buf[65536];
  for (size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) out.append(buf, n);
  if (::pclose(p) != 0) {
    r.error_text = out;
    return r;
  }
  const nlohmann::json j = nlohmann::json::parse(out, nullptr, false);
  if (j.is_discarded() || !j.contains("issues")) {
    r.error_text = out.substr(0, 500);
    return r;
  }
  r.ran = true;
  for (const nlohmann::json& m : j["issues"]["messages"]) {
    const int severity = m.value("severity", 3);
    if (severity == 0 && ++r.errors <= 3) r.error_text += m.dump() + "\n";
    if (severity == 1) r.warnings.insert(m.value("code", std::string()));
  }
  return r;
}

// `out` has no error and no warning code `in` lacks
void expectValidLike(const Report& in, const std::string& out) {
  SCOPED_TRACE(out);
  const Report r = validate(out);
  ASSERT_TRUE(r.ran) << r.error_text;
  EXPECT_EQ(r.errors, 0u) << r.error_text;
  for (const std::string& code : r.warnings) EXPECT_TRUE(in.warnings.count(code)) << "new warning " << code;
}

std::string stem(const std::string& model) { return model.substr(0, model.find('/')); }

}  // namespace

TEST(GltfValidator, LodsOutputsValidate) {
  SCENELOD_REQUIRE_SHARED_MODELS();
  SCENELOD_REQUIRE_VALIDATOR();
  const std::string dir = test::makeDir("validator_lods");
  for (const std::string& model : test::sharedGltfModels()) {
    SCOPED_TRACE(model);
    const std::string in = test::sharedModelsDir() + "/" + model;
    const Report input = validate(in);
    ASSERT_TRUE(input.ran) << input.error_text;
    for (const char* ext : {".glb", ".gltf"}) {
      const std::string out = test::makeDir("validator_lods/" + stem(model) + ext) + "/" + stem(model) + ext;
      SceneLods lods;
      const Error e = test::writeLods(in, out, 3, lods);
      ASSERT_TRUE(e.ok()) << e.message;
      expectValidLike(input, out);
    }
  }
}

TEST(GltfValidator, ConvertOutputsValidate) {
  SCENELOD_REQUIRE_SHARED_MODELS();
  SCENELOD_REQUIRE_VALIDATOR();
  const std::string dir = test::makeDir("validator_convert");
  for (const std::string& model : test::sharedGltfModels()) {
    SCOPED_TRACE(model);
    const std::string in = test::sharedModelsDir() + "/" + model;
    // what `scenelod convert IN OUT.glb` does
    SceneData s;
    ASSERT_TRUE(loadScene(in, s).ok());
    bakeMaterialColors(s);
    const std::string out = dir + "/" + stem(model) + ".glb";
    ASSERT_TRUE(exportGlb(out, s).ok());
    expectValidLike(validate(in), out);
  }
}
