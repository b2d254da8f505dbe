#pragma once
// A partial voxelization (voxel/octree_voxelizer.h: voxelizeChunks) as a file, so the workers of a
// distributed voxelization hand their parts to the merge through the file system they share
// instead of through the scheduler's memory. A working file, not an exchange format: little-endian,
// read back by the same build, every read bounds-checked (a truncated part is an InputError naming
// the file, the byte and the field).
//
//   "CVXP" u32 version
//   header: u32 resolution, f64 origin[3], f64 extent, u32 blockSize, u32 separability, u8 hasColors
//   u64 firstChunk, u64 chunkCount, u64 blocks
//   per block: u32 coord[3], u64 leaves, u32 leafMorton[leaves],
//              per leaf i64 normal[3], i64 weight, u8 faceMask, u8 targets,
//              with colours per leaf i64 rgb[3],
//              u64 triangles, u64 keys[triangles], SourceTriangle[triangles] (60 bytes each)

#include <filesystem>
#include <ostream>

#include "voxel/octree_voxelizer.h"

namespace cuberille::voxel {

void writePartialVoxelization(const PartialVoxelization& part, std::ostream& out);
PartialVoxelization readPartialVoxelization(const std::filesystem::path& path);

}  // namespace cuberille::voxel
