#pragma once
// Strict reading of JSON numbers for the replay and level-scene readers. A whole number must be
// integral and inside its range, or the reader refuses it naming the key: 2^32 + 1 must not wrap to
// 1, and 1e300 must not be converted to an integer (undefined behaviour).
#include <cmath>
#include <cstdint>

#include <nlohmann/json.hpp>

namespace scenelod::selection::detail {

// `v` as an integer in [lo, hi]: JSON integers as stored, floating-point values only when integral
// (and at most 2^53, where doubles stop being exact). Returns false otherwise, `out` untouched.
inline bool wholeNumber(const nlohmann::json& v, int64_t lo, int64_t hi, int64_t& out) {
  if (v.is_number_unsigned()) {
    const uint64_t u = v.get<uint64_t>();
    if (u > static_cast<uint64_t>(INT64_MAX) || static_cast<int64_t>(u) < lo || static_cast<int64_t>(u) > hi)
      return false;
    out = static_cast<int64_t>(u);
    return true;
  }
  if (v.is_number_integer()) {
    const int64_t i = v.get<int64_t>();
    if (i < lo || i > hi) return false;
    out = i;
    return true;
  }
  if (v.is_number_float()) {
    const double d = v.get<double>();
    const double exact = 9007199254740992.0;  // 2^53
    if (!(std::fabs(d) <= exact) || d != std::floor(d) || d < static_cast<double>(lo) || d > static_cast<double>(hi))
      return false;
    out = static_cast<int64_t>(d);
    return true;
  }
  return false;
}

// the largest coordinate the readers take: its square (distances) stays finite in float
constexpr double kMaxCoordinate = 1e18;

}  // namespace scenelod::selection::detail
