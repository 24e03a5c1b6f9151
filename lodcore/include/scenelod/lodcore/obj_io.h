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
// vertex per distinct (v, vt, vn) triple. Errors name the file, the line and the problem (missing
// file, index out of range or 0, NaN or infinite coordinate, malformed number).
Error readObj(const std::string& path, Mesh& out);

// Writes `mesh` as OBJ (v, vn when present, f for triangles or the original faces, l, p).
Error writeObj(const std::string& path, const Mesh& mesh);

}  // namespace scenelod
