// Wavefront OBJ reading and writing: a hand-written line parser over the whole file in memory
// (std::from_chars, no iostreams per token), so a 70k-triangle model loads in milliseconds.
#include "scenelod/lodcore/obj_io.h"

#include "scenelod/lodcore/atomic_file.h"

#include <sys/stat.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <unordered_map>

namespace scenelod {

namespace {

struct FileCloser {
  void operator()(std::FILE* f) const {
    if (f) std::fclose(f);
  }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

Error readWholeFile(const std::string& path, std::string& data) {
  FilePtr f(std::fopen(path.c_str(), "rb"));
  if (!f) return {Status::kIoError, path + ": cannot open file (" + std::strerror(errno) + ")"};
  struct stat st;
  if (::fstat(::fileno(f.get()), &st) != 0 || !S_ISREG(st.st_mode))
    return {Status::kIoError, path + ": cannot open file (not a regular file)"};
  if (std::fseek(f.get(), 0, SEEK_END) != 0) return {Status::kIoError, path + ": cannot seek (not a regular file?)"};
  const long size = std::ftell(f.get());
  if (size < 0) return {Status::kIoError, path + ": cannot tell the file size (not a regular file?)"};
  std::rewind(f.get());
  data.resize(static_cast<size_t>(size));
  if (size > 0 && std::fread(&data[0], 1, data.size(), f.get()) != data.size())
    return {Status::kIoError, path + ": read error"};
  return {};
}

// one corner of a face, line or point: 0-based indices, -1 when absent
struct Corner {
  int64_t v = -1, vt = -1, vn = -1;
};

enum class ElementKind : uint8_t { kFace, kLine, kPoint };

struct Element {
  ElementKind kind;
  uint32_t first_corner;
  uint32_t corner_count;
  uint32_t line;      // source line, for messages
  float thickness;    // from a preceding "#t" comment (lines only)
};

inline bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

class LineParser {
 public:
  LineParser(const char* begin, const char* end) : p_(begin), end_(end) {}
  void skipSpace() {
    while (p_ < end_ && isSpace(*p_)) ++p_;
  }
  bool atEnd() {
    skipSpace();
    return p_ >= end_;
  }
  // the next whitespace-separated token
  std::string_view token() {
    skipSpace();
    const char* b = p_;
    while (p_ < end_ && !isSpace(*p_)) ++p_;
    return std::string_view(b, static_cast<size_t>(p_ - b));
  }

