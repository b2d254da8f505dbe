// The wide voxel BVH (rt/wide_voxel_bvh.h): collapsed from the binary voxel BVH, traversed with a
// node's eight child boxes tested in vector lanes.
//
//   build:  the binary VoxelBvh; each wide node opens the interior child of largest surface area
//           until it holds eight children (or only leaves); nodes laid out depth-first
//   trace:  clip the ray to the root box
//     node:  the children whose segment in [scene entry, scene exit] has positive length and
//            starts no later than the best hit, in lanes; pushed farthest first
//     leaf:  the shared voxel test (rt/voxel_traversal.h)
//     pop:   an entry whose segment starts past the best hit found since is dropped

#include "rt/wide_voxel_bvh.h"

#include <algorithm>
#include <bit>
#include <stdexcept>
#include <vector>

#include "rt/voxel_traversal.h"

// Compiled once per instruction set (see raster/tile_raster.cpp for how foreach_target.h works).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "rt/wide_voxel_bvh.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace cuberille::rt {
namespace HWY_NAMESPACE {
namespace {

namespace hn = hwy::HWY_NAMESPACE;
// Eight float lanes where the target has them; fewer (Highway's scalar baseline: one) take the
// children in turns with the same operations.
using DF = hn::CappedTag<float, kWideVoxelBvhWidth>;
using DI = hn::RebindToSigned<DF>;
using DU16 = hn::Rebind<uint16_t, DF>;

/// A node's children as VoxelRay::segment sees them: a bit per child whose segment, clipped to
/// [tLo, tHi], has positive length and starts no later than bestT, and each child's entry. Each
/// lane runs segment()'s operations in its order: the box's planes are its 16-bit coordinates and
/// hi + 1, exact in float; a parallel axis keeps the lanes whose slab [lo, hi + 1) holds the
/// origin; otherwise each plane's t is (plane - origin) * 1/direction, and the entry and exit are
/// raised and lowered by strict comparisons.
HWY_INLINE unsigned childrenEntered(const WideVoxelBvhNode& node, const VoxelRay& ray, float tLo, float tHi, float bestT,
                                    float* entry) {
    const DF d;
    const DI di;
    const DU16 d16;
    constexpr size_t kLanes = hn::MaxLanes(DF());
    unsigned bits = 0;
    for (size_t first = 0; first < size_t(kWideVoxelBvhWidth); first += kLanes) {
        auto nearT = hn::Set(d, tLo), farT = hn::Set(d, tHi);
        auto inside = hn::FirstN(d, kLanes);
        for (int a = 0; a < 3; ++a) {
            const auto lo = hn::ConvertTo(d, hn::PromoteTo(di, hn::LoadU(d16, node.lo[a] + first)));
            const auto hi = hn::Add(hn::ConvertTo(d, hn::PromoteTo(di, hn::LoadU(d16, node.hi[a] + first))), hn::Set(d, 1.0f));
            const auto origin = hn::Set(d, ray.origin[a]);
            if (ray.parallel[a]) {
                inside = hn::And(inside, hn::And(hn::Ge(origin, lo), hn::Lt(origin, hi)));
                continue;
            }
            const auto inverse = hn::Set(d, ray.inverseDirection[a]);
            const auto t0 = hn::Mul(hn::Sub(ray.farSide[a] ? hi : lo, origin), inverse);
            const auto t1 = hn::Mul(hn::Sub(ray.farSide[a] ? lo : hi, origin), inverse);
            nearT = hn::IfThenElse(hn::Gt(t0, nearT), t0, nearT);
            farT = hn::IfThenElse(hn::Lt(t1, farT), t1, farT);
        }
        hn::StoreU(nearT, d, entry + first);
        const auto met = hn::And(inside, hn::And(hn::Lt(nearT, farT), hn::Le(nearT, hn::Set(d, bestT))));
        uint8_t laneBits = 0;
        hn::StoreMaskBits(d, met, &laneBits);
        bits |= unsigned(laneBits) << first;
    }
    return bits;
}

/// A node or leaf to come back to, and where the ray enters it.
struct Pending {
    uint32_t ref;
    float entry;
};

}  // namespace

/// The traversal of a ray whose segment in the root box is [sceneEnter, sceneExit]: the best
/// hit, its voxel numbered in the tree's order.
VoxelHit traceWideVoxelBvhOnTarget(const WideVoxelBvh& tree, const VoxelRay& ray, bool anyHit, float sceneEnter,
                                   float sceneExit, VoxelStepCounts& counts) {
    const std::span<const WideVoxelBvhNode> nodes = tree.nodes();
    const VoxelLeaves& data = tree.leafData();
    VoxelHit best;
    // Each level pops one node and pushes at most kWideVoxelBvhWidth children.
    Pending stack[(kWideVoxelBvhWidth - 1) * kMaxWideVoxelBvhDepth + 1];
    int top = 0;
    stack[top++] = {tree.root(), sceneEnter};
    alignas(32) float entry[kWideVoxelBvhWidth];
    while (top > 0) {
        const Pending p = stack[--top];
        if (p.entry > best.t) continue;
        if (VoxelNodeRef::isLeaf(p.ref)) {
            counts.step(kLeafStep);
            if (testLeaf(data, VoxelNodeRef::index(p.ref), ray, anyHit, best, counts)) break;
            continue;
        }
        counts.step(kInteriorStep);
        const WideVoxelBvhNode& node = nodes[p.ref];
        // The children met, farthest first (ties in slot order), so the nearest is popped next.
        // Any-hit rays too: pushed in slot order instead, soft-shadow and occlusion rays visited
        // more nodes and ran 6-13% slower on the 2048³ dragon (voxel_rays_bench).
        // Sorted in place on the stack: gathered first and copied there, the copy became a
        // `rep movsq`, with 15% of a soft-shadow frame's traversal samples (perf).
        const int base = top;
        for (unsigned bits = childrenEntered(node, ray, sceneEnter, sceneExit, best.t, entry); bits != 0; bits &= bits - 1) {
            const int c = std::countr_zero(bits);
            int at = top++;
            for (; at > base && stack[at - 1].entry < entry[c]; --at) stack[at] = stack[at - 1];
            stack[at] = {node.child[c], entry[c]};
        }
    }
    return best;
}

}  // namespace HWY_NAMESPACE
}  // namespace cuberille::rt
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace cuberille::rt {

HWY_EXPORT(traceWideVoxelBvhOnTarget);

namespace {

/// A child of a wide node being collapsed: its reference in the binary tree and its box.
struct Slot {
    uint32_t ref;
    uint16_t lo[3], hi[3];  // inclusive voxel coordinates
};

uint64_t surfaceArea(const Slot& s) {
    uint64_t e[3];
    for (int a = 0; a < 3; ++a) e[a] = uint64_t(s.hi[a]) - s.lo[a] + 1;
    return e[0] * e[1] + e[1] * e[2] + e[2] * e[0];
}

class Collapse {
public:
    Collapse(const VoxelBvh& binary, std::vector<WideVoxelBvhNode>& out) : binary_(binary), out_(out) {}

    /// A binary interior node's two children.
    std::vector<Slot> childrenOf(uint32_t binaryNode) const {
        const VoxelBvhNode& n = binary_.nodes()[binaryNode];
        std::vector<Slot> slots(2);
        for (int c = 0; c < 2; ++c) {
            slots[c].ref = n.child[c];
            for (int a = 0; a < 3; ++a) slots[c].lo[a] = n.lo[c][a], slots[c].hi[a] = n.hi[c][a];
        }
        return slots;
    }

    /// The wide node holding `slots` opened up to eight, at `depth` (the root's is 1), and its
    /// subtree after it; returns its index.
    uint32_t node(std::vector<Slot> slots, int depth) {
        if (depth > kMaxWideVoxelBvhDepth) throw std::length_error("wide voxel BVH deeper than its traversal stack");
        height_ = std::max(height_, depth);
        open(slots);
        const uint32_t index = uint32_t(out_.size());
        out_.emplace_back();
        WideVoxelBvhNode filled;
        for (int c = 0; c < kWideVoxelBvhWidth; ++c) {
            for (int a = 0; a < 3; ++a) filled.lo[a][c] = 65535, filled.hi[a][c] = 0;
            filled.child[c] = VoxelNodeRef::kNull;
        }
        for (size_t c = 0; c < slots.size(); ++c) {
            for (int a = 0; a < 3; ++a) filled.lo[a][c] = slots[c].lo[a], filled.hi[a][c] = slots[c].hi[a];
            filled.child[c] = VoxelNodeRef::isLeaf(slots[c].ref) ? slots[c].ref : node(childrenOf(slots[c].ref), depth + 1);
        }
        out_[index] = filled;
        return index;
    }

    int height() const { return height_; }

private:
    /// Replaces the interior child of largest surface area (the first of equals) by its two
    /// children, until there are eight or only leaves.
    void open(std::vector<Slot>& slots) const {
        while (slots.size() < size_t(kWideVoxelBvhWidth)) {
            int largest = -1;
            uint64_t area = 0;
            for (size_t i = 0; i < slots.size(); ++i)
                if (!VoxelNodeRef::isLeaf(slots[i].ref) && (largest < 0 || surfaceArea(slots[i]) > area)) {
                    largest = int(i);
                    area = surfaceArea(slots[i]);
                }
            if (largest < 0) return;
            const std::vector<Slot> two = childrenOf(slots[size_t(largest)].ref);
            slots[size_t(largest)] = two[0];
            slots.insert(slots.begin() + largest + 1, two[1]);
        }
    }

    const VoxelBvh& binary_;
    std::vector<WideVoxelBvhNode>& out_;
    int height_ = 0;
};

}  // namespace

WideVoxelBvh::WideVoxelBvh(std::span<const VoxelCoord> voxels) : WideVoxelBvh(VoxelBvh(voxels)) {}

WideVoxelBvh::WideVoxelBvh(const VoxelBvh& binary) : VoxelTreeStorage(std::span<const VoxelCoord>{}) {
    if (binary.root() == VoxelNodeRef::kNull) return;
    data_.voxels = binary.leafData().voxels;
    data_.sourceIndex = binary.leafData().sourceIndex;
    std::vector<WideVoxelBvhNode> nodes;
    Collapse collapse(binary, nodes);
    std::vector<Slot> top;
    if (VoxelNodeRef::isLeaf(binary.root())) {
        // Eight voxels or fewer: a root node over the one leaf.
        Slot s{binary.root(), {}, {}};
        for (int a = 0; a < 3; ++a) s.lo[a] = uint16_t(binary.rootLo()[a]), s.hi[a] = uint16_t(binary.rootHi()[a] - 1.0f);
        top.push_back(s);
    } else {
        top = collapse.childrenOf(binary.root());
    }
    collapse.node(std::move(top), 1);
    height_ = collapse.height();
    adopt(std::move(nodes), std::vector<VoxelLeaf>(binary.leafData().leaves), 0, binary.rootLo(), binary.rootHi());
}

VoxelHit WideVoxelBvh::trace(const VoxelRay& ray, const VoxelTraversal& how, VoxelTraversalCounters* counters,
                             VoxelStepTrace* steps) const {
    VoxelStepCounts counts{.trace = steps};
    float sceneEnter, sceneExit;
    if (!enterRoot(ray, &sceneEnter, &sceneExit)) return counts.finish(VoxelHit{}, data_, counters);
    const VoxelHit best =
        HWY_DYNAMIC_DISPATCH(traceWideVoxelBvhOnTarget)(*this, ray, how.anyHit, sceneEnter, sceneExit, counts);
    return counts.finish(best, data_, counters);
}

}  // namespace cuberille::rt
#endif  // HWY_ONCE
