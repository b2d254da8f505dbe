#pragma once
// Geometry streams (.cgs; Chajdas 2015, section 3.1.1): a file of independent geometry chunks,
// each a fixed-size header (format, counts, bounds, payload size) followed by its vertex and
// index data compressed as one LZ4 frame with a content checksum. A reader walks the headers
// alone to learn the whole file's layout and bounds, then decompresses chunks on demand, in any
// order and from any thread; a voxelizer thread steals the next chunk when it is done.
//
// Layout (little-endian; docs/formats.md has the table):
//   file header, 32 bytes: "CGS1", version, chunk count, triangle count, reserved
//   per chunk: header, 64 bytes: "CHNK", flags, vertex count, triangle count, bounds (6 float),
//              raw bytes, compressed bytes, reserved; then the compressed payload
//   payload (raw): positions float32 x3, normals 10-10-10, [colours sRGB RGB8, padded to 4],
//                  indices uint16 when the chunk has at most 65536 vertices, else uint32

#include <cstdint>
#include <filesystem>
#include <memory>
#include <ostream>

#include "voxel/mesh_view.h"

namespace cuberille::voxel {

struct GeometryStreamWriteStats {
    uint64_t chunks = 0, triangles = 0, vertices = 0;
    uint64_t rawBytes = 0, compressedBytes = 0;
};

/// Writes every chunk of the view, in order, to out. Throws std::runtime_error when the stream
/// fails.
GeometryStreamWriteStats writeGeometryStream(const MeshView& view, std::ostream& out);

/// Opens a .cgs file: reads and checks every chunk header (a truncated file, a bad magic or
/// sizes that do not add up throw scene::InputError naming the file, chunk and byte offset).
/// Chunks are decompressed and checked (checksum, index range) when read.
std::unique_ptr<MeshView> openGeometryStream(const std::filesystem::path& path);

}  // namespace cuberille::voxel
