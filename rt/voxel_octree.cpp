// The voxel octree (Chajdas 2015, §5.4.2): voxels sorted by Morton code, split by octant until a
// node holds at most kVoxelLeafSize, traversed front to back with a short stack and restarts
// (Algorithm 5.2).
//
//   trace: clip the ray to the root cube [0, 2^level)³
//     interior: the three mid-planes the ray crosses after the segment's start decide the child
//               it is in and where it leaves it; push this node with the rest of the segment
//               (the paper pushes the node, not its children: one entry however many follow);
//               go down into that child, or treat a null child as an empty leaf
//     leaf:     the shared voxel test
//     pop:      a popped node is entered again past the child just finished

#include <algorithm>
#include <numeric>

#include <tbb/parallel_sort.h>

#include "rt/voxel_traversal.h"
#include "rt/voxel_trees.h"

namespace cuberille::rt {

namespace {

/// The 16 bits of v spread to every third bit of 48.
uint64_t spreadBits(uint64_t v) {
    v &= 0xFFFF;
    v = (v | (v << 16)) & 0x0000FF0000FFull;
    v = (v | (v << 8)) & 0x00F00F00F00Full;
    v = (v | (v << 4)) & 0x0C30C30C30C3ull;
    v = (v | (v << 2)) & 0x249249249249ull;
    return v;
}

/// x in bit 0 of each triple, y in bit 1, z in bit 2: a triple is an octant number.
uint64_t mortonCode(const VoxelCoord& v) { return spreadBits(v.x) | spreadBits(v.y) << 1 | spreadBits(v.z) << 2; }

}  // namespace

struct VoxelOctreeBuilder {
    const std::vector<uint64_t>& codes;  // sorted, one per voxel

    /// The subtree over voxels [first, first + count), a cube of 2^level voxels a side, into `out`.
    uint32_t build(VoxelSubtree<VoxelOctreeNode>& out, uint32_t first, uint32_t count, int level) {
        if (count == 0) return VoxelNodeRef::kNull;
        if (count <= kVoxelLeafSize || level == 0) return out.leaf(first, count);
        const int shift = 3 * (level - 1);
        uint32_t bounds[9];
        bounds[0] = first;
        for (uint32_t octant = 0, i = first; octant < 8; ++octant) {
            while (i < first + count && ((codes[i] >> shift) & 7) == octant) ++i;
            bounds[octant + 1] = i;
        }
        const uint32_t node = uint32_t(out.nodes.size());
        out.nodes.emplace_back();
        uint32_t refs[8];
        buildChildren(out, 8, count >= kParallelBuildVoxels, [&](int octant, VoxelSubtree<VoxelOctreeNode>& into) {
            return build(into, bounds[octant], bounds[octant + 1] - bounds[octant], level - 1);
        }, refs);
        std::copy(refs, refs + 8, out.nodes[node].child);
        return node;
    }
};

VoxelOctree::VoxelOctree(std::span<const VoxelCoord> voxels) : VoxelTreeStorage(voxels) {
    if (voxels.empty()) return;
    std::vector<uint64_t> key(voxels.size());
    uint32_t largest = 0;
    for (size_t i = 0; i < voxels.size(); ++i) {
        key[i] = mortonCode(voxels[i]);
        largest = std::max({largest, uint32_t(voxels[i].x), uint32_t(voxels[i].y), uint32_t(voxels[i].z)});
    }
    while ((1u << rootLevel_) <= largest) ++rootLevel_;
    std::vector<uint32_t> order(voxels.size());
    std::iota(order.begin(), order.end(), 0u);
    // A total order (ties by index), so the parallel sort's result is the one order there is.
    tbb::parallel_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key[a] < key[b] || (key[a] == key[b] && a < b); });
    std::vector<uint64_t> codes(voxels.size());
    data_.voxels.resize(voxels.size());
    data_.sourceIndex = order;
    for (size_t i = 0; i < order.size(); ++i) {
        data_.voxels[i] = voxels[order[i]];
        codes[i] = key[order[i]];
    }
    VoxelSubtree<VoxelOctreeNode> tree;
    const uint32_t root = VoxelOctreeBuilder{codes}.build(tree, 0, uint32_t(voxels.size()), rootLevel_);
    adopt(std::move(tree.nodes), std::move(tree.leaves), root, glm::vec3(0.0f), glm::vec3(float(1u << rootLevel_)));
}

VoxelHit VoxelOctree::trace(const VoxelRay& ray, const VoxelTraversal& how, VoxelTraversalCounters* counters,
                            VoxelStepTrace* steps) const {
    VoxelStepCounts counts{.trace = steps};
    VoxelHit best;
    float sceneEnter, sceneExit;
    if (!enterRoot(ray, &sceneEnter, &sceneExit)) return counts.finish(best, data_, counters);

    struct Entry {
        uint32_t ref;
        int level;
        glm::u16vec3 base;  // the node's cube is [base, base + 2^level)
        float enter, exit;
    };
    VoxelTraversalStack<Entry> stack(how.stackEntries);
    Entry at{root_, rootLevel_, glm::u16vec3(0), sceneEnter, sceneExit};
    for (;;) {
        bool leafDone = false;
        while (!leafDone) {
            if (at.ref == VoxelNodeRef::kNull || VoxelNodeRef::isLeaf(at.ref)) {
                counts.step(kLeafStep);
                if (at.ref != VoxelNodeRef::kNull &&
                    testLeaf(data_, VoxelNodeRef::index(at.ref), ray, how.anyHit, best, counts))
                    return counts.finish(best, data_, counters);
                leafDone = true;
                break;
            }
            counts.step(kInteriorStep);
            // The child the ray is in just after at.enter: past each mid-plane it has crossed by
            // then (a crossing exactly at at.enter counts as crossed, as the kD tree's does), and
            // where it leaves that child: the first crossing after at.enter, or the node's exit.
            const uint32_t half = 1u << (at.level - 1);
            int octant = 0;
            float childExit = at.exit;
            for (int a = 0; a < 3; ++a) {
                const float middle = float(uint32_t(at.base[a]) + half);
                bool upper;
                if (ray.parallel[a]) {
                    upper = ray.origin[a] >= middle;
                } else {
                    const float crossing = ray.planeT(a, middle);
                    const bool crossed = crossing <= at.enter;
                    upper = crossed != bool(ray.farSide[a]);
                    if (!crossed && crossing < childExit) childExit = crossing;
                }
                if (upper) octant |= 1 << a;
            }
            if (childExit < at.exit) stack.push({at.ref, at.level, at.base, childExit, at.exit});
            const uint32_t child = nodes_[at.ref].child[octant];
            glm::u16vec3 base = at.base;
            for (int a = 0; a < 3; ++a)
                if (octant & (1 << a)) base[a] = uint16_t(base[a] + half);
            at = {child, at.level - 1, base, at.enter, childExit};
        }
        const float finishedTo = at.exit;
        if (Entry next; stack.popStartingBy(best.t, &next)) {
            at = next;
            continue;
        }
        if (!stack.takeLost() || finishedTo >= sceneExit || finishedTo > best.t)
            return counts.finish(best, data_, counters);
        ++counts.restarts;
        at = {root_, rootLevel_, glm::u16vec3(0), finishedTo, sceneExit};
    }
}

}  // namespace cuberille::rt
