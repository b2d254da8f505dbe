// The voxel BVH (Chajdas 2015, §5.4.3): middle split of the longest axis, a BVH2 whose nodes hold
// their children's boxes, traversed with a short stack and restarts (Algorithm 5.3).
//
//   trace: clip the ray to the root box
//     interior: test both child boxes against [restart point, scene exit]; go to the nearer hit,
//               push the farther
//     leaf:     the shared voxel test (rt/voxel_traversal.h)
//     pop:      the next entry that starts no later than the best hit; when the stack ran dry
//               having lost an entry, restart from the root past the last node finished

#include <algorithm>

#include "rt/voxel_traversal.h"
#include "rt/voxel_trees.h"

namespace cuberille::rt {

struct VoxelBvhBuilder {
    VoxelLeaves& data;

    /// The subtree over data.voxels[first, first + count), whose bounds are b, into `out`.
    uint32_t build(VoxelSubtree<VoxelBvhNode>& out, uint32_t first, uint32_t count, const VoxelBounds& b) {
        if (count <= kVoxelLeafSize) return out.leaf(first, count);
        // More than one voxel: the longest axis spans at least two, so the middle plane m has
        // voxels on both sides (the lowest below it, the highest at or above it).
        const glm::ivec3 extent = b.hi - b.lo;
        const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
        const int middle = b.lo[axis] + extent[axis] / 2;
        const uint32_t below = partitionBelow(data, first, count, axis, middle);
        const VoxelCoord* begin = data.voxels.data() + first;
        const VoxelBounds children[2] = {voxelBounds({begin, below}), voxelBounds({begin + below, count - below})};
        const uint32_t node = uint32_t(out.nodes.size());
        out.nodes.emplace_back();
        for (int c = 0; c < 2; ++c)
            for (int a = 0; a < 3; ++a) {
                out.nodes[node].lo[c][a] = uint16_t(children[c].lo[a]);
                out.nodes[node].hi[c][a] = uint16_t(children[c].hi[a] - 1);
            }
        uint32_t refs[2];
        buildChildren(out, 2, count >= kParallelBuildVoxels, [&](int c, VoxelSubtree<VoxelBvhNode>& into) {
            return c == 0 ? build(into, first, below, children[0]) : build(into, first + below, count - below, children[1]);
        }, refs);
        out.nodes[node].child[0] = refs[0];
        out.nodes[node].child[1] = refs[1];
        return node;
    }
};

VoxelBvh::VoxelBvh(std::span<const VoxelCoord> voxels) : VoxelTreeStorage(voxels) {
    if (voxels.empty()) return;
    const VoxelBounds b = voxelBounds(voxels);
    VoxelSubtree<VoxelBvhNode> tree;
    const uint32_t root = VoxelBvhBuilder{data_}.build(tree, 0, uint32_t(voxels.size()), b);
    adopt(std::move(tree.nodes), std::move(tree.leaves), root, glm::vec3(b.lo), glm::vec3(b.hi));
}

VoxelHit VoxelBvh::trace(const VoxelRay& ray, const VoxelTraversal& how, VoxelTraversalCounters* counters,
                         VoxelStepTrace* steps) const {
    VoxelStepCounts counts{.trace = steps};
    VoxelHit best;
    float sceneEnter, sceneExit;
    if (!enterRoot(ray, &sceneEnter, &sceneExit)) return counts.finish(best, data_, counters);

    VoxelTraversalStack<VoxelSegmentEntry> stack(how.stackEntries);
    float restartFrom = sceneEnter;  // the ray before this point has been followed through the tree
    uint32_t ref = root_;
    float exit = sceneExit;  // of the node at hand
    for (;;) {
        if (!VoxelNodeRef::isLeaf(ref)) {
            counts.step(kInteriorStep);
            const Node& n = nodes_[ref];
            float enters[2], exits[2];
            bool hits[2];
            for (int c = 0; c < 2; ++c) {
                const glm::vec3 lo(n.lo[c][0], n.lo[c][1], n.lo[c][2]);
                const glm::vec3 hi = glm::vec3(n.hi[c][0], n.hi[c][1], n.hi[c][2]) + 1.0f;
                hits[c] = ray.segment(lo, hi, restartFrom, sceneExit, &enters[c], &exits[c]) && enters[c] <= best.t;
            }
            if (hits[0] || hits[1]) {
                const int near = hits[0] && hits[1] ? (enters[1] < enters[0] ? 1 : 0) : hits[0] ? 0 : 1;
                if (hits[0] && hits[1]) stack.push({n.child[1 - near], enters[1 - near], exits[1 - near]});
                ref = n.child[near];
                exit = exits[near];
                continue;
            }
        } else {
            counts.step(kLeafStep);
            if (testLeaf(data_, VoxelNodeRef::index(ref), ray, how.anyHit, best, counts))
                return counts.finish(best, data_, counters);
        }
        // The node at hand is finished: everything up to its exit has been seen.
        const float finishedTo = exit;
        if (VoxelSegmentEntry next; stack.popStartingBy(best.t, &next)) {
            ref = next.ref;
            exit = next.exit;
            continue;
        }
        if (!stack.takeLost()) return counts.finish(best, data_, counters);
        restartFrom = finishedTo;
        if (restartFrom >= sceneExit || restartFrom > best.t) return counts.finish(best, data_, counters);
        ++counts.restarts;
        ref = root_;
        exit = sceneExit;
    }
}

}  // namespace cuberille::rt
