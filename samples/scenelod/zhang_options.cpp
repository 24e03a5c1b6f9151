#include "zhang_options.h"

namespace scenelod::tool {

const char kZhangOptionsHelp[] =
    "  with --method zhang (vision-characteristic edge collapse, Zhang, Shu & Luo 2003):\n"
    "  --zhang-placement P  interpolated (the paper: by CA, default) or neighbour (onto the chosen\n"
    "                       neighbour; lower error on the bunny, docs/bench/zhang.md)\n"
    "  --zhang-mode M       edge (edge collapse, default) or triangle (the triangle-decimation extension)\n"
    "  --zhang-influence I  ca (vision characteristic, default) or sh (super height) orders the queue\n"
    "  --keep-corners B     yes keeps angle vertices (corners) fixed; no (default) processes them\n"
    "  --zhang-ring B       yes (default) scores a candidate collapse by the CA it gives the merged vertex\n"
    "                       and the ring vertices of the changed triangles (Fig. 6); no: the merged one only\n"
    "  --weld B             yes joins vertices at the same position first, for meshes without texture\n"
    "                       coordinates, tangents, a skin or several groups; those are always welded\n"
    "                       with their seams kept (docs/ZHANG.md); no (default)\n";

bool parseZhangOptions(const Args& args, ZhangParams& p, std::string& error) {
  p = ZhangParams();
  const std::string placement = args.get("--zhang-placement", "interpolated");
  if (placement == "interpolated") p.placement = ZhangPlacement::kInterpolated;
  else if (placement == "neighbour" || placement == "neighbor") p.placement = ZhangPlacement::kNeighbour;
  else {
    error = "unknown --zhang-placement '" + placement + "' (interpolated, neighbour)";
    return false;
  }
  const std::string mode = args.get("--zhang-mode", "edge");
  if (mode == "edge") p.mode = ZhangMode::kEdgeCollapse;
  else if (mode == "triangle") p.mode = ZhangMode::kTriangleDecimation;
  else {
    error = "unknown --zhang-mode '" + mode + "' (edge, triangle)";
    return false;
  }
  const std::string influence = args.get("--zhang-influence", "ca");
  if (influence == "ca") p.influence = ZhangInfluence::kVisionCharacteristic;
  else if (influence == "sh") p.influence = ZhangInfluence::kSuperHeight;
  else {
    error = "unknown --zhang-influence '" + influence + "' (ca, sh)";
    return false;
  }
  const std::string corners = args.get("--keep-corners", "no");
  if (corners == "yes") p.keep_angle_vertices = true;
  else if (corners == "no") p.keep_angle_vertices = false;
  else {
    error = "--keep-corners takes yes or no, not '" + corners + "'";
    return false;
  }
  const std::string ring = args.get("--zhang-ring", "yes");
  if (ring == "yes") p.ring_vision = true;
  else if (ring == "no") p.ring_vision = false;
  else {
    error = "--zhang-ring takes yes or no, not '" + ring + "'";
    return false;
  }
  const std::string weld = args.get("--weld", "no");
  if (weld == "yes") p.weld_positions = true;
  else if (weld == "no") p.weld_positions = false;
  else {
    error = "--weld takes yes or no, not '" + weld + "'";
    return false;
  }
  return true;
}

}  // namespace scenelod::tool
