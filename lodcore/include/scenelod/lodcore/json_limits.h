#pragma once
// Limits every JSON reader of scenelod applies to what it is given (glTF, replays, level scenes):
// - how deeply a text nests, found by one scan without recursion, so that a reader can refuse a
//   hostile document (a 40 KB file of 20,000 nested arrays) before any recursive parse, copy or
//   conversion of it overflows the stack;
// - whole numbers read strictly: integral and in range, so that 2^32 + 1 never wraps to 1 and 1e300
//   is never converted to an integer (undefined behaviour).
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace scenelod {

// The deepest nesting of arrays and objects in `text` (0 for a scalar), skipping brackets inside
// strings. Malformed text gets a number all the same; the parser reports the malformation.
// Cost: one pass over the bytes, no allocation.
size_t jsonNestingDepth(const char* text, size_t size);

// The readers' limit: glTF, replays and level scenes nest a handful of levels; extras and
// extensions written by other tools get room to spare.
constexpr size_t kMaxJsonNesting = 64;

// `v` (a nlohmann::json value; a template so that this header names no third-party type) as an
// integer in [lo, hi]: JSON integers as stored, floating-point values only when integral and at most
// 2^53, where doubles stop being exact. Returns false otherwise, leaving `out` untouched.
template <class Json>
bool jsonWholeNumber(const Json& v, int64_t lo, int64_t hi, int64_t& out) {
  if (v.is_number_unsigned()) {
    const uint64_t u = v.template get<uint64_t>();
    if (u > static_cast<uint64_t>(INT64_MAX) || static_cast<int64_t>(u) < lo || static_cast<int64_t>(u) > hi) return false;
    out = static_cast<int64_t>(u);
    return true;
  }
  if (v.is_number_integer()) {
    const int64_t i = v.template get<int64_t>();
    if (i < lo || i > hi) return false;
    out = i;
    return true;
  }
  if (v.is_number_float()) {
    const double d = v.template get<double>();
    if (!(std::fabs(d) <= 9007199254740992.0) || d != std::floor(d) || d < static_cast<double>(lo) ||
        d > static_cast<double>(hi))
      return false;
    out = static_cast<int64_t>(d);
    return true;
  }
  return false;
}

}  // namespace scenelod
