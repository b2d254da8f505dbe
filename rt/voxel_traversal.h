#pragma once
// What the three voxel trees (rt/voxel_trees.h) share besides the leaf test: their parallel build
// (subtrees spliced in order) and, for traversal, the short stack and the per-ray counts.
//
// The short stack of Chajdas's voxel traversals (2015, §5.4.4): a ring of a fixed number of
// entries; a push always succeeds, overwriting the oldest entry when the ring is full, and the
// traversal learns at the next empty pop that it lost one and restarts from the root. Every
// structure's nodes are disjoint along a ray, so a restart needs nothing but the point the ray
// has been followed to.

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include <tbb/parallel_for.h>

#include "rt/voxel_rays.h"
#include "rt/voxel_trees.h"

namespace cuberille::rt {

/// A subtree built on its own, its nodes and leaves numbered from 0. A node is appended before its
/// children and children in order (preorder), and a child subtree built on another thread is
/// spliced into its parent's arrays in that same order, so the tree's layout is the serial
/// build's whatever ran in parallel: the same bits at every thread count.
template <class Node>
struct VoxelSubtree {
    std::vector<Node> nodes;
    std::vector<VoxelLeaf> leaves;

    uint32_t leaf(uint32_t first, uint32_t count) {
        leaves.push_back({first, count});
        return uint32_t(leaves.size() - 1) | VoxelNodeRef::kLeafBit;
    }
    /// Appends `child` (whose root reference is `root`) and returns that root in this numbering.
    uint32_t splice(VoxelSubtree&& child, uint32_t root) {
        const uint32_t nodeOffset = uint32_t(nodes.size()), leafOffset = uint32_t(leaves.size());
        auto moved = [&](uint32_t r) {
            if (r == VoxelNodeRef::kNull) return r;
            return VoxelNodeRef::isLeaf(r) ? (VoxelNodeRef::index(r) + leafOffset) | VoxelNodeRef::kLeafBit : r + nodeOffset;
        };
        for (Node& n : child.nodes)
            for (uint32_t& c : n.child) c = moved(c);
        nodes.insert(nodes.end(), child.nodes.begin(), child.nodes.end());
        leaves.insert(leaves.end(), child.leaves.begin(), child.leaves.end());
        return moved(root);
    }
};

/// Voxels [first, first + count) of `data` put in two runs, those whose coordinate on `axis` is
/// below `plane` first (their source indices with them); returns how many are below.
inline uint32_t partitionBelow(VoxelLeaves& data, uint32_t first, uint32_t count, int axis, int plane) {
    VoxelCoord* v = data.voxels.data() + first;
    uint32_t* index = data.sourceIndex.data() + first;
    uint32_t below = 0;
    for (uint32_t i = 0; i < count; ++i) {
        const int c = axis == 0 ? v[i].x : axis == 1 ? v[i].y : v[i].z;
        if (c < plane) {
            std::swap(v[i], v[below]);
            std::swap(index[i], index[below]);
            ++below;
        }
    }
    return below;
}

/// A node over at least this many voxels builds its children on other threads (below it, a
/// subtree's build is shorter than handing it over).
constexpr uint32_t kParallelBuildVoxels = 1u << 15;

/// The `count` children of a node, child c built by build(c, subtree) into refs[c]: straight into
/// `out` in order, or, for a large node, each into a subtree of its own in parallel, then spliced.
template <class Node, class BuildChild>
void buildChildren(VoxelSubtree<Node>& out, int count, bool parallel, BuildChild&& build, uint32_t* refs) {
    if (!parallel) {
        for (int c = 0; c < count; ++c) refs[c] = build(c, out);
        return;
    }
    std::array<VoxelSubtree<Node>, 8> parts;
    std::array<uint32_t, 8> roots{};
    tbb::parallel_for(0, count, [&](int c) { roots[size_t(c)] = build(c, parts[size_t(c)]); });
    for (int c = 0; c < count; ++c) refs[c] = out.splice(std::move(parts[size_t(c)]), roots[size_t(c)]);
}

template <class Entry>
class VoxelTraversalStack {
public:
    /// capacity: 0 (every push is lost: restart each time) or a power of two up to kFullStack.
    explicit VoxelTraversalStack(int capacity) : capacity_(capacity), mask_(capacity > 0 ? uint32_t(capacity - 1) : 0u) {}

    void push(const Entry& e) {
        if (capacity_ == 0) {
            lost_ = true;
            return;
        }
        entries_[head_ & mask_] = e;
        ++head_;
        if (count_ == capacity_) lost_ = true;
        else ++count_;
    }
    bool pop(Entry* e) {
        if (count_ == 0) return false;
        --head_;
        --count_;
        *e = entries_[head_ & mask_];
        return true;
    }
    /// The most recent entry whose segment starts no later than `t` (the best hit so far): those
    /// after it cannot hold a nearer hit. False when none is left.
    bool popStartingBy(float t, Entry* e) {
        while (pop(e))
            if (e->enter <= t) return true;
        return false;
    }
    /// Whether an entry has been overwritten (or, with no entries, pushed) since the last call.
    bool takeLost() {
        const bool l = lost_;
        lost_ = false;
        return l;
    }

private:
    Entry entries_[VoxelTraversal::kFullStack];
    int capacity_;
    uint32_t mask_;
    uint32_t head_ = 0;
    int count_ = 0;
    bool lost_ = false;
};

/// A node to come back to and the ray's segment in it (the BVH's and kD tree's stack entry).
struct VoxelSegmentEntry {
    uint32_t ref;
    float enter, exit;
};

/// Per-ray counts kept in registers and added to the caller's totals once.
struct VoxelStepCounts {
    uint64_t interior = 0, leaf = 0, voxelTests = 0, restarts = 0;
    VoxelStepTrace* trace = nullptr;

    void step(VoxelStep kind) {
        (kind == kInteriorStep ? interior : leaf) += 1;
        if (trace) trace->push_back(kind);
    }
    /// The hit with its voxel named by the index it had in the builder's input.
    VoxelHit finish(VoxelHit hit, const VoxelLeaves& data, VoxelTraversalCounters* counters) const {
        if (hit.hit()) hit.voxel = data.sourceIndex[hit.voxel];
        if (counters) {
            counters->rays += 1;
            counters->hits += hit.hit() ? 1 : 0;
            counters->interiorSteps += interior;
            counters->leafSteps += leaf;
            counters->voxelTests += voxelTests;
            counters->restarts += restarts;
        }
        return hit;
    }
};

/// A leaf's voxels offered to `best` (ids in the structure's order until finish()); true when an
/// any-hit search may stop.
inline bool testLeaf(const VoxelLeaves& data, uint32_t leaf, const VoxelRay& ray, bool anyHit, VoxelHit& best,
                     VoxelStepCounts& counts) {
    const VoxelLeaf& l = data.leaves[leaf];
    counts.voxelTests += l.count;
    for (uint32_t i = l.first; i < l.first + l.count; ++i)
        if (offerVoxel(ray, data.voxels[i], i, best) && anyHit) return true;
    return false;
}

}  // namespace cuberille::rt
