#pragma once
// How deeply a JSON text nests, found by one scan without recursion, so that a reader can refuse a
// hostile document (a 40 KB file of 20,000 nested arrays) before any recursive parse, copy or
// conversion of it overflows the stack.
#include <cstddef>

namespace scenelod {

// The deepest nesting of arrays and objects in `text` (0 for a scalar), skipping brackets inside
// strings. Malformed text gets a number all the same; the parser reports the malformation.
// Cost: one pass over the bytes, no allocation.
size_t jsonNestingDepth(const char* text, size_t size);

// The readers' limit: glTF, replays and level scenes nest a handful of levels; extras and
// extensions written by other tools get room to spare.
constexpr size_t kMaxJsonNesting = 64;

}  // namespace scenelod
