#pragma once
// The voxel BVH with eight children a node, their boxes tested in vector lanes: what
// rt/wide_bvh.h is for triangles, for voxels (Chajdas 2015, chapter 5, measured on a CPU).
//
// Chapter 5 finds the BVH the best voxel structure on a GPU, and this CPU agrees
// (docs/ray_tracing.md), but a binary node tests two boxes per step, one after the other, and a
// shadow ray through the 2048³ dragon visits 28 of them: Embree's eight-wide nodes on the voxels'
// faces were 1.4–2.6× faster on secondary rays. Here a node holds eight children's boxes as 16-bit
// voxel coordinates (§5.3), structure of arrays, two cache lines; one pass of lanes finds the
// children the ray enters and where, and they are visited nearest first.
//
// Made by collapsing the binary VoxelBvh (middle splits, §5.4.3): a node takes its two children,
// then replaces the interior child of largest surface area by that child's own two, until it holds
// eight or only leaves. Every box is a box of the binary tree and the leaves are its leaves, so the
// exactness argument of rt/voxel_rays.h carries over: each lane computes VoxelRay::segment's
// operations in its order (the same integer planes, the same half-open parallel slabs), a child is
// entered when its segment has positive length and starts no later than the best hit, and the leaf
// routine is the shared one. The hit is brute force's bit for bit, whatever order the children are
// visited in (the WideVoxelBvh tests of tests/rt/voxel_trees_test.cpp, run once per instruction set).
//
// The stack is a full one, never the short stack of §5.4.4: a wide node pushes up to seven
// children at once, so a ring of a few entries would lose most of them and restart at nearly every
// leaf, and a CPU's stack costs nothing to keep whole (a VoxelTraversal's stackEntries is ignored).

#include <cstdint>
#include <span>

#include "rt/voxel_rays.h"
#include "rt/voxel_trees.h"

namespace cuberille::rt {

/// Children a wide node holds at most: one AVX vector of floats per box bound.
constexpr int kWideVoxelBvhWidth = 8;

/// Two cache lines: the children's boxes as inclusive voxel coordinates, lo[axis][child] and
/// hi[axis][child], then their references. Children fill the first slots; an unused slot has child
/// VoxelNodeRef::kNull and the box lo 65535, hi 0, whose slabs are inverted so no ray enters it.
struct alignas(64) WideVoxelBvhNode {
    uint16_t lo[3][kWideVoxelBvhWidth];
    uint16_t hi[3][kWideVoxelBvhWidth];
    uint32_t child[kWideVoxelBvhWidth];  // VoxelNodeRef: a wide node, a leaf (kLeafBit), or kNull
};
static_assert(sizeof(WideVoxelBvhNode) == 128, "two 64-byte cache lines");

/// The deepest a wide tree may be: the stack holds (width - 1) entries a level. The binary tree's
/// middle splits halve the longest of three 16-bit extents, so it is at most about 48 levels deep,
/// and collapsing never deepens it; the build checks the bound.
constexpr int kMaxWideVoxelBvhDepth = 64;

class WideVoxelBvh : public VoxelTreeStorage<WideVoxelBvhNode> {
public:
    /// Builds the binary VoxelBvh over `voxels` and collapses it.
    explicit WideVoxelBvh(std::span<const VoxelCoord> voxels);
    /// Collapses `binary`: the same leaves and voxels, in its order.
    explicit WideVoxelBvh(const VoxelBvh& binary);

    /// The closest hit (with how.anyHit, any hit), as VoxelBvh::trace gives it; how.stackEntries
    /// is ignored (a full stack, above).
    VoxelHit trace(const VoxelRay& ray, const VoxelTraversal& how, VoxelTraversalCounters* counters = nullptr,
                   VoxelStepTrace* steps = nullptr) const;

    /// Table 11's sizes; a node's unused slots are not counted as null leaves (none are leaves).
    VoxelTreeSize size() const {
        VoxelTreeSize s = VoxelTreeStorage::size();
        s.nullLeaves = 0;
        return s;
    }

    /// The deepest leaf's depth in wide nodes.
    int height() const { return height_; }

private:
    int height_ = 0;
};

}  // namespace cuberille::rt
