#include "lod/lod_pyramid.h"

#include <algorithm>

#include "lod/simplify.h"
#include "raster/clock.h"
#include "raster/parallel.h"
#include "voxel/morton.h"

namespace cuberille::lod {
namespace {

using voxel::VoxelBlock;

std::vector<const VoxelBlock*> pointersTo(const std::vector<VoxelBlock>& blocks) {
    std::vector<const VoxelBlock*> p;
    for (const VoxelBlock& b : blocks) p.push_back(&b);
    return p;
}

/// Child links: the blocks are ordered coarsest first, Morton within a level, so a parent's
/// children are a consecutive run of the level below, found by walking both levels together.
void linkChildren(std::vector<VoxelBlock>& blocks) {
    size_t levelStart = 0;
    while (levelStart < blocks.size()) {
        const uint32_t level = blocks[levelStart].level;
        size_t levelEnd = levelStart;
        while (levelEnd < blocks.size() && blocks[levelEnd].level == level) ++levelEnd;
        size_t child = levelEnd;  // the level below starts right after
        for (size_t p = levelStart; p < levelEnd; ++p) {
            VoxelBlock& parent = blocks[p];
            parent.childMask = 0;
            parent.firstChild = 0;
            if (level == 0) continue;
            const uint64_t parentCode = voxel::mortonOf(parent.coord);
            while (child < blocks.size() && blocks[child].level == level - 1 && voxel::mortonOf(blocks[child].coord) >> 3 < parentCode)
                ++child;
            parent.firstChild = uint32_t(child);
            while (child < blocks.size() && blocks[child].level == level - 1 &&
                   voxel::mortonOf(blocks[child].coord) >> 3 == parentCode) {
                parent.childMask |= uint8_t(1u << (voxel::mortonOf(blocks[child].coord) & 7));
                ++child;
            }
        }
        levelStart = levelEnd;
    }
}

uint64_t addSkirts(VoxelBlock& b, uint32_t blockSize) {
    uint64_t added = 0;
    for (uint32_t& packed : b.voxels) {
        const glm::uvec3 p = voxel::voxelPositionInBlock(packed);
        uint8_t faces = voxel::voxelFaceMask(packed);
        const uint8_t before = faces;
        if (p.x == 0) faces |= voxel::kFaceNegX;
        if (p.x == blockSize - 1) faces |= voxel::kFacePosX;
        if (p.y == 0) faces |= voxel::kFaceNegY;
        if (p.y == blockSize - 1) faces |= voxel::kFacePosY;
        if (p.z == 0) faces |= voxel::kFaceNegZ;
        if (p.z == blockSize - 1) faces |= voxel::kFacePosZ;
        added += uint64_t(__builtin_popcount(faces ^ before));
        packed = voxel::packVoxel(p.x, p.y, p.z, faces);
    }
    return added;
}

}  // namespace

uint32_t pyramidLevels(uint32_t resolution, uint32_t blockSize) {
    uint32_t levels = 1;
    for (uint32_t r = resolution; r > blockSize; r /= 2) ++levels;
    return levels;
}

void buildLodPyramid(voxel::VoxelModel& model, const PyramidOptions& options, PyramidStats* statsOut) {
    const double t0 = raster::nowMs();
    PyramidStats stats;
    uint32_t levels = pyramidLevels(model.grid.resolution, model.blockSize);
    if (options.maxLevels > 0) levels = std::min(levels, options.maxLevels);
    std::vector<std::vector<VoxelBlock>> pyramid(1);
    pyramid[0] = std::move(model.blocks);
    for (uint32_t l = 1; l < levels; ++l) {
        const std::vector<const VoxelBlock*> below = pointersTo(pyramid[l - 1]);
        pyramid.push_back(options.method == SimplifyMethod::Serial ? simplifySerial(below, model.blockSize)
                                                                   : simplifyParallel(below, model.blockSize));
    }
    model.blocks.clear();
    for (uint32_t l = levels; l-- > 0;) {
        stats.blocksPerLevel.insert(stats.blocksPerLevel.begin(), pyramid[l].size());
        uint64_t voxels = 0;
        for (VoxelBlock& b : pyramid[l]) {
            voxels += b.voxels.size();
            model.blocks.push_back(std::move(b));
        }
        stats.voxelsPerLevel.insert(stats.voxelsPerLevel.begin(), voxels);
    }
    linkChildren(model.blocks);
    std::vector<uint64_t> skirts(model.blocks.size(), 0);
    raster::parallelFor(model.blocks.size(), [&](size_t i) { skirts[i] = addSkirts(model.blocks[i], model.blockSize); });
    for (uint64_t s : skirts) stats.skirtFaces += s;
    stats.levels = levels;
    stats.simplifyMs = raster::nowMs() - t0;
    if (statsOut) *statsOut = stats;
}

}  // namespace cuberille::lod
