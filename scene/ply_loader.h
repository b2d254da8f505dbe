#pragma once
// PLY meshes (the format of the big scans): ASCII, binary little- and big-endian, optionally
// gzip-compressed (`.ply.gz`). Reads vertex x y z (any numeric type), nx ny nz, red green blue
// (8-bit or float, sRGB-encoded, converted to linear), faces from the list property
// `vertex_indices` (or `vertex_index`) of a `face` element, polygons becoming triangle fans, and
// triangle strips from the same list of a `tristrips` element (-1 restarts a strip, winding
// alternates along it, the zero-area joins are dropped). Other elements and properties are
// skipped. Normals are computed when the file has none. Every reader of meshes (render, pack,
// voxelize) reads PLY through this one function.
//
// Bad input throws InputError naming the file, the place (header line, or element and index
// with its byte offset) and the problem. Counts are checked against the bytes left before any
// allocation, so a corrupt header cannot make the reader allocate more than the file implies.

#include <filesystem>
#include <string>
#include <string_view>

#include "scene/mesh.h"

namespace cuberille::scene {

Mesh parsePly(std::string_view bytes, const std::string& fileName);
/// Reads the file (decompressing `.gz`) and parses it.
Mesh loadPly(const std::filesystem::path& path);

/// The whole file, decompressed when it ends in `.gz`; throws InputError on failure.
std::string readFileBytes(const std::filesystem::path& path);

}  // namespace cuberille::scene
