#pragma once
// For tests only: Scene::update() computes world spheres eight at a time with AVX2 when the CPU has
// it, else one at a time with SSE; both must give the same bits, and a test compares them.

namespace scenelod::scene::detail {

// Picks the wide (AVX2, when the CPU supports it) or the narrow sphere code for every later
// update() in the process; returns whether the wide code was in use. Not thread-safe.
bool useWideSpheres(bool on);

}  // namespace scenelod::scene::detail
