#pragma once
// `scenelod eval --animated MODEL [LEVEL...]`: the geometric error of a skinned model's levels in
// motion, next to the same levels' error in the bind pose (eval_animated.cpp).
#include <string>
#include <vector>

namespace scenelod::tool {

// Builds the chain of every mesh drawn with a skin (buildChain, `level_count` simplified levels),
// poses the original and each level (all, or the indices in `level_args`) at 16 evenly spaced times
// of every animation and prints, per level, the bind-pose Hausdorff distance and the worst posed
// one. Returns the process exit code.
int runAnimatedEval(const std::string& path, const std::vector<std::string>& level_args, long level_count,
                    long samples, bool json);

}  // namespace scenelod::tool
