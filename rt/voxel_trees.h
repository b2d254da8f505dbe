#pragma once
// Three acceleration structures over voxels, as Chajdas compares them (2015, chapter 5.4): a
// bounding volume hierarchy, a kD tree and an octree. Each keeps its interior nodes apart from
// its leaves (a leaf is a range of the structure's own copy of the voxels, at most
// kVoxelLeafSize of them), tests leaves with the one shared routine (rt/voxel_rays.h), and
// traverses front to back with a short stack and restarts (§5.4.4, VoxelTraversal).
//
//   VoxelBvh      middle split of the longest axis down to kVoxelLeafSize voxels (§5.4.3); a node
//                 holds its two children's boxes in 16-bit coordinates (a "BVH2"), 32 bytes.
//                 Voxels never straddle a split, so sibling boxes never overlap.
//   VoxelKdTree   binned SAH (32 bins along the voxels' longest axis, a voxel costing one test
//                 wherever it is, §5.4.1); a node is a split plane and two children, 12 bytes; a
//                 split may leave a side empty, a null leaf.
//   VoxelOctree   voxels sorted in Morton order and split by octant until a node holds at most
//                 kVoxelLeafSize (§5.4.2); a node is eight children, 32 bytes, null where empty.
//
// Every structure, with every stack size, gives closestVoxelBruteForce's hit bit for bit: the
// argument is in rt/voxel_rays.h, the proof on random and degenerate rays in the VoxelTrees tests.

#include <algorithm>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "rt/voxel_rays.h"

namespace cuberille::rt {

/// At most this many voxels a leaf (§5.4.2, §5.4.3: "eight or less").
constexpr uint32_t kVoxelLeafSize = 8;

/// A leaf: voxels [first, first + count) of the structure's voxel array.
struct VoxelLeaf {
    uint32_t first = 0, count = 0;
};

/// A child reference: an interior node's index, a leaf's index with kLeafBit, or kNull.
struct VoxelNodeRef {
    static constexpr uint32_t kLeafBit = 1u << 31, kNull = ~0u;
    static bool isLeaf(uint32_t r) { return (r & kLeafBit) && r != kNull; }
    static uint32_t index(uint32_t r) { return r & ~kLeafBit; }
};

/// What the structures have in common: their voxels, in their own order, with the index each had
/// in the array they were built from (hits report that index).
struct VoxelLeaves {
    std::vector<VoxelCoord> voxels;
    std::vector<uint32_t> sourceIndex;
    std::vector<VoxelLeaf> leaves;
};

/// Sizes for Table 11: interior nodes, leaves, bytes of each, and the depth of the deepest leaf.
struct VoxelTreeSize {
    uint64_t interiorNodes = 0, leaves = 0, nullLeaves = 0;
    uint64_t interiorBytes = 0, leafBytes = 0;
    int depth = 0;
    double meanLeafDepth = 0;
};

enum class VoxelStructure { Bvh, KdTree, Octree, WideBvh };
const char* voxelStructureName(VoxelStructure s);
/// "bvh", "kdtree", "octree", "bvh8" (rt/wide_voxel_bvh.h); false for anything else.
bool parseVoxelStructure(const std::string& name, VoxelStructure* out);

/// Voxels' bounds as a cell range: [lo, hi) on each axis, in grid units (empty: lo > hi).
struct VoxelBounds {
    glm::ivec3 lo{65536}, hi{-1};
};
VoxelBounds voxelBounds(std::span<const VoxelCoord> voxels);

/// What the three trees hold alike: interior nodes (each with a `child` array of VoxelNodeRef),
/// the root reference and the box a traversal starts in, and the leaves with their voxels.
template <class NodeType>
class VoxelTreeStorage {
public:
    using Node = NodeType;
    /// Table 11's sizes, and the depths of Figure 49, by walking the tree.
    VoxelTreeSize size() const {
        VoxelTreeSize s;
        s.interiorNodes = nodes_.size();
        s.leaves = data_.leaves.size();
        s.interiorBytes = s.interiorNodes * sizeof(Node);
        s.leafBytes = s.leaves * sizeof(VoxelLeaf);
        if (root_ == VoxelNodeRef::kNull) return s;
        std::vector<std::pair<uint32_t, int>> todo{{root_, 0}};
        double depthSum = 0;
        while (!todo.empty()) {
            const auto [ref, depth] = todo.back();
            todo.pop_back();
            if (ref == VoxelNodeRef::kNull) {
                ++s.nullLeaves;
            } else if (VoxelNodeRef::isLeaf(ref)) {
                s.depth = std::max(s.depth, depth);
                depthSum += depth;
            } else {
                for (uint32_t c : nodes_[ref].child) todo.push_back({c, depth + 1});
            }
        }
        s.meanLeafDepth = depthSum / double(s.leaves);
        return s;
    }

