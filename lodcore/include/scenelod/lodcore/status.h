#pragma once
// Status codes for failures that can really happen (bad files, degenerate input, out of memory).
// Broken preconditions in hot code are programming errors and only assert in debug builds.
#include <string>

namespace scenelod {

enum class Status : int {
  kOk = 0,
  kInvalidArgument,  // a parameter out of range (cell width <= 0, target count 0, ...)
  kInvalidMesh,      // NaN/inf coordinate, index out of range, mismatched attribute sizes
  kIoError,          // missing file, unreadable, cannot write
  kParseError,       // malformed file content
  kUnsupported,      // valid input we do not handle (primitive mode, extension)
  kCorrupt,          // truncated or checksum-failing binary data
  kOutOfMemory,
  kNotFound,         // stale handle, unknown object
};

// Short stable name of a status ("invalid-mesh"), for messages and logs.
const char* statusName(Status status);

// A status with a human-readable message naming the file (when there is one) and the problem.
// Offline APIs return it; the message is empty on success.
struct Error {
  Status status = Status::kOk;
  std::string message;

  Error() = default;
  Error(Status s, std::string m) : status(s), message(std::move(m)) {}
  bool ok() const { return status == Status::kOk; }
};

}  // namespace scenelod
