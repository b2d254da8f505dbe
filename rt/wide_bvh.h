#pragma once
// A BVH with eight children a node, tested in one vector operation per slab: the layout of
// Embree's BVH8 and of Wald, Benthin and Boulos, "Getting Rid of Packets" (2008). A single ray
// gets the vector units' width from the node instead of from a packet of rays, so incoherent
// rays (shadow rays from scattered hits, ambient occlusion) gain as much as camera rays.
//
// It is made by collapsing a binary Bvh: a node takes its two children, then replaces the inner
// child of largest surface area by that child's own two, until it holds eight (or only leaves).
// Leaves hold up to four triangles, tested in one vector operation too.
// Every box of the wide tree is a box of the binary one and the leaves are the binary leaves, so
// the binary tree's build quality carries over and the ray queries keep its exactness argument:
// the same conservative slab test (rt/ray.h) decides each box, the same watertight test each
// triangle, and the answers are brute force's, whatever order the children are visited in.

#include <cstdint>
#include <vector>

#include "rt/bvh.h"
#include "rt/ray.h"
#include "rt/ray_query.h"

namespace cuberille::rt {

/// The children a wide node holds at most (one AVX vector of floats per box bound), and the
/// triangles a leaf group holds (one SSE vector per coordinate). Eight children were measured
/// faster than four on the dragon's random rays (bvh_bench: closest hits 1.8-2.0x the binary
/// tree's against 1.7-1.8x, shadow rays 2.4-2.6x against 1.9-2.2x): half the levels, half the
/// dependent cache misses. Groups stay at four: most leaves are smaller.
constexpr int kWideBvhWidth = 8;
constexpr int kTriangleGroupWidth = 4;

/// Four cache lines: six bound vectors (structure of arrays, so a slab of all eight children is
/// one load), then per child its node or its leaf's groups of triangles. Children fill the first
/// slots; an unused slot has child kNoChild and an empty box (lo +inf, hi -inf), which every ray
/// with a finite origin misses, and traversal checks the child as well.
struct alignas(64) WideBvhNode {
    static constexpr uint32_t kNoChild = ~0u;
    float lo[3][kWideBvhWidth];  // lo[axis][child]
    float hi[3][kWideBvhWidth];
    uint32_t child[kWideBvhWidth];       // inner child: its node index; leaf child: its first triangle group
    uint32_t leafGroups[kWideBvhWidth];  // 0 for an inner child (and an unused slot); else the leaf's groups

    int childCount() const {
        int n = 0;
        while (n < kWideBvhWidth && child[n] != kNoChild) ++n;
        return n;
    }
};
static_assert(sizeof(WideBvhNode) == 256, "four 64-byte cache lines");

/// Four of a leaf's triangles, structure of arrays, so that one watertight test (rt/ray.h) runs
/// on all four in vector lanes, each lane with the scalar test's operations in its order. A leaf
/// of n triangles has ceil(n / 4) groups; the last group's unused lanes have triangle
/// kNoTriangle and NaN vertices, which no test hits.
struct alignas(16) WideBvhTriangles {
    static constexpr uint32_t kNoTriangle = ~0u;
    float a[3][kTriangleGroupWidth];  // a[axis][lane]: the first vertex of each triangle
    float b[3][kTriangleGroupWidth];
    float c[3][kTriangleGroupWidth];
    uint32_t triangle[kTriangleGroupWidth];  // triangle ids
};
static_assert(sizeof(WideBvhTriangles) == 160);

struct WideBvh {
    std::vector<WideBvhNode> nodes;                // nodes[0] is the root; empty for an empty mesh
    std::vector<WideBvhTriangles> triangleGroups;  // leaves' triangles, each leaf's groups contiguous
    int height = 0;                                // the deepest leaf's depth in wide nodes
    // Where each box and vertex came from, for refreshWideBvh (side arrays: traversal never reads
    // them): per node, the binary node of each child slot; per group, the binary tree's slot
    // (leafVertices entry) of each lane. kNoChild / kNoTriangle where unused.
    std::vector<uint32_t> childSource;  // kWideBvhWidth per node
    std::vector<uint32_t> laneSource;   // kTriangleGroupWidth per group

    bool empty() const { return nodes.empty(); }
};

/// The wide tree over the same leaves as `binary`, whose leafVertices must be current (after a
/// build or a refit): it copies the vertices into its triangle groups. Deterministic: children
/// are taken in a fixed order, nodes laid out depth-first.
WideBvh collapseToWideBvh(const Bvh& binary);

/// Brings the boxes and vertices up to date with `binary` after it was refitted (rt/bvh_refit.h):
/// the same nodes as before, each box the binary node's it stands for and each vertex the leaf's
/// (tight, as the refit's are), at the cost of copies. `binary` must be the tree `wide` was
/// collapsed from, refitted but not rebuilt.
void refreshWideBvh(WideBvh& wide, const Bvh& binary);

/// The queries of rt/ray_query.h through the wide tree: the same answers, bit for bit (same
/// triangle, t and barycentrics as closestHitBruteForce; the same occlusion as anyHitBruteForce).
RayHit closestHit(const WideBvh& bvh, const Ray& ray);
RayHit closestHit(const WideBvh& bvh, const Ray& ray, TraversalCounters& counters);
/// The closest hit among the triangles not skipped (rt/ray.h, HitFilter).
RayHit closestHit(const WideBvh& bvh, const Ray& ray, const HitFilter& filter);
bool anyHit(const WideBvh& bvh, const Ray& ray, const HitFilter* filter = nullptr);

/// The most rays one packet of closestHits() holds: an 8x8 tile of camera rays.
inline constexpr int kMaxWidePacketRays = 64;

/// Closest hits of rays traced together as packets of up to kMaxWidePacketRays (camera rays of a
/// tile): a node is fetched once for the packet and its eight children tested against the packet
/// as a whole, in interval arithmetic over the box of the rays' origins and of their reciprocal
/// directions — a test no ray of the packet passes where it fails, so only boxes no ray can enter
/// are skipped — and a leaf's triangles are tested for each ray that passes its own exact test of
/// the leaf's box. hits[i] is exactly closestHit(bvh, rays[i]) (through `filter` where given),
/// whatever the packet. A packet whose rays do not all travel the same way along every axis, or
/// with a direction component of zero, is traced ray by ray.
void closestHits(const WideBvh& bvh, std::span<const Ray> rays, std::span<RayHit> hits, const HitFilter* filter = nullptr,
                 TraversalCounters* counters = nullptr);

/// Shadow and occlusion rays as packets the same way (a tile's surface points toward one light):
/// occluded[i] is exactly anyHit(bvh, rays[i]); a ray leaves its packet at its first hit.
void anyHits(const WideBvh& bvh, std::span<const Ray> rays, std::span<uint8_t> occluded, const HitFilter* filter = nullptr);

}  // namespace cuberille::rt
