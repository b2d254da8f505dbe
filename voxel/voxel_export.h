#pragma once
// `--export-voxels`: the finest level's voxels as text, for checking against other tools. The
// first line is `# cuberille voxels R ox oy oz extent` (the grid's resolution, origin and edge
// length in model units, printed so that they read back to the same doubles); then one line
// `i j k` per voxel, grid coordinates, in the file's block order.

#include <filesystem>
#include <ostream>
#include <vector>

#include <glm/glm.hpp>

#include "voxel/voxel_model.h"

namespace cuberille::voxel {

void writeVoxelExport(const VoxelModel& model, std::ostream& out);
/// writeVoxelExport a block at a time (lod/pyramid_ranges.h): the first line, then each level-0
/// block's lines in the file's block order (only the block's coordinates and voxels are read).
void writeVoxelExportHeader(const VoxelGrid& grid, std::ostream& out);
void appendVoxelExportLines(const VoxelBlock& block, uint32_t blockSize, std::string& text);

struct VoxelExport {
    VoxelGrid grid;
    std::vector<glm::uvec3> voxels;
};

/// Throws scene::InputError naming the file and line for malformed text.
VoxelExport readVoxelExport(const std::filesystem::path& path);

}  // namespace cuberille::voxel
