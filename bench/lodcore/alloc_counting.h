#pragma once
// The allocation counters of the lodcore benchmark program: cluster_bench.cpp replaces the global
// operator new and delete and counts the bytes they hold (malloc_usable_size), so that any of the
// program's benchmarks can measure a peak.
namespace scenelod::bench {

long long allocatedBytes();       // held through operator new now
long long resetAllocationPeak();  // sets the peak to the bytes held now, and returns them
long long allocationPeak();       // the most held since the last reset

}  // namespace scenelod::bench
