#pragma once
// Wavefront OBJ input and output.
//
// Reads v, vn, vt, f (polygons kept as faces and triangulated), negative (relative) indices, l and p
// elements; other statements (o, g, s, usemtl, mtllib) are skipped. Writes f, l and p. OBJ has no
// way to hold an edge's thickness: the writer adds a comment line per thick edge ("#t <thickness>")
// that this reader understands and other readers ignore.
#include <string>

#include "scenelod/lodcore/mesh.h"
#include "scenelod/lodcore/status.h"

namespace scenelod {

// Reads an OBJ file into `out`. Attributes indexed separately by f (v/vt/vn) are unified into one
// vertex per distinct (v, vt, vn) triple: vertex i is the i-th `v` line with the first (vt, vn) it
// is used with, further combinations are appended, so a file without vt/vn keeps its vertex order
// and count (unreferenced vertices included). l and p elements use vertex i of position i (they
// carry no normal). Faces with more than 3 corners make the mesh keep every face in
// face_offsets/face_corners and triangulate them (triangulateFaces); all-triangle files fill only
// triangles. "v x y z r g b" colours are read as sRGB in [0,1] and stored linear. Errors name the
// file, the line and the problem (missing file, index out of range or 0, NaN or infinite coordinate,
// malformed number, too few corners). Cost: reads the whole file into memory, one pass, O(size).
Error readObj(const std::string& path, Mesh& out);

// Writes `mesh` as OBJ (v with sRGB colours when present, vt and vn when present, f for the original
// faces when the mesh has them or else triangles, l per edge preceded by "#t" when thick, p). Floats
// are written in their shortest exact form, so readObj gets the same positions back.
Error writeObj(const std::string& path, const Mesh& mesh);

}  // namespace scenelod
