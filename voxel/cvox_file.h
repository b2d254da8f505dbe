#pragma once
// The voxel model file (.cvox): a header, a block table, then each block's data. Blocks are
// independently addressable (byte ranges in the table), so a renderer can stream them in any
// order (lod/); the table also carries each block's level and tight voxel bounds, which culling
// reads without touching voxel data.
//
// Layout (little-endian; docs/formats.md has the table):
//   header, 96 bytes: "CVOX", version, resolution, block size, level count, separability,
//                     flags (1: colours from the source, 2: source triangles), origin (3 double),
//                     extent (double), block count, voxel count, triangle count, reserved
//   block table, 64 bytes per block: level, coord (3 uint32), voxel count, triangle count,
//                     voxel byte offset, triangle byte offset, tight min and max (3+3 uint8), reserved
//   block data: packed voxels, normals, colours (uint32 each), then source triangles
//               (3 positions float32 x3, 3 normals, 3 colours: 60 bytes each)

#include <filesystem>
#include <ostream>

#include "voxel/voxel_model.h"

namespace cuberille::voxel {

/// Throws std::runtime_error when the stream fails.
void writeCvox(const VoxelModel& model, std::ostream& out);

/// Reads a whole .cvox file. A truncated or corrupted file throws scene::InputError naming the
/// file, the block or field, and the byte offset.
VoxelModel readCvox(const std::filesystem::path& path);

}  // namespace cuberille::voxel
