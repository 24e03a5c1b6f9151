// lodcore's private test hooks: switches between code paths that give the same bits (a fast path
// and its reference), for the tests that compare them and for the bench tools that time them.
// Not part of the API; not thread-safe (set them while no clustering runs).
//
// Each switch sets its choice for every later call and returns the choice it replaces. In a test,
// set one through HookGuard, which restores that choice however the scope ends (a failed ASSERT
// returns from the test body, which would otherwise leave the switch set for later tests):
//
//   detail::HookGuard avx2(detail::useAvx2Paths, false);
//   ASSERT_TRUE(clusterMesh(m, p, base).ok());   // the baseline paths
//   avx2.set(true);                              // still restored at the end of the scope
//
// A test that starts threads must join them before it asserts (a guard's destructor must not run
// while another thread clusters).
#pragma once

namespace scenelod::detail {

// synthesis.cpp: the AVX2 variants of the elimination's classification, of synthesis, of the
// output pass and of the grading pair pass (on, the default where the CPU has AVX2) or their
// baseline builds (off)
bool useAvx2Paths(bool on);
// synthesis.cpp: the quadric solve's eigenvalue cases four clusters at a time in lanes (on, the
// default) or one at a time (off, the reference)
bool useEigenvalueLanes(bool on);
// elimination.cpp: dropping the collapsed triangles whose cluster pair or point repeats the one
// before (on, the default) or looking every one up (off, the reference)
bool useRepeatedEdgeDrop(bool on);
// synthesis.cpp: the grouped pass of fine levels, whose sums take less memory than the single
// pass's (on, the default), or the single pass at every level (off, the reference)
bool useGroupedSynthesis(bool on);
// normals.cpp: the output pass without its shortcuts (on; off is the default)
bool useOutputReference(bool on);
// cluster_mesh.cpp: the renumbering of a level's clusters in space: -1 by size (the default), 0
// never, 1 always
int setRenumberingForTest(int mode);
// chain.cpp: how a chain builds its coarse levels during its w_1 search's first probe: 0 not at
// all, 1 on another thread while the probe runs (the default), 2 all of them before the probe
int setChainSpeculationForTest(int mode);
// chain.cpp: not a switch between equal paths but a fault to exercise a rare one: the levels whose
// bit is set (bit k: level k) are rebuilt by a chain's last step as though they gained primitives
// (0, the default: none)
unsigned setChainRebuildForTest(unsigned levels);
// floating_cell_cluster.cpp: the AVX2 paths of the assignment (on, the default where the CPU has
// AVX2) or its SSE2 (scalar) ones
bool setFloatingAvx2ForTest(bool on);
// floating_cell_cluster.cpp: the bricked grid of side w in blocks: -1 the default, 0 never (the
// hash instead), k > 0 the hash where the vertices' bricks are more than k
int setFloatingBlockBricksForTest(int mode);
// floating_cell_cluster.cpp: the AVX2 grid of side w/2's candidate cache (on, the default) or none
bool setFloatingCacheForTest(bool on);
// floating_cell_cluster.cpp: the candidate cache's runs (cachedRun): -1 the default (where the
// bricks' strides allow them), 0 none, 1 at every cached width they allow
int setFloatingCacheRunsForTest(int runs);
// floating_cell_cluster.cpp: the grid the last assignment searched: 0 a flat one, 1 the bricked
// grid of side w, 2 the hash, 3 the hash where the bricked grid would have taken too many bricks
int lastFloatingGridForTest();

// A switch set for the guard's lifetime: the constructor sets `value`, the destructor restores the
// choice it replaced.
template <typename T>
class HookGuard {
 public:
  HookGuard(T (*hook)(T), T value) : hook_(hook), previous_(hook(value)) {}
  ~HookGuard() { hook_(previous_); }
  HookGuard(const HookGuard&) = delete;
  HookGuard& operator=(const HookGuard&) = delete;
  // a new choice, restored like the first
  void set(T value) { hook_(value); }

 private:
  T (*hook_)(T);
  T previous_;
};

}  // namespace scenelod::detail
