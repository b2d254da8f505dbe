#include "lod/simplify.h"

#include <algorithm>
#include <numeric>

#include "raster/parallel.h"
#include "voxel/morton.h"
#include "voxel/packing.h"

namespace cuberille::lod {
namespace {

using voxel::VoxelBlock;

/// One voxel of the level being simplified, addressed by its Morton code in the whole level:
/// key >> 3 is its parent's code, key & 7 its octant in the parent.
struct ChildRef {
    uint64_t key;
    uint32_t block, voxel;
};

/// The parent of a run of children (in Morton order): the reduction both versions share.
struct ParentVoxel {
    glm::uvec3 position;  // in the parent level's grid
    uint8_t faceMask;
    uint32_t normal, color;
};

ParentVoxel combineChildren(const ChildRef* first, size_t count, const std::vector<const VoxelBlock*>& level,
                            uint32_t blockSize) {
    uint8_t faces = 0;
    glm::vec3 normalSum(0.0f), colorSum(0.0f);
    for (size_t i = 0; i < count; ++i) {
        const VoxelBlock& b = *level[first[i].block];
        faces |= voxel::voxelFaceMask(b.voxels[first[i].voxel]);
        normalSum += voxel::unpackNormal1010102(b.normals[first[i].voxel]);
        colorSum += voxel::unpackSrgba8Rgb(b.colors[first[i].voxel]);
    }
    const VoxelBlock& b0 = *level[first[0].block];
    const glm::uvec3 child = b0.coord * blockSize + voxel::voxelPositionInBlock(b0.voxels[first[0].voxel]);
    const float len = glm::length(normalSum);
    return {child / 2u, faces, voxel::packNormal1010102(len > 0.0f ? normalSum / len : glm::vec3(0.0f)),
            voxel::packSrgba8(colorSum / float(count))};
}

/// Gathers parents (in Morton order of their positions) into blocks of the parent level.
void appendParentBlocks(const std::vector<ParentVoxel>& parents, uint32_t blockSize, uint32_t parentLevel,
                        std::vector<VoxelBlock>& out) {
    for (const ParentVoxel& p : parents) {
        const glm::uvec3 coord = p.position / blockSize;
        if (out.empty() || out.back().coord != coord || out.back().level != parentLevel) {
            VoxelBlock b;
            b.level = parentLevel;
            b.coord = coord;
            b.tightMin = glm::uvec3(blockSize);
            out.push_back(std::move(b));
        }
        VoxelBlock& b = out.back();
        const glm::uvec3 local = p.position - coord * blockSize;
        b.voxels.push_back(voxel::packVoxel(local.x, local.y, local.z, p.faceMask));
        b.normals.push_back(p.normal);
        b.colors.push_back(p.color);
        b.tightMin = glm::min(b.tightMin, local);
        b.tightMax = glm::max(b.tightMax, local);
    }
}

void appendChildren(const std::vector<const VoxelBlock*>& level, uint32_t blockIndex, uint32_t blockSize,
                    std::vector<ChildRef>& out) {
    const VoxelBlock& b = *level[blockIndex];
    for (uint32_t v = 0; v < b.voxels.size(); ++v)
        out.push_back({voxel::mortonOf(b.coord * blockSize + voxel::voxelPositionInBlock(b.voxels[v])), blockIndex, v});
}

}  // namespace

void simplifySerial(const LevelSource& level, uint32_t blockSize, const std::function<void(VoxelBlock&&)>& emit) {
    std::vector<ChildRef> children;
    std::vector<ParentVoxel> parents;
    // Child blocks of one parent block are consecutive in Morton order of block coordinates.
    for (size_t first = 0; first < level.blockCount();) {
        const glm::uvec3 parentBlock = level.blockCoord(first) / 2u;
        size_t last = first;
        while (last < level.blockCount() && level.blockCoord(last) / 2u == parentBlock) ++last;
        std::vector<std::shared_ptr<const VoxelBlock>> held;
        std::vector<const VoxelBlock*> loaded;
        for (size_t b = first; b < last; ++b) {
            held.push_back(level.load(b));
            loaded.push_back(held.back().get());
        }
        // 1. Sort this parent block's children by Morton key.
        children.clear();
        for (uint32_t b = 0; b < loaded.size(); ++b) appendChildren(loaded, b, blockSize, children);
        std::sort(children.begin(), children.end(), [](const ChildRef& a, const ChildRef& b) { return a.key < b.key; });
        // 2. Compact runs with the same parent.
        parents.clear();
        for (size_t i = 0; i < children.size();) {
            size_t j = i + 1;
            while (j < children.size() && children[j].key >> 3 == children[i].key >> 3) ++j;
            parents.push_back(combineChildren(&children[i], j - i, loaded, blockSize));
            i = j;
        }
        std::vector<VoxelBlock> out;
        appendParentBlocks(parents, blockSize, loaded[0]->level + 1, out);
        for (VoxelBlock& b : out) emit(std::move(b));
        first = last;
    }
}

std::vector<VoxelBlock> simplifySerial(const std::vector<const VoxelBlock*>& level, uint32_t blockSize) {
    // The in-memory level as a source: loading is handing out a pointer that owns nothing.
    struct InMemory final : LevelSource {
        const std::vector<const VoxelBlock*>& blocks;
        explicit InMemory(const std::vector<const VoxelBlock*>& b) : blocks(b) {}
        size_t blockCount() const override { return blocks.size(); }
        glm::uvec3 blockCoord(size_t i) const override { return blocks[i]->coord; }
        std::shared_ptr<const VoxelBlock> load(size_t i) const override {
            return std::shared_ptr<const VoxelBlock>(std::shared_ptr<const VoxelBlock>(), blocks[i]);
        }
    } source(level);
    std::vector<VoxelBlock> out;
    simplifySerial(source, blockSize, [&](VoxelBlock&& b) { out.push_back(std::move(b)); });
    return out;
}

std::vector<VoxelBlock> simplifyParallel(const std::vector<const VoxelBlock*>& level, uint32_t blockSize) {
    std::vector<VoxelBlock> out;
    if (level.empty()) return out;
    const uint32_t parentLevel = level[0]->level + 1;
    // Every voxel's key, blocks in parallel (each block's slice of the array is known up front).
    std::vector<size_t> offsets(level.size() + 1, 0);
    for (size_t b = 0; b < level.size(); ++b) offsets[b + 1] = offsets[b] + level[b]->voxels.size();
    std::vector<ChildRef> children(offsets.back());
    raster::parallelFor(level.size(), [&](size_t b) {
        const VoxelBlock& block = *level[b];
        for (uint32_t v = 0; v < block.voxels.size(); ++v)
            children[offsets[b] + v] = {voxel::mortonOf(block.coord * blockSize + voxel::voxelPositionInBlock(block.voxels[v])),
                                        uint32_t(b), v};
    });
    // 1. Parallel sort (keys are unique: one voxel per position).
    raster::parallelSort(children.begin(), children.end(),
                         [](const ChildRef& a, const ChildRef& b) { return a.key < b.key; });
    // 2. Run marking and 3. prefix sum: runsSoFar[i] = run starts at or before i, so voxel i belongs
    // to run runsSoFar[i] - 1.
    const size_t n = children.size();
    std::vector<uint32_t> runsSoFar;
    const size_t runs = raster::parallelInclusiveScan<uint32_t>(
        n, [&](size_t i) { return (i == 0 || children[i].key >> 3 != children[i - 1].key >> 3) ? 1u : 0u; },
        runsSoFar);
    std::vector<size_t> runStart(runs + 1, n);
    raster::parallelFor(n, [&](size_t i) {
        if (i == 0 || runsSoFar[i] != runsSoFar[i - 1]) runStart[runsSoFar[i] - 1] = i;
    });
    // 4. Compaction: one parent per run.
    std::vector<ParentVoxel> parents(runs);
    raster::parallelFor(runs, [&](size_t r) {
        parents[r] = combineChildren(&children[runStart[r]], runStart[r + 1] - runStart[r], level, blockSize);
    });
    appendParentBlocks(parents, blockSize, parentLevel, out);
    return out;
}

}  // namespace cuberille::lod