    /// The arrays as laid out (the same bits at every thread count the build ran on).
    std::span<const Node> nodes() const { return nodes_; }
    const VoxelLeaves& leafData() const { return data_; }
    /// The root's reference (VoxelNodeRef; kNull for an empty tree) and the box a traversal
    /// starts in, [rootLo, rootHi).
    uint32_t root() const { return root_; }
    glm::vec3 rootLo() const { return rootLo_; }
    glm::vec3 rootHi() const { return rootHi_; }

protected:
    /// Copies the voxels, each remembering its index in `voxels`.
    explicit VoxelTreeStorage(std::span<const VoxelCoord> voxels) {
        data_.voxels.assign(voxels.begin(), voxels.end());
        data_.sourceIndex.resize(voxels.size());
        for (uint32_t i = 0; i < voxels.size(); ++i) data_.sourceIndex[i] = i;
    }
    /// Takes a build's arrays: the tree rooted at `root`, starting in the box [lo, hi).
    void adopt(std::vector<Node>&& nodes, std::vector<VoxelLeaf>&& leaves, uint32_t root, const glm::vec3& lo,
               const glm::vec3& hi) {
        nodes_ = std::move(nodes);
        data_.leaves = std::move(leaves);
        root_ = root;
        rootLo_ = lo;
        rootHi_ = hi;
    }
    /// The ray's segment in the root's box, where every traversal starts: false for an empty
    /// tree or a ray that misses it.
    bool enterRoot(const VoxelRay& ray, float* enter, float* exit) const {
        return root_ != VoxelNodeRef::kNull && ray.segment(rootLo_, rootHi_, ray.tMin, ray.tMax, enter, exit);
    }
    std::vector<Node> nodes_;
    uint32_t root_ = VoxelNodeRef::kNull;
    glm::vec3 rootLo_{0.0f}, rootHi_{0.0f};
    VoxelLeaves data_;
};

struct VoxelBvhNode {
    uint16_t lo[2][3], hi[2][3];  // child boxes, inclusive voxel coordinates
    uint32_t child[2];            // VoxelNodeRef
};
static_assert(sizeof(VoxelBvhNode) == 32);

struct VoxelKdNode {
    uint32_t child[2];  // VoxelNodeRef: below and above the split
    uint16_t split;     // the plane's coordinate
    uint8_t axis;
    uint8_t unused = 0;
};
static_assert(sizeof(VoxelKdNode) == 12);

struct VoxelOctreeNode {
    uint32_t child[8];  // VoxelNodeRef, by octant: bit 0 x, bit 1 y, bit 2 z (1: upper half)
};
static_assert(sizeof(VoxelOctreeNode) == 32);

class VoxelBvh : public VoxelTreeStorage<VoxelBvhNode> {
public:
    explicit VoxelBvh(std::span<const VoxelCoord> voxels);
    /// The closest hit (with how.anyHit, any hit), adding to `counters` and recording each loop
    /// iteration's step in `steps` when given. The other trees' trace is the same.
    VoxelHit trace(const VoxelRay& ray, const VoxelTraversal& how, VoxelTraversalCounters* counters = nullptr,
                   VoxelStepTrace* steps = nullptr) const;
};

class VoxelKdTree : public VoxelTreeStorage<VoxelKdNode> {
public:
    static constexpr int kBins = 32;
    explicit VoxelKdTree(std::span<const VoxelCoord> voxels);
    VoxelHit trace(const VoxelRay& ray, const VoxelTraversal& how, VoxelTraversalCounters* counters = nullptr,
                   VoxelStepTrace* steps = nullptr) const;
};

class VoxelOctree : public VoxelTreeStorage<VoxelOctreeNode> {
public:
    explicit VoxelOctree(std::span<const VoxelCoord> voxels);
    VoxelHit trace(const VoxelRay& ray, const VoxelTraversal& how, VoxelTraversalCounters* counters = nullptr,
                   VoxelStepTrace* steps = nullptr) const;

private:
    int rootLevel_ = 0;  // the root's cube is [0, 2^rootLevel) on each axis
};

}  // namespace cuberille::rt
