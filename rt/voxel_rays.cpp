// The reference every voxel traversal is tested against, and the lockstep-lane simulation the
// voxel benchmark reports beside Chajdas's GPU coherency.

#include "rt/voxel_rays.h"

#include <algorithm>

namespace cuberille::rt {

VoxelHit closestVoxelBruteForce(std::span<const VoxelCoord> voxels, const VoxelRay& ray) {
    VoxelHit best;
    for (uint32_t i = 0; i < voxels.size(); ++i) offerVoxel(ray, voxels[i], i, best);
    return best;
}

LaneOccupancy voxelLaneOccupancy(std::span<const VoxelStepTrace> rayTraces, int lanes) {
    LaneOccupancy o;
    for (size_t first = 0; first < rayTraces.size(); first += size_t(lanes)) {
        const size_t last = std::min(rayTraces.size(), first + size_t(lanes));
        size_t iterations = 0;
        for (size_t r = first; r < last; ++r) iterations = std::max(iterations, rayTraces[r].size());
        for (size_t k = 0; k < iterations; ++k) {
            uint64_t active = 0;
            bool interior = false, leaf = false;
            for (size_t r = first; r < last; ++r) {
                if (k >= rayTraces[r].size()) continue;
                ++active;
                (rayTraces[r][k] == kInteriorStep ? interior : leaf) = true;
            }
            o.usefulSlots += active;
            o.laneSlots += uint64_t(lanes) * (uint64_t(interior) + uint64_t(leaf));
        }
    }
    return o;
}

}  // namespace cuberille::rt
