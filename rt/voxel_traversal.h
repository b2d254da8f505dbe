#pragma once
// What the three voxel traversals (rt/voxel_trees.h) share besides the leaf test: the short stack
// and the per-ray counts.
//
// The short stack of Chajdas's voxel traversals (2015, §5.4.4): a ring of a fixed number of
// entries; a push always succeeds, overwriting the oldest entry when the ring is full, and the
// traversal learns at the next empty pop that it lost one and restarts from the root. Every
// structure's nodes are disjoint along a ray, so a restart needs nothing but the point the ray
// has been followed to.

#include <cstdint>

#include "rt/voxel_rays.h"
#include "rt/voxel_trees.h"

namespace cuberille::rt {

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
