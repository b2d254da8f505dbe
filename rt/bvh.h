#pragma once
// A bounding volume hierarchy over triangles, flattened for traversal.
//
// Layout (Lauterbach, section 4.1.6): 32-byte nodes, a node's two children side by side, so one
// index reaches both; a leaf names a run of `primitiveIndices`. Every subtree's primitives are
// one contiguous run too (the build partitions in place), which the lazy update and the frustum
// cull use to take a whole subtree at once. What traversal never reads (the build-time area
// ratios of the rebuild criterion, the subtree runs, depths) lives in side arrays, as Larsson
// advises, so the nodes a ray walks stay small.

#include <cstdint>
#include <vector>

#include "rt/aabb.h"
#include "rt/triangle_mesh.h"

namespace cuberille::rt {

/// No hierarchy is deeper than this (the build guarantees it), so traversal stacks are fixed
/// arrays on the stack: no allocation per ray.
constexpr int kMaxBvhDepth = 96;

struct BvhNode {
    glm::vec3 lo;
    uint32_t first;  // inner: index of the first child (the second follows); leaf: first primitive
    glm::vec3 hi;
    uint32_t primitiveCount;  // 0 for an inner node

    bool isLeaf() const { return primitiveCount != 0; }
    Aabb box() const { return {lo, hi}; }
    void setBox(const Aabb& b) {
        lo = b.lo;
        hi = b.hi;
    }
};
static_assert(sizeof(BvhNode) == 32, "two nodes to a 64-byte cache line");

enum class BvhBuildMethod : uint8_t {
    BinnedSah,      // surface area heuristic over binned centroids: the better tree
    SpatialMedian,  // split the centroid box at its middle: the fastest build
};

struct Bvh {
    std::vector<BvhNode> nodes;              // nodes[0] is the root
    std::vector<uint32_t> primitiveIndices;  // triangle ids in leaf order
    // The triangles' vertices copied in leaf order, three per entry of primitiveIndices, as of the
    // last build or refit: a leaf's triangles are one contiguous read instead of three dependent
    // ones (id, then indices, then positions), which profiling showed to dominate ray queries.
    std::vector<glm::vec3> leafVertices;
    // Per node: the first of its subtree's primitives in primitiveIndices, and how many.
    std::vector<uint32_t> subtreeFirst, subtreeCount;
    std::vector<uint8_t> depth;  // the root is 0
    // Per inner node, at build time: area(node) / (area(left) + area(right)) (Lauterbach 4.1.5).
    std::vector<float> buildAreaRatio;
    int height = 0;  // the deepest leaf's depth
    BvhBuildMethod method = BvhBuildMethod::BinnedSah;

    bool empty() const { return nodes.empty(); }
    size_t innerNodeCount() const { return nodes.size() / 2; }  // a full binary tree: n leaves, n-1 inner
};

/// Copies each triangle's vertices into leafVertices in leaf order (after a build or a refit).
void gatherLeafVertices(Bvh& bvh, const TriangleMeshView& mesh);

/// Lauterbach's per-node quality measure: how much larger a node is than its two children
/// together. 1 when the children fill it; grows as they drift apart inside it.
inline float areaRatio(const Aabb& node, const Aabb& left, const Aabb& right) {
    const float children = left.surfaceArea() + right.surfaceArea();
    return children > 0.0f ? node.surfaceArea() / children : 1.0f;
}

}  // namespace cuberille::rt
