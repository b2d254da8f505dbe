#pragma once
// Which blocks a frame draws, and how (Chajdas 2015, sections 4.3-4.5, 4.7): the block octree is
// walked from the root; a node outside the view frustum (tested with its tight voxel bounds, not
// its octree cell) is culled with everything below it; a node whose voxels may project to more
// than the pixel error is refined into its children; a finest-level block that still needs
// refinement is drawn from its source triangles instead (hybrid rendering), when it has them.

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "voxel/voxel_model.h"

namespace cuberille::lod {

struct SelectionOptions {
    float pixelError = 1.0f;  // largest projected voxel, in pixels; 0: always the finest level
    bool hybrid = true;       // draw source triangles where even the finest voxels are too coarse
    /// The finest level refined into (--voxel-resolution): blocks there are drawn as voxels even
    /// when too coarse, so the model renders as if voxelized at resolution / 2^finestLevel.
    uint32_t finestLevel = 0;
    int viewportHeightPixels = 720;
    float verticalFovRadians = 0.7f;  // perspective only
    bool orthographic = false;
    float orthographicHalfHeight = 1.0f;  // model units
};

struct SelectionStats {
    uint64_t blocksVisited = 0, frustumCulled = 0, hybridBlocks = 0;
    std::vector<uint64_t> drawnPerLevel;  // voxel blocks drawn, by level
};

struct BlockSelection {
    std::vector<uint32_t> voxelBlocks;     // drawn as voxel faces, front to back
    std::vector<uint32_t> triangleBlocks;  // drawn from their source triangles, front to back
    std::vector<uint32_t> frustumCulled;   // the nodes culled by the frustum (their subtrees with them)
    SelectionStats stats;
};

/// clipFromModel: the frame's model-to-clip transform (D3D depth range); camera in model units.
BlockSelection selectBlocks(const voxel::VoxelModel& model, const glm::dmat4& clipFromModel,
                            const glm::dvec3& camera, const SelectionOptions& options);

/// The tight model-space bounds of a block's voxels.
void blockBounds(const voxel::VoxelModel& model, const voxel::VoxelBlock& block, glm::dvec3& lo, glm::dvec3& hi);

/// An upper bound on the size, in pixels, of any voxel of the block on screen: the voxel's edge
/// over the nearest distance from the camera to the block's bounds. The thesis's bound (Chajdas
/// 2015, section 4.3: "the projected size of a voxel never exceeds the size of a pixel"); its
/// edge, not its diagonal, which would refine one level further for a √3 that no image shows
/// (docs/voxelization.md measures both against the source triangles). Infinite when the camera
/// is inside them.
double projectedVoxelPixels(const voxel::VoxelModel& model, const voxel::VoxelBlock& block, const glm::dvec3& camera,
                            const SelectionOptions& options);

}  // namespace cuberille::lod
