#pragma once
// The voxelizer's octree (Chajdas 2015, section 3.1.1, "tree memory storage"). Interior nodes
// and leaves live in separate pools: an interior node is just eight 32-bit child indices, a leaf
// is just its payload, and which one an index names follows from the depth the traversal is at,
// so no node spends a bit on saying what it is. Pools grow in fixed blocks (no per-node malloc,
// and nodes never move, so references stay valid while the tree grows).
//
// Leaf payloads are sums in 64-bit fixed point rather than floats: integer addition is
// associative, so merging per-thread trees gives the same bits whichever thread voxelized which
// triangle and in whatever order their leaves are summed (DESIGN.md, determinism).

#include <cstdint>
#include <memory>
#include <vector>

namespace cuberille::voxel {

/// Fixed point of the leaf sums: units of 2^-40 voxel² of area. A piece of area a contributes
/// weight a·2^40 + 2^12, so even a piece of no area (a triangle touching the voxel along an edge or
/// at a point) carries its normal and colour, to 12 bits, into a voxel nothing else reaches, while
/// any piece of real area outweighs it. A voxel overflows only past 2^22 voxel² of surface.
constexpr double kLeafWeightScale = double(1ull << 40);
constexpr double kContactWeight = double(1 << 12);

struct LeafSums {
    int64_t normal[3] = {0, 0, 0};  // weight × unit normal
    int64_t weight = 0;
    uint8_t faceMask = 0;  // union of the pieces' active faces
    uint8_t targets = 0;   // TargetBit: which intersection targets some piece met
};

struct LeafColorSums {
    int64_t rgb[3] = {0, 0, 0};  // weight × linear colour
};

enum TargetBit : uint8_t { kMetCrosshair = 1u << 0, kMetDiagonals = 1u << 1 };

struct InteriorNode {
    uint32_t child[8] = {0, 0, 0, 0, 0, 0, 0, 0};  // 0: empty (index 0 is never a child)
};

/// A growing array in blocks of 2^16 elements whose elements never move.
template <class T>
class BlockPool {
public:
    static constexpr uint32_t kBlockShift = 16;
    static constexpr uint32_t kBlockElements = 1u << kBlockShift;

    uint32_t allocate() {
        if (size_ % kBlockElements == 0) blocks_.push_back(std::make_unique<T[]>(kBlockElements));
        return size_++;
    }
    T& operator[](uint32_t i) { return blocks_[i >> kBlockShift][i & (kBlockElements - 1)]; }
    const T& operator[](uint32_t i) const { return blocks_[i >> kBlockShift][i & (kBlockElements - 1)]; }
    uint32_t size() const { return size_; }
    uint64_t reservedBytes() const { return uint64_t(blocks_.size()) * kBlockElements * sizeof(T); }

private:
    std::vector<std::unique_ptr<T[]>> blocks_;
    uint32_t size_ = 0;
};

class VoxelOctree {
public:
    /// leafDepth = log2(resolution) >= 1. Index 0 of the interior pool is the root; index 0 of the
    /// leaf pools is unused, so 0 can mean "no child" at every depth.
    VoxelOctree(int leafDepth, bool withColors) : leafDepth_(leafDepth), withColors_(withColors) {
        interiors_.allocate();
        leaves_.allocate();
        if (withColors_) colors_.allocate();
    }

    int leafDepth() const { return leafDepth_; }
    bool withColors() const { return withColors_; }
    static constexpr uint32_t root() { return 0; }

    /// The child slot of an interior node at `depth`, created when absent: an interior node, or a
    /// leaf when depth + 1 is the leaf depth.
    uint32_t childOf(uint32_t node, int depth, int octant) {
        uint32_t c = interiors_[node].child[octant];
        if (c == 0) {
            c = depth + 1 == leafDepth_ ? newLeaf() : interiors_.allocate();
            interiors_[node].child[octant] = c;
        }
        return c;
    }
    uint32_t existingChild(uint32_t node, int octant) const { return interiors_[node].child[octant]; }

    LeafSums& leaf(uint32_t i) { return leaves_[i]; }
    const LeafSums& leaf(uint32_t i) const { return leaves_[i]; }
    LeafColorSums& leafColor(uint32_t i) { return colors_[i]; }
    const LeafColorSums& leafColor(uint32_t i) const { return colors_[i]; }

    uint32_t interiorCount() const { return interiors_.size(); }
    uint32_t leafCount() const { return leaves_.size() - 1; }
    uint64_t reservedBytes() const {
        return interiors_.reservedBytes() + leaves_.reservedBytes() + colors_.reservedBytes();
    }

private:
    uint32_t newLeaf() {
        const uint32_t i = leaves_.allocate();
        if (withColors_) colors_.allocate();
        return i;
    }

    int leafDepth_;
    bool withColors_;
    BlockPool<InteriorNode> interiors_;
    BlockPool<LeafSums> leaves_;
    BlockPool<LeafColorSums> colors_;
};

}  // namespace cuberille::voxel
