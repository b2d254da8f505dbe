// What the voxel trees share outside their builds and traversals: voxels' bounds, and the
// structures' names as the command line and the benchmark spell them.

#include "rt/voxel_trees.h"

namespace cuberille::rt {

VoxelBounds voxelBounds(std::span<const VoxelCoord> voxels) {
    VoxelBounds b;
    for (const VoxelCoord& v : voxels) {
        const glm::ivec3 p(v.x, v.y, v.z);
        b.lo = glm::min(b.lo, p);
        b.hi = glm::max(b.hi, p + 1);
    }
    return b;
}

const char* voxelStructureName(VoxelStructure s) {
    switch (s) {
        case VoxelStructure::Bvh: return "bvh";
        case VoxelStructure::KdTree: return "kdtree";
        case VoxelStructure::Octree: return "octree";
        case VoxelStructure::WideBvh: return "bvh8";
    }
    return "?";
}

bool parseVoxelStructure(const std::string& name, VoxelStructure* out) {
    for (VoxelStructure s : {VoxelStructure::Bvh, VoxelStructure::KdTree, VoxelStructure::Octree, VoxelStructure::WideBvh})
        if (name == voxelStructureName(s)) {
            *out = s;
            return true;
        }
    return false;
}

}  // namespace cuberille::rt
