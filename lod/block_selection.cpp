#include "lod/block_selection.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "voxel/face_expansion.h"

namespace cuberille::lod {
namespace {

/// The six clip planes of a D3D-style projection (0 <= z <= w), as model-space half-spaces
/// a·p + d >= 0 (Gribb and Hartmann).
struct Frustum {
    glm::dvec4 planes[6];

    explicit Frustum(const glm::dmat4& m) {
        const glm::dvec4 r0(m[0][0], m[1][0], m[2][0], m[3][0]), r1(m[0][1], m[1][1], m[2][1], m[3][1]),
            r2(m[0][2], m[1][2], m[2][2], m[3][2]), r3(m[0][3], m[1][3], m[2][3], m[3][3]);
        planes[0] = r3 + r0, planes[1] = r3 - r0, planes[2] = r3 + r1, planes[3] = r3 - r1, planes[4] = r2,
        planes[5] = r3 - r2;
    }
    /// False only when the box is wholly outside one plane (conservative).
    bool mayContain(const glm::dvec3& lo, const glm::dvec3& hi) const {
        for (const glm::dvec4& p : planes) {
            const glm::dvec3 farthest(p.x >= 0 ? hi.x : lo.x, p.y >= 0 ? hi.y : lo.y, p.z >= 0 ? hi.z : lo.z);
            if (p.x * farthest.x + p.y * farthest.y + p.z * farthest.z + p.w < 0) return false;
        }
        return true;
    }
};

double distanceToBox(const glm::dvec3& p, const glm::dvec3& lo, const glm::dvec3& hi) {
    return glm::length(glm::max(glm::max(lo - p, p - hi), glm::dvec3(0.0)));
}

}  // namespace

void blockBounds(const voxel::VoxelModel& model, const voxel::VoxelBlock& block, glm::dvec3& lo, glm::dvec3& hi) {
    const voxel::VoxelBoxes boxes(model, block);
    lo = boxes.lowCorner(block.tightMin);
    hi = boxes.lowCorner(block.tightMax) + boxes.voxelSize;
    if (!block.hasVoxels()) {  // triangles only: the whole block cell
        lo = boxes.lowCorner(glm::uvec3(0));
        hi = boxes.lowCorner(glm::uvec3(model.blockSize));
    }
}

double projectedVoxelPixels(const voxel::VoxelModel& model, const voxel::VoxelBlock& block, const glm::dvec3& camera,
                            const SelectionOptions& o) {
    const double edge = voxel::VoxelBoxes(model, block).voxelSize;
    if (o.orthographic) return edge * o.viewportHeightPixels / (2.0 * o.orthographicHalfHeight);
    glm::dvec3 lo, hi;
    blockBounds(model, block, lo, hi);
    const double d = distanceToBox(camera, lo, hi);
    if (d <= 0.0) return std::numeric_limits<double>::infinity();
    const double focalPixels = o.viewportHeightPixels / (2.0 * std::tan(o.verticalFovRadians / 2.0));
    return edge * focalPixels / d;
}

BlockSelection selectBlocks(const voxel::VoxelModel& model, const glm::dmat4& clipFromModel, const glm::dvec3& camera,
                            const SelectionOptions& o) {
    BlockSelection s;
    if (model.blocks.empty()) return s;
    const Frustum frustum(clipFromModel);
    s.stats.drawnPerLevel.assign(model.blocks.front().level + 1, 0);
    std::vector<uint32_t> stack{0};  // the root: the first block
    while (!stack.empty()) {
        const uint32_t i = stack.back();
        stack.pop_back();
        const voxel::VoxelBlock& b = model.blocks[i];
        ++s.stats.blocksVisited;
        glm::dvec3 lo, hi;
        blockBounds(model, b, lo, hi);
        if (!frustum.mayContain(lo, hi)) {
            ++s.stats.frustumCulled;
            s.frustumCulled.push_back(i);
            continue;
        }
        const bool tooCoarse = o.pixelError <= 0.0f || projectedVoxelPixels(model, b, camera, o) > o.pixelError;
        if (tooCoarse && b.childMask && b.level > o.finestLevel) {
            for (int k = __builtin_popcount(b.childMask); k-- > 0;) stack.push_back(b.firstChild + uint32_t(k));
            continue;
        }
        if (tooCoarse && o.hybrid && b.level == 0 && b.hasTriangles()) {
            s.triangleBlocks.push_back(i);
            ++s.stats.hybridBlocks;
            continue;
        }
        if (b.hasVoxels()) {
            s.voxelBlocks.push_back(i);
            ++s.stats.drawnPerLevel[b.level];
        }
    }
    // Front to back (by nearest distance, ties by index): near blocks fill the depth buffer first.
    auto byDistance = [&](std::vector<uint32_t>& list) {
        std::vector<std::pair<double, uint32_t>> keyed;
        for (uint32_t i : list) {
            glm::dvec3 lo, hi;
            blockBounds(model, model.blocks[i], lo, hi);
            keyed.push_back({distanceToBox(camera, lo, hi), i});
        }
        std::sort(keyed.begin(), keyed.end());
        for (size_t k = 0; k < list.size(); ++k) list[k] = keyed[k].second;
    };
    byDistance(s.voxelBlocks);
    byDistance(s.triangleBlocks);
    return s;
}

}  // namespace cuberille::lod
