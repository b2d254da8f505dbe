#pragma once
// A partial voxelization (voxel/octree_voxelizer.h: voxelizeChunks) as a file, so the workers of a
// distributed voxelization hand their parts to the merge through the file system they share
// instead of through the scheduler's memory. A working file, not an exchange format: little-endian,
// read back by the same build, every read bounds-checked (a truncated part is an InputError naming
// the file, the byte and the field).
//
//   "CVXP" u32 version
//   header: u32 resolution, f64 origin[3], f64 extent, u32 blockSize, u32 separability, u8 hasColors
//   u64 firstChunk, u64 chunkCount, u64 winding volume, u64 winding area[3] (WindingSums), u64 blocks
//   per block: u32 coord[3], u64 leaves, u32 leafMorton[leaves],
//              per leaf i64 normal[3], i64 weight, u8 faceMask, u8 targets,
//              with colours per leaf i64 rgb[3],
//              u64 triangles, u64 keys[triangles], SourceTriangle[triangles] (60 bytes each)

#include <filesystem>
#include <ostream>

#include "voxel/octree_voxelizer.h"

namespace cuberille::voxel {

void writePartialVoxelization(const PartialVoxelization& part, std::ostream& out);

/// The part's blocks whose Morton code (of their finest-level block coordinates) lies in
/// [mortonBegin, mortonEnd): a distributed voxelization merges the model a range of blocks at a
/// time (lod/pyramid_ranges.h), each range from every part. The blocks outside are stepped over by
/// their counts, not read; the part's header and chunk run are read whatever the range.
PartialVoxelization readPartialVoxelization(const std::filesystem::path& path, uint64_t mortonBegin = 0,
                                            uint64_t mortonEnd = UINT64_MAX);

/// A part's header and chunk run (no blocks), and each block as (Morton code, bytes in the file)
/// in the part's (Morton) order: what planning the ranges weighs (lod::planPyramidRanges), read
/// without reading the blocks.
struct PartialVoxelizationIndex {
    PartialVoxelization part;
    std::vector<std::pair<uint64_t, uint64_t>> blocks;
};
PartialVoxelizationIndex readPartialVoxelizationIndex(const std::filesystem::path& path);

}  // namespace cuberille::voxel
