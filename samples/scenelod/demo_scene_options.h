#pragma once
// Options that shape the built-in demo scene, shared by `scenelod demo` and `scenelod demo-scene`.
#include <string>
#include <vector>

#include "args.h"
#include "scenelod/scene/demo_scene.h"

namespace scenelod::tool {

// help text for --bunny, --gearboxes, --bunnies, --segments
extern const char kDemoSceneOptionsHelp[];

// the options readDemoSceneOptions reads (all take a value)
inline std::vector<std::string> demoSceneOptionNames() { return {"--bunny", "--gearboxes", "--bunnies", "--segments"}; }

// Fills `p` from the options (defaults: DemoSceneParams()). Returns false with `error` set when a
// value is not a number or out of range.
bool readDemoSceneOptions(Args& args, scene::DemoSceneParams& p, std::string& error);

}  // namespace scenelod::tool
