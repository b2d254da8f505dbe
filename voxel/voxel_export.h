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

struct VoxelExport {
    VoxelGrid grid;
    std::vector<glm::uvec3> voxels;
};

/// Throws scene::InputError naming the file and line for malformed text.
VoxelExport readVoxelExport(const std::filesystem::path& path);

}  // namespace cuberille::voxel
