#pragma once
// Progress reporting for long offline work (chains, whole-scene precompute, benchmarks).

namespace scenelod {

// Called with the fraction done in [0, 1] and a short stage label. May be called from worker threads,
// but never concurrently: implementations need no lock. Null fn means no reporting.
struct ProgressCallback {
  void (*fn)(void* user, double fraction, const char* stage) = nullptr;
  void* user = nullptr;

  void operator()(double fraction, const char* stage) const {
    if (fn) fn(user, fraction, stage);
  }
};

}  // namespace scenelod
