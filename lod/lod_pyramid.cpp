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

/// Faces no camera can see: a face whose neighbour across it, in the same block, holds a voxel
/// is covered by that voxel wherever it could be seen from, so it is cleared; a voxel inside a
/// thick shell (all six neighbours present) loses every face and draws nothing (issue 25: a
/// conservative surface is two to three voxels thick). Only neighbours in the same block count:
/// the block across a boundary may be drawn at another level, or not at all, and there the
/// skirt decides. Run after simplification, so a parent's mask still unites its children's.
/// Returns the faces cleared.
uint64_t clearHiddenFaces(VoxelBlock& b, uint32_t blockSize) {
    const uint32_t n = blockSize;
    std::vector<uint64_t> occupied((size_t(n) * n * n + 63) / 64, 0);
    auto index = [n](glm::uvec3 p) { return size_t(p.x) + size_t(n) * (size_t(p.y) + size_t(n) * size_t(p.z)); };
    auto has = [&](glm::uvec3 p) { return (occupied[index(p) >> 6] >> (index(p) & 63)) & 1u; };
    for (uint32_t packed : b.voxels) {
        const size_t i = index(voxel::voxelPositionInBlock(packed));
        occupied[i >> 6] |= uint64_t(1) << (i & 63);
    }
    uint64_t cleared = 0;
    for (uint32_t& packed : b.voxels) {
        const glm::uvec3 p = voxel::voxelPositionInBlock(packed);
        const uint8_t before = voxel::voxelFaceMask(packed);
        uint8_t faces = before;
        for (int axis = 0; axis < 3; ++axis) {
            glm::uvec3 q = p;
            if (p[axis] + 1 < n && (q[axis] = p[axis] + 1, has(q))) faces &= uint8_t(~(1u << (2 * axis)));
            q = p;
            if (p[axis] > 0 && (q[axis] = p[axis] - 1, has(q))) faces &= uint8_t(~(2u << (2 * axis)));
        }
        cleared += uint64_t(__builtin_popcount(faces ^ before));
        packed = voxel::packVoxel(p.x, p.y, p.z, faces);
    }
    return cleared;
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

std::vector<VoxelBlock> simplifyLevel(const std::vector<VoxelBlock>& below, uint32_t blockSize, SimplifyMethod method) {
    const std::vector<const VoxelBlock*> pointers = pointersTo(below);
    return method == SimplifyMethod::Serial ? simplifySerial(pointers, blockSize) : simplifyParallel(pointers, blockSize);
}

void finishBlockFaces(std::span<VoxelBlock> blocks, uint32_t blockSize, bool clearHidden, PyramidStats& stats) {
    std::vector<uint64_t> hidden(blocks.size(), 0), skirts(blocks.size(), 0);
    raster::parallelFor(blocks.size(), [&](size_t i) {
        if (clearHidden) hidden[i] = clearHiddenFaces(blocks[i], blockSize);
        skirts[i] = addSkirts(blocks[i], blockSize);
    });
    for (size_t i = 0; i < blocks.size(); ++i) stats.hiddenFacesCleared += hidden[i], stats.skirtFaces += skirts[i];
}

uint32_t pyramidLevels(uint32_t resolution, uint32_t blockSize) {
    uint32_t levels = 1;
    for (uint32_t r = resolution; r > blockSize; r /= 2) ++levels;
    return levels;
}

uint32_t pyramidLevels(uint32_t resolution, uint32_t blockSize, const PyramidOptions& options) {
    const uint32_t levels = pyramidLevels(resolution, blockSize);
    return options.maxLevels > 0 ? std::min(levels, options.maxLevels) : levels;
}

void buildLodPyramid(voxel::VoxelModel& model, const PyramidOptions& options, PyramidStats* statsOut) {
    const double t0 = raster::nowMs();
    PyramidStats stats;
    const uint32_t levels = pyramidLevels(model.grid.resolution, model.blockSize, options);
    std::vector<std::vector<VoxelBlock>> pyramid(1);
    pyramid[0] = std::move(model.blocks);
    for (uint32_t l = 1; l < levels; ++l) pyramid.push_back(simplifyLevel(pyramid[l - 1], model.blockSize, options.method));
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
    finishBlockFaces(model.blocks, model.blockSize, options.clearHiddenFaces, stats);
    stats.levels = levels;
    stats.simplifyMs = raster::nowMs() - t0;
    if (statsOut) *statsOut = stats;
}

}  // namespace cuberille::lod
