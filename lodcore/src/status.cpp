#include "scenelod/lodcore/status.h"

#include "scenelod/lodcore/lod_chain.h"

namespace scenelod {

const char* statusName(Status status) {
  switch (status) {
    case Status::kOk: return "ok";
    case Status::kInvalidArgument: return "invalid-argument";
    case Status::kInvalidMesh: return "invalid-mesh";
    case Status::kIoError: return "io-error";
    case Status::kParseError: return "parse-error";
    case Status::kUnsupported: return "unsupported";
    case Status::kCorrupt: return "corrupt";
    case Status::kOutOfMemory: return "out-of-memory";
    case Status::kNotFound: return "not-found";
  }
  return "unknown";
}

const char* lodMethodName(LodMethod method) {
  switch (method) {
    case LodMethod::kOriginal: return "original";
    case LodMethod::kUniform: return "uniform";
    case LodMethod::kFloatingHeaviest: return "floating-heaviest";
    case LodMethod::kFloatingNearest: return "floating-nearest";
    case LodMethod::kZhang: return "zhang";
    case LodMethod::kScrooge: return "scrooge";
  }
  return "unknown";
}

}  // namespace scenelod
