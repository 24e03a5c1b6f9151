#pragma once
// Internal to the glTF reader and writer: the checked tinygltf model of a file, for the export
// that keeps an input file and adds LOD levels to it.
#include <cstdint>
#include <string>
#include <vector>

#include <tiny_gltf.h>

#include "scenelod/lodcore/status.h"

namespace scenelod::scene::detail {

// A file's tinygltf model after every check importGltf makes before reading it (container,
// hostile JSON, URIs inside the folder, required geometry extensions refused), and the encoded
// bytes of every image as the file holds them (empty when an external image is missing).
struct GltfFile {
  tinygltf::Model model;
  std::vector<std::vector<uint8_t>> image_bytes;
  std::vector<std::string> read_paths;  // every file read: the glTF itself, buffers, images
};

Error loadGltfFile(const std::string& path, GltfFile& out);

// the MIME type of encoded image bytes: PNG and JPEG by their signatures, else `declared`
std::string imageMimeType(const std::vector<uint8_t>& bytes, const std::string& declared);

}  // namespace scenelod::scene::detail