 private:
  const char* p_;
  const char* end_;
};

// parses a whole token as a float; false when malformed
bool parseFloat(std::string_view tok, float& out) {
  const char* b = tok.data();
  const char* e = b + tok.size();
  if (b < e && *b == '+') ++b;  // from_chars refuses a leading '+'
  if (b >= e) return false;
  auto r = std::from_chars(b, e, out);
  if (r.ec == std::errc::result_out_of_range && r.ptr == e) {
    // from_chars leaves the value unset: strtod tells overflow (inf) from underflow (0 or denormal)
    const std::string copy(b, e);
    out = static_cast<float>(std::strtod(copy.c_str(), nullptr));
    return true;
  }
  return r.ec == std::errc() && r.ptr == e;
}

bool parseInt(const char* b, const char* e, int64_t& out) {
  if (b < e && *b == '+') ++b;
  if (b >= e) return false;
  auto r = std::from_chars(b, e, out);
  return r.ec == std::errc() && r.ptr == e;
}

float srgbToLinear(float c) {
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}
float linearToSrgb(float c) {
  if (c <= 0.0f) return 0.0f;
  return c <= 0.0031308f ? c * 12.92f : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

class ObjReader {
 public:
  explicit ObjReader(const std::string& path) : path_(path) {}

  Error read(Mesh& out) {
    std::string data;
    if (Error e = readWholeFile(path_, data); !e.ok()) return e;
    if (Error e = parse(data); !e.ok()) return e;
    return build(out);
  }

 private:
  Error fail(Status s, uint32_t line, const std::string& what) const {
    return {s, path_ + ":" + std::to_string(line) + ": " + what};
  }

  Error parseVector(LineParser& lp, uint32_t line, const char* kind, size_t min_count, size_t max_count, float* out,
                    size_t& count) {
    count = 0;
    while (!lp.atEnd()) {
      const std::string_view tok = lp.token();
      if (count >= max_count)
        return fail(Status::kParseError, line, std::string("too many numbers in '") + kind + "' statement");
      float v;
      if (!parseFloat(tok, v))
        return fail(Status::kParseError, line, "malformed number '" + std::string(tok) + "' in '" + kind + "' statement");
      if (!std::isfinite(v))
        return fail(Status::kInvalidMesh, line, std::string("NaN or infinite coordinate in '") + kind + "' statement");
      out[count++] = v;
    }
    if (count < min_count)
      return fail(Status::kParseError, line, std::string("'") + kind + "' statement needs at least " +
                                                 std::to_string(min_count) + " numbers, has " + std::to_string(count));
    return {};
  }

  // resolves a 1-based or negative OBJ index against the current count; 0-based result
  Error resolveIndex(const char* b, const char* e, size_t current, uint32_t line, const char* what, int64_t& out) {
    int64_t i;
    if (!parseInt(b, e, i))
      return fail(Status::kParseError, line, std::string("malformed ") + what + " index '" + std::string(b, e) + "'");
    if (i == 0) return fail(Status::kInvalidMesh, line, std::string(what) + " index 0 (OBJ indices start at 1)");
    if (i < 0) {
      const int64_t r = static_cast<int64_t>(current) + i;
      if (r < 0)
        return fail(Status::kInvalidMesh, line, std::string("relative ") + what + " index " + std::to_string(i) +
                                                    " reaches before the first of " + std::to_string(current) + " defined so far");
      out = r;
    } else {
      out = i - 1;  // checked against the final count once the file is read (forward references)
    }
    return {};
  }

  Error parseCorners(LineParser& lp, uint32_t line, ElementKind kind, float thickness) {
    Element el{kind, static_cast<uint32_t>(corners_.size()), 0, line, thickness};
    while (!lp.atEnd()) {
      const std::string_view tok = lp.token();
      Corner c;
      const char* b = tok.data();
      const char* e = b + tok.size();
      const char* s1 = static_cast<const char*>(std::memchr(b, '/', tok.size()));
      const char* vend = s1 ? s1 : e;
      if (Error err = resolveIndex(b, vend, positions_.size(), line, "vertex", c.v); !err.ok()) return err;
      if (s1) {
        const char* s2 = static_cast<const char*>(std::memchr(s1 + 1, '/', static_cast<size_t>(e - s1 - 1)));
        const char* tend = s2 ? s2 : e;
        if (tend > s1 + 1)
          if (Error err = resolveIndex(s1 + 1, tend, uvs_.size(), line, "texture coordinate", c.vt); !err.ok()) return err;
        if (s2) {
          if (kind != ElementKind::kFace)
            return fail(Status::kParseError, line, "normal index in a line or point element '" + std::string(tok) + "'");
          if (Error err = resolveIndex(s2 + 1, e, normals_.size(), line, "normal", c.vn); !err.ok()) return err;
        }
      }
      corners_.push_back(c);
      ++el.corner_count;
    }
    const uint32_t need = kind == ElementKind::kFace ? 3 : kind == ElementKind::kLine ? 2 : 1;
    if (el.corner_count < need)
      return fail(Status::kParseError, line,
                  std::string(kind == ElementKind::kFace ? "face" : kind == ElementKind::kLine ? "line" : "point") +
                      " element needs at least " + std::to_string(need) + " corners, has " + std::to_string(el.corner_count));
    if (kind == ElementKind::kFace && el.corner_count > 3) has_polygons_ = true;
    elements_.push_back(el);
    return {};
  }

  // OBJ is text: a control byte other than white space means another format (a GLB renamed .obj) or
  // a damaged file, which would otherwise read as an OBJ whose lines are all unknown statements
  Error checkText(const std::string& data) const {
    for (size_t i = 0; i < data.size(); ++i) {
      const unsigned char c = static_cast<unsigned char>(data[i]);
      if (c < 0x20 && c != '\t' && c != '\n' && c != '\r' && c != '\v' && c != '\f') {
        char hex[8];
        std::snprintf(hex, sizeof hex, "0x%02x", c);
        return {Status::kParseError, path_ + ": binary data (byte " + hex + " at offset " + std::to_string(i) +
                                         "): not an OBJ file"};
      }
    }
    return {};
  }

  Error parse(const std::string& data) {
    if (Error e = checkText(data); !e.ok()) return e;
    const char* p = data.data();
    const char* end = p + data.size();
    uint32_t line = 0;
    float pending_thickness = 0.0f;
    while (p < end) {
      ++line;
      const char* eol = static_cast<const char*>(std::memchr(p, '\n', static_cast<size_t>(end - p)));
      if (!eol) eol = end;
      const char* next = eol < end ? eol + 1 : end;
      // a trailing backslash continues the statement on the next line
      std::string joined;
      const char* le = eol;
      while (le > p && (le[-1] == '\r')) --le;
      if (le > p && le[-1] == '\\') {
        joined.assign(p, le - 1);
        while (next < end) {
          ++line;
          const char* e2 = static_cast<const char*>(std::memchr(next, '\n', static_cast<size_t>(end - next)));
          if (!e2) e2 = end;
          const char* l2 = e2;
          while (l2 > next && l2[-1] == '\r') --l2;
          const bool more = l2 > next && l2[-1] == '\\';
          joined.append(" ").append(next, more ? l2 - 1 : l2);
          next = e2 < end ? e2 + 1 : end;
          if (!more) break;
        }
      }
      const char* lb = joined.empty() ? p : joined.data();
      const char* lend = joined.empty() ? le : joined.data() + joined.size();
      p = next;

      LineParser lp(lb, lend);
      const std::string_view kw = lp.token();
      if (kw.empty()) continue;
      if (kw[0] == '#') {
        // "#t <thickness>": the thickness of the edges of the next l statement
        if (kw == "#t") {
          float t;
          const std::string_view tok = lp.token();
          if (!parseFloat(tok, t)) return fail(Status::kParseError, line, "malformed thickness '" + std::string(tok) + "' in '#t' comment");
          if (!std::isfinite(t) || t < 0.0f) return fail(Status::kInvalidMesh, line, "negative or non-finite thickness in '#t' comment");
          pending_thickness = t;
        }
        continue;
      }
      float v[7];
      size_t n = 0;
      if (kw == "v") {
        if (Error e = parseVector(lp, line, "v", 3, 7, v, n); !e.ok()) return e;
        if (n == 5) return fail(Status::kParseError, line, "'v' statement with 5 numbers (expected x y z [w] or x y z r g b)");
        positions_.emplace_back(v[0], v[1], v[2]);
        if (n >= 6) {
          const size_t c = n == 7 ? 4 : 3;  // x y z w r g b is not standard but seen; colour after w
          if (colors_.size() < positions_.size() - 1) colors_.resize(positions_.size() - 1, glm::vec3(1.0f));
          colors_.emplace_back(srgbToLinear(v[c]), srgbToLinear(v[c + 1]), srgbToLinear(v[c + 2]));
        }
      } else if (kw == "vn") {
        if (Error e = parseVector(lp, line, "vn", 3, 3, v, n); !e.ok()) return e;
        normals_.emplace_back(v[0], v[1], v[2]);
      } else if (kw == "vt") {
        if (Error e = parseVector(lp, line, "vt", 1, 3, v, n); !e.ok()) return e;
        uvs_.emplace_back(v[0], n > 1 ? v[1] : 0.0f);
      } else if (kw == "f") {
        if (Error e = parseCorners(lp, line, ElementKind::kFace, 0.0f); !e.ok()) return e;
      } else if (kw == "l") {
        if (Error e = parseCorners(lp, line, ElementKind::kLine, pending_thickness); !e.ok()) return e;
        pending_thickness = 0.0f;
      } else if (kw == "p") {
        if (Error e = parseCorners(lp, line, ElementKind::kPoint, 0.0f); !e.ok()) return e;
      }
      // o, g, s, usemtl, mtllib, vp, curves and anything else: skipped
    }
    if (positions_.empty() && elements_.empty())
      return {Status::kParseError, path_ + ": no vertices and no elements (v, f, l or p statements): an empty OBJ or not an OBJ file"};
    if (!colors_.empty()) colors_.resize(positions_.size(), glm::vec3(1.0f));
    return {};
  }

  // one vertex per distinct (v, vt, vn); position p keeps vertex index p for its first combination
  // so files without vt/vn keep their vertex order, further combinations are appended
  Error build(Mesh& out) {
    const size_t np = positions_.size();
    bool any_uv = false, any_normal = false;
    for (const Element& el : elements_) {
      for (uint32_t i = 0; i < el.corner_count; ++i) {
        const Corner& c = corners_[el.first_corner + i];
        if (c.v >= static_cast<int64_t>(np))
          return fail(Status::kInvalidMesh, el.line, "vertex index " + std::to_string(c.v + 1) + " out of range (the file has " +
                                                         std::to_string(np) + " vertices)");
        if (c.vt >= static_cast<int64_t>(uvs_.size()))
          return fail(Status::kInvalidMesh, el.line, "texture coordinate index " + std::to_string(c.vt + 1) +
                                                         " out of range (the file has " + std::to_string(uvs_.size()) + ")");
        if (c.vn >= static_cast<int64_t>(normals_.size()))
          return fail(Status::kInvalidMesh, el.line, "normal index " + std::to_string(c.vn + 1) +
                                                         " out of range (the file has " + std::to_string(normals_.size()) + ")");
        if (el.kind == ElementKind::kFace) {
          any_uv |= c.vt >= 0;
          any_normal |= c.vn >= 0;
        }
      }
    }
    if (np > UINT32_MAX / 2) return {Status::kUnsupported, path_ + ": too many vertices"};

    out = Mesh{};
    out.positions = positions_;
    if (!colors_.empty()) out.colors = colors_;
    if (any_normal) out.normals.assign(np, glm::vec3(0.0f));
    if (any_uv) out.uvs.assign(np, glm::vec2(0.0f));

    // first combination used by each position; -2 = none yet
    std::vector<int64_t> first_vt(np, -2), first_vn(np, -2);
    struct Key {
      int64_t v, vt, vn;
      bool operator==(const Key& o) const { return v == o.v && vt == o.vt && vn == o.vn; }
    };
    struct KeyHash {
      size_t operator()(const Key& k) const {
        uint64_t h = static_cast<uint64_t>(k.v) * 0x9E3779B97F4A7C15ull;
        h ^= static_cast<uint64_t>(k.vt + 1) * 0xC2B2AE3D27D4EB4Full + (h << 6) + (h >> 2);
        h ^= static_cast<uint64_t>(k.vn + 1) * 0x165667B19E3779F9ull + (h << 6) + (h >> 2);
        return static_cast<size_t>(h);
      }
    };
    std::unordered_map<Key, uint32_t, KeyHash> extra;
    auto vertexOf = [&](const Corner& c) -> uint32_t {
      const size_t p = static_cast<size_t>(c.v);
      if (first_vt[p] == -2) {
        first_vt[p] = c.vt;
        first_vn[p] = c.vn;
        if (c.vt >= 0) out.uvs[p] = uvs_[static_cast<size_t>(c.vt)];
        if (c.vn >= 0) out.normals[p] = normals_[static_cast<size_t>(c.vn)];
        return static_cast<uint32_t>(p);
      }
      if (first_vt[p] == c.vt && first_vn[p] == c.vn) return static_cast<uint32_t>(p);
      auto it = extra.find(Key{c.v, c.vt, c.vn});
      if (it != extra.end()) return it->second;
      const uint32_t idx = static_cast<uint32_t>(out.positions.size());
      out.positions.push_back(positions_[p]);
      if (!out.colors.empty()) out.colors.push_back(colors_[p]);
      if (any_uv) out.uvs.push_back(c.vt >= 0 ? uvs_[static_cast<size_t>(c.vt)] : glm::vec2(0.0f));
      if (any_normal) out.normals.push_back(c.vn >= 0 ? normals_[static_cast<size_t>(c.vn)] : glm::vec3(0.0f));
      extra.emplace(Key{c.v, c.vt, c.vn}, idx);
      return idx;
    };

    bool any_thick = false;
    for (const Element& el : elements_) any_thick |= el.kind == ElementKind::kLine && el.thickness > 0.0f;
    if (has_polygons_) out.face_offsets.push_back(0);
    for (const Element& el : elements_) {
      const Corner* c = &corners_[el.first_corner];
      switch (el.kind) {
        case ElementKind::kFace:
          if (has_polygons_) {
            for (uint32_t i = 0; i < el.corner_count; ++i) out.face_corners.push_back(vertexOf(c[i]));
            out.face_offsets.push_back(static_cast<uint32_t>(out.face_corners.size()));
          } else {
            for (uint32_t i = 0; i < 3; ++i) out.triangles.push_back(vertexOf(c[i]));
          }
          break;
        case ElementKind::kLine: {
          // lines and points carry no normal: they use vertex p of position p and never split it
          uint32_t prev = static_cast<uint32_t>(c[0].v);
          for (uint32_t i = 1; i < el.corner_count; ++i) {
            const uint32_t cur = static_cast<uint32_t>(c[i].v);
            out.edges.push_back(prev);
            out.edges.push_back(cur);
            if (any_thick) out.edge_thickness.push_back(el.thickness);
            prev = cur;
          }
          break;
        }
        case ElementKind::kPoint:
          for (uint32_t i = 0; i < el.corner_count; ++i) out.points.push_back(static_cast<uint32_t>(c[i].v));
          break;
      }
    }
    if (has_polygons_) triangulateFaces(out);
    return validateMesh(out, path_);
  }

  std::string path_;
  std::vector<glm::vec3> positions_, normals_, colors_;
  std::vector<glm::vec2> uvs_;
  std::vector<Corner> corners_;
  std::vector<Element> elements_;
  bool has_polygons_ = false;
};

// appends a float written with the shortest text that reads back to the same float
void appendFloat(std::string& s, float v) {
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof(buf), v);
  s.append(buf, r.ptr);
}
void appendUint(std::string& s, uint64_t v) {
  char buf[24];
  auto r = std::to_chars(buf, buf + sizeof(buf), v);
  s.append(buf, r.ptr);
}

}  // namespace

Error readObj(const std::string& path, Mesh& out) {
  try {
    ObjReader reader(path);
    return reader.read(out);
  } catch (const std::bad_alloc&) {
    return {Status::kOutOfMemory, path + ": out of memory while reading"};
  } catch (const std::exception& e) {
    return {Status::kParseError, path + ": " + e.what()};
  }
}

Error writeObj(const std::string& path, const Mesh& mesh) {
  if (Error e = validateMesh(mesh, path); !e.ok()) return e;
  try {
    std::string s;
    s.reserve(mesh.positions.size() * 40 + mesh.triangles.size() * 8 + 256);
    s += "# written by scenelod\n";
    if (!mesh.edge_thickness.empty())
      s += "# '#t <thickness>' before an 'l' line gives the thickness of that edge (OBJ has no edge thickness)\n";
    const bool colors = !mesh.colors.empty();
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
      const glm::vec3& p = mesh.positions[i];
      s += "v ";
      appendFloat(s, p.x), s += ' ', appendFloat(s, p.y), s += ' ', appendFloat(s, p.z);
      if (colors) {
        const glm::vec3& c = mesh.colors[i];
        s += ' ', appendFloat(s, linearToSrgb(c.x)), s += ' ', appendFloat(s, linearToSrgb(c.y)), s += ' ',
            appendFloat(s, linearToSrgb(c.z));
      }
      s += '\n';
    }
    for (const glm::vec2& t : mesh.uvs) {
      s += "vt ", appendFloat(s, t.x), s += ' ', appendFloat(s, t.y), s += '\n';
    }
    for (const glm::vec3& n : mesh.normals) {
      s += "vn ", appendFloat(s, n.x), s += ' ', appendFloat(s, n.y), s += ' ', appendFloat(s, n.z), s += '\n';
    }
    const bool uv = !mesh.uvs.empty(), nrm = !mesh.normals.empty();
    auto corner = [&](uint32_t i) {
      s += ' ';
      appendUint(s, uint64_t(i) + 1);
      if (uv || nrm) {
        s += '/';
        if (uv) appendUint(s, uint64_t(i) + 1);
        if (nrm) s += '/', appendUint(s, uint64_t(i) + 1);
      }
    };
    if (mesh.faceCount() > 0) {
      for (size_t f = 0; f < mesh.faceCount(); ++f) {
        s += 'f';
        for (uint32_t k = mesh.face_offsets[f]; k < mesh.face_offsets[f + 1]; ++k) corner(mesh.face_corners[k]);
        s += '\n';
      }
    } else {
      for (size_t t = 0; t + 2 < mesh.triangles.size(); t += 3) {
        s += 'f', corner(mesh.triangles[t]), corner(mesh.triangles[t + 1]), corner(mesh.triangles[t + 2]);
        s += '\n';
      }
    }
    auto plain = [&](uint32_t i) {
      s += ' ';
      appendUint(s, uint64_t(i) + 1);
    };
    for (size_t e = 0; e < mesh.edgeCount(); ++e) {
      const float t = mesh.edgeThickness(e);
      if (t > 0.0f) s += "#t ", appendFloat(s, t), s += '\n';
      s += 'l', plain(mesh.edges[2 * e]), plain(mesh.edges[2 * e + 1]), s += '\n';
    }
    for (uint32_t p : mesh.points) s += 'p', plain(p), s += '\n';

    return writeFileAtomic(path, s.data(), s.size());
  } catch (const std::bad_alloc&) {
    return {Status::kOutOfMemory, path + ": out of memory while writing"};
  }
}

}  // namespace scenelod
