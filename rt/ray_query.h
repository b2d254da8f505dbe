#pragma once
// Ray queries against a BVH: closest hit (what a camera or reflection ray needs) and any hit
// (what a shadow ray needs: is anything between here and the light?).
//
// Results are exactly those of testing every triangle (the brute-force functions below, which
// the tests compare against): the same watertight triangle test decides every hit, boxes are
// tested conservatively, and ties in t go to the lower triangle id.

#include "rt/bvh.h"
#include "rt/ray.h"
#include "rt/triangle_mesh.h"

namespace cuberille::rt {

/// The tree answers from its own copy of the vertices (leafVertices, as of its last build or
/// refit); the mesh is the one it was built or refitted over.
RayHit closestHit(const Bvh& bvh, const TriangleMeshView& mesh, const Ray& ray);
bool anyHit(const Bvh& bvh, const TriangleMeshView& mesh, const Ray& ray, const HitFilter* filter = nullptr);
/// The closest hit among the triangles not skipped (rt/ray.h, HitFilter; ids are the mesh's).
RayHit closestHit(const Bvh& bvh, const TriangleMeshView& mesh, const Ray& ray, const HitFilter& filter);

/// The slow-but-sure references: every triangle, in id order.
RayHit closestHitBruteForce(const TriangleMeshView& mesh, const Ray& ray, const HitFilter* filter = nullptr);
bool anyHitBruteForce(const TriangleMeshView& mesh, const Ray& ray, const HitFilter* filter = nullptr);

/// Counts of the work one query did, for benchmarks and tests of the traversal's efficiency.
struct TraversalCounters {
    uint64_t nodesVisited = 0;
    uint64_t trianglesTested = 0;
};

namespace detail {

/// How far past a found hit a box's entry may lie and still be opened: the watertight test's t
/// and the slab test's entry are computed differently, each with a few roundings, so a box whose
/// computed entry lies a few ulps beyond a hit may still hold a triangle at that same t (a face
/// of the box, say). 64 ulps is far more than both error bounds together and costs nothing
/// measurable.
constexpr float kEntrySlack = 1.0f + 64.0f * std::numeric_limits<float>::epsilon();

/// The traversal both queries and both update schemes share. `boxOf(node)` yields the node's
/// current box: the node's own for an up-to-date tree, or one refreshed on first touch for the
/// lazy update (rt/lazy_refit.h). `vertexOf(slot, corner)` yields a leaf triangle's vertex:
/// from the tree's leafVertices, or from the mesh for the lazy update (the same values).
/// `filter`: what the search leaves out (HitFilter).
template <bool kAnyHit, class BoxOf, class VertexOf>
RayHit traverse(const Bvh& bvh, const Ray& ray, BoxOf&& boxOf, VertexOf&& vertexOf,
                TraversalCounters* counters = nullptr, const HitFilter* filter = nullptr) {
    RayHit best;
    best.t = ray.tMax;
    if (bvh.empty()) return best;
    const RayBoxTest boxTest(ray);
    const WatertightRay triangleTest(ray);
    uint32_t stack[kMaxBvhDepth + 1];
    int top = 0;
    uint32_t nodeIndex = 0;
    float entry = 0.0f;
    {
        const Aabb root = boxOf(0u);
        if (!boxTest.hits(root.lo, root.hi, ray.tMin, best.t * kEntrySlack, &entry)) return best;
    }
    for (;;) {
        const BvhNode& node = bvh.nodes[nodeIndex];
        if (counters) ++counters->nodesVisited;
        if (node.isLeaf()) {
            for (uint32_t i = node.first; i < node.first + node.primitiveCount; ++i) {
                const uint32_t triangle = bvh.primitiveIndices[i];
                if (counters) ++counters->trianglesTested;
                if (offerHit(triangleTest, vertexOf(i, 0), vertexOf(i, 1), vertexOf(i, 2), triangle, ray.tMin, best, filter, &ray) &&
                    kAnyHit)
                    return best;
            }
        } else {
            const Aabb left = boxOf(node.first), right = boxOf(node.first + 1);
            float leftEntry = 0.0f, rightEntry = 0.0f;
            const float limit = best.t * kEntrySlack;
            const bool hitLeft = boxTest.hits(left.lo, left.hi, ray.tMin, limit, &leftEntry);
            const bool hitRight = boxTest.hits(right.lo, right.hi, ray.tMin, limit, &rightEntry);
            if (hitLeft && hitRight) {
                const bool rightFirst = rightEntry < leftEntry;
                stack[top++] = rightFirst ? node.first : node.first + 1;
                nodeIndex = rightFirst ? node.first + 1 : node.first;
                continue;
            }
            if (hitLeft || hitRight) {
                nodeIndex = hitLeft ? node.first : node.first + 1;
                continue;
            }
        }
        if (top == 0) break;
        nodeIndex = stack[--top];
    }
    if (!best.hit()) best.t = std::numeric_limits<float>::infinity();
    return best;
}

}  // namespace detail

/// closestHit with counters (benchmarks).
RayHit closestHit(const Bvh& bvh, const TriangleMeshView& mesh, const Ray& ray, TraversalCounters& counters);

}  // namespace cuberille::rt
