#pragma once
// The LOD pyramid and its block octree (Chajdas 2015, sections 3.2 and 4.3): level 0 is the
// voxelizer's output; each further level halves the resolution (lod/simplify.h) until the whole
// model is one block. Blocks are then ordered coarsest level first, Morton order within a level,
// so a block's (at most 8) children are consecutive at the level below: a block links to them by
// the index of the first and an 8-bit mask of the octants present. The root is the single block
// of the coarsest level, which a renderer keeps resident.
//
// Hidden faces: an active face with a voxel across it in the same block can never be seen and is
// cleared (a voxel inside a thick conservative shell draws nothing).
//
// Skirts: every voxel on a block's boundary gets the face on that boundary marked active, so a
// block drawn next to a neighbour at another level (or next to source triangles) closes the gap
// between them instead of showing a crack (section 4.3). They are added after simplification, so
// a parent's face mask is still exactly the union of its children's interior faces.

#include <cstdint>
#include <span>

#include "voxel/voxel_model.h"

namespace cuberille::lod {

enum class SimplifyMethod { Serial, Parallel };

struct PyramidOptions {
    SimplifyMethod method = SimplifyMethod::Parallel;
    uint32_t maxLevels = 0;  // 0: down to a single block; 1: level 0 only (skirts and links still)
    bool clearHiddenFaces = true;  // false keeps the voxelizer's masks (to measure what clearing saves)
};

struct PyramidStats {
    uint32_t levels = 0;
    std::vector<uint64_t> blocksPerLevel, voxelsPerLevel;
    uint64_t skirtFaces = 0;  // faces the skirts activated
    uint64_t hiddenFacesCleared = 0;  // active faces with a voxel across them in the block
    double simplifyMs = 0;
};

/// Builds every level above level 0 into the model (whose blocks must be level 0, in Morton
/// order, voxels in Morton order), orders and links the blocks, adds skirts.
void buildLodPyramid(voxel::VoxelModel& model, const PyramidOptions& options, PyramidStats* stats = nullptr);

/// Number of levels a model of this resolution gets: down to one block of kBlockSize.
uint32_t pyramidLevels(uint32_t resolution, uint32_t blockSize);
/// The levels buildLodPyramid builds under the options (maxLevels applied).
uint32_t pyramidLevels(uint32_t resolution, uint32_t blockSize, const PyramidOptions& options);

// The pyramid's steps, for building it a range of blocks at a time (lod/pyramid_ranges.h).

/// The level above `below` (blocks of one level in Morton order), by the options' method.
std::vector<voxel::VoxelBlock> simplifyLevel(const std::vector<voxel::VoxelBlock>& below, uint32_t blockSize,
                                             SimplifyMethod method);

/// The blocks' last step, once the level above them is built: hidden faces cleared (when asked)
/// and skirts added, block by block in parallel. Adds what it changed to the stats' counts.
void finishBlockFaces(std::span<voxel::VoxelBlock> blocks, uint32_t blockSize, bool clearHiddenFaces, PyramidStats& stats);

/// Sets every block's child links from the levels and coordinates alone (the blocks may be a
/// layout without their voxels): they must be ordered coarsest level first, Morton within a level.
void linkChildren(std::vector<voxel::VoxelBlock>& blocks);

}  // namespace cuberille::lod
