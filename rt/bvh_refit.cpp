#include "rt/bvh_refit.h"

#include <cmath>

#include "raster/parallel.h"

namespace cuberille::rt {
namespace {

// Subtrees over more primitives than this refit their two halves as parallel tasks.
constexpr uint32_t kParallelSubtreePrimitives = 4096;

/// A leaf's box from its triangles' new positions, copied into leafVertices on the way.
Aabb refitLeaf(Bvh& bvh, const TriangleMeshView& mesh, const BvhNode& leaf) {
    Aabb box;
    for (uint32_t i = leaf.first; i < leaf.first + leaf.primitiveCount; ++i)
        for (int c = 0; c < 3; ++c) {
            const glm::vec3 p = mesh.vertex(bvh.primitiveIndices[i], c);
            bvh.leafVertices[3 * size_t(i) + c] = p;
            box.grow(p);
        }
    return box;
}

/// Refits the subtree at `index` post-order and returns its inner nodes' summed ratio change.
/// The halves' sums are added in a fixed order (left + right), so the total does not depend on
/// which half finished first.
double refitSubtree(Bvh& bvh, const TriangleMeshView& mesh, uint32_t index) {
    BvhNode& node = bvh.nodes[index];
    if (node.isLeaf()) {
        node.setBox(refitLeaf(bvh, mesh, node));
        return 0.0;
    }
    const uint32_t left = node.first, right = node.first + 1;
    double leftSum = 0.0, rightSum = 0.0;
    if (bvh.subtreeCount[index] > kParallelSubtreePrimitives) {
        raster::parallelInvoke([&] { leftSum = refitSubtree(bvh, mesh, left); },
                               [&] { rightSum = refitSubtree(bvh, mesh, right); });
    } else {
        leftSum = refitSubtree(bvh, mesh, left);
        rightSum = refitSubtree(bvh, mesh, right);
    }
    const Aabb l = bvh.nodes[left].box(), r = bvh.nodes[right].box();
    const Aabb box = merged(l, r);
    node.setBox(box);
    return leftSum + rightSum + std::abs(double(areaRatio(box, l, r)) - double(bvh.buildAreaRatio[index]));
}

}  // namespace

double refitBvh(Bvh& bvh, const TriangleMeshView& mesh) {
    if (bvh.empty()) return 0.0;
    const double sum = refitSubtree(bvh, mesh, 0);
    const size_t inner = bvh.innerNodeCount();
    return inner ? sum / double(inner) : 0.0;
}

double bvhDegradation(const Bvh& bvh) {
    double sum = 0.0;
    size_t inner = 0;
    for (uint32_t i = 0; i < bvh.nodes.size(); ++i) {
        const BvhNode& n = bvh.nodes[i];
        if (n.isLeaf()) continue;
        sum += std::abs(double(areaRatio(n.box(), bvh.nodes[n.first].box(), bvh.nodes[n.first + 1].box())) - double(bvh.buildAreaRatio[i]));
        ++inner;
    }
    return inner ? sum / double(inner) : 0.0;
}

}  // namespace cuberille::rt
