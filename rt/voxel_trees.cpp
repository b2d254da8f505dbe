// Names of the voxel acceleration structures, as the command line and the benchmark spell them.

#include "rt/voxel_trees.h"

namespace cuberille::rt {

const char* voxelStructureName(VoxelStructure s) {
    switch (s) {
        case VoxelStructure::Bvh: return "bvh";
        case VoxelStructure::KdTree: return "kdtree";
        case VoxelStructure::Octree: return "octree";
    }
    return "?";
}

bool parseVoxelStructure(const std::string& name, VoxelStructure* out) {
    for (VoxelStructure s : {VoxelStructure::Bvh, VoxelStructure::KdTree, VoxelStructure::Octree})
        if (name == voxelStructureName(s)) {
            *out = s;
            return true;
        }
    return false;
}

}  // namespace cuberille::rt
