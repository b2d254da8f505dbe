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

namespace {

struct Bounds {
    glm::u16vec3 lo{0xFFFF}, hi{0};  // inclusive voxel coordinates
    void grow(const VoxelCoord& v) {
        lo = glm::min(lo, glm::u16vec3(v.x, v.y, v.z));
        hi = glm::max(hi, glm::u16vec3(v.x, v.y, v.z));
    }
};

Bounds boundsOf(std::span<const VoxelCoord> voxels) {
    Bounds b;
    for (const VoxelCoord& v : voxels) b.grow(v);
    return b;
}

uint16_t coordinate(const VoxelCoord& v, int axis) { return axis == 0 ? v.x : axis == 1 ? v.y : v.z; }

}  // namespace

struct VoxelBvhBuilder {
    VoxelBvh& bvh;

    /// The subtree over data.voxels[first, first + count), whose bounds are b.
    uint32_t build(uint32_t first, uint32_t count, const Bounds& b) {
        VoxelLeaves& data = bvh.data_;
        if (count <= kVoxelLeafSize) {
            data.leaves.push_back({first, count});
            return uint32_t(data.leaves.size() - 1) | VoxelNodeRef::kLeafBit;
        }
        // More than one voxel: the longest axis spans at least two, so the middle plane m has
        // voxels on both sides (the lowest below it, the highest at or above it).
        const glm::ivec3 extent = glm::ivec3(b.hi) - glm::ivec3(b.lo) + 1;
        const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
        const int middle = b.lo[axis] + extent[axis] / 2;
        auto* begin = data.voxels.data() + first;
        auto* indexBegin = data.sourceIndex.data() + first;
        // Partition voxels and their source indices together (a hand loop: two arrays, one order).
        uint32_t below = 0;
        for (uint32_t i = 0; i < count; ++i)
            if (coordinate(begin[i], axis) < middle) {
                std::swap(begin[i], begin[below]);
                std::swap(indexBegin[i], indexBegin[below]);
                ++below;
            }
        const Bounds left = boundsOf({begin, below}), right = boundsOf({begin + below, count - below});
        const uint32_t node = uint32_t(bvh.nodes_.size());
        bvh.nodes_.emplace_back();
        const uint32_t c0 = build(first, below, left);
        const uint32_t c1 = build(first + below, count - below, right);
        VoxelBvhNode& n = bvh.nodes_[node];
        const Bounds* children[2] = {&left, &right};
        for (int c = 0; c < 2; ++c)
            for (int a = 0; a < 3; ++a) {
                n.lo[c][a] = children[c]->lo[a];
                n.hi[c][a] = children[c]->hi[a];
            }
        n.child[0] = c0;
        n.child[1] = c1;
        return node;
    }
};

VoxelBvh::VoxelBvh(std::span<const VoxelCoord> voxels) : VoxelTreeStorage(voxels) {
    if (voxels.empty()) return;
    const Bounds b = boundsOf(voxels);
    rootLo_ = glm::vec3(b.lo);
    rootHi_ = glm::vec3(b.hi) + 1.0f;
    root_ = VoxelBvhBuilder{*this}.build(0, uint32_t(voxels.size()), b);
}

VoxelHit VoxelBvh::trace(const VoxelRay& ray, const VoxelTraversal& how, VoxelTraversalCounters* counters,
                         VoxelStepTrace* steps) const {
    VoxelStepCounts counts{.trace = steps};
    VoxelHit best;
    float sceneEnter, sceneExit;
    if (root_ == VoxelNodeRef::kNull || !ray.segment(rootLo_, rootHi_, ray.tMin, ray.tMax, &sceneEnter, &sceneExit))
        return counts.finish(best, data_, counters);

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
