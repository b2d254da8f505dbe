// Ray queries through the wide BVH (rt/wide_bvh.h): one vector slab test for a node's eight
// children, then the hit children visited nearest first.
//
// Exactness is rt/ray_query.h's argument unchanged: each lane computes RayBoxTest::hits's
// operations in its order (two roundings a slab bound, the same NaN-ignoring selects, the same
// 2 gamma(3) growth of the far value), so a lane opens exactly the boxes the scalar test opens,
// and a triangle is only ever skipped behind a box whose entry lies past the best hit times
// kEntrySlack. The closest hit is then found whatever the order, and the tie rule of offerHit
// makes it brute force's.

#include "rt/wide_bvh.h"


// Compiled once per instruction set (see raster/tile_raster.cpp for how foreach_target.h works).
// Eight float lanes are one AVX register; Highway's emulation gives the same bits where a CPU has
// none of its vector targets.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "rt/wide_bvh_query.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace cuberille::rt {
namespace HWY_NAMESPACE {
namespace {

namespace hn = hwy::HWY_NAMESPACE;
// Eight lanes (four a triangle group) where the target has them; Highway's scalar target, the
// baseline of this Highway version, takes the children one lane at a time with the same
// operations.
using DL = hn::CappedTag<float, kWideBvhWidth>;
using VL = hn::Vec<DL>;
using DG = hn::CappedTag<float, kTriangleGroupWidth>;
using VG = hn::Vec<DG>;
using detail::kEntrySlack;

/// A child waiting on the stack: where to go, and where the ray enters its box (a child whose
/// entry has fallen behind a hit found since it was pushed is dropped when popped).
struct Pending {
    uint32_t child;
    uint32_t leafGroups;  // 0: an inner node; else a leaf's groups of triangles from `child`
    float entry;
};

/// The ray in every lane, with each axis's near and far bound chosen by the direction's sign.
struct LaneRay {
    VL origin[3], inverseDirection[3];
    int nearSide[3];  // 0: the near bound is lo (a non-negative direction); 1: hi
};

HWY_INLINE LaneRay laneRay(const RayBoxTest& test) {
    const DL d;
    LaneRay r;
    for (int a = 0; a < 3; ++a) {
        r.origin[a] = hn::Set(d, test.origin[a]);
        r.inverseDirection[a] = hn::Set(d, test.inverseDirection[a]);
        r.nearSide[a] = test.farSide[a];
    }
    return r;
}

/// RayBoxTest::hits for the node's eight children at once: a bit per child that the ray meets
/// within [tNear, tFar], and each child's entry.
HWY_INLINE unsigned hitChildren(const LaneRay& r, const WideBvhNode& node, float tNear, float tFar, float* entry) {
    const DL d;
    constexpr size_t kLanes = hn::MaxLanes(DL());
    unsigned bits = 0;
    for (size_t first = 0; first < kWideBvhWidth; first += kLanes) {
        VL nearT = hn::Set(d, tNear), farT = hn::Set(d, tFar);
        for (int a = 0; a < 3; ++a) {
            const float* nearBound = (r.nearSide[a] ? node.hi[a] : node.lo[a]) + first;
            const float* farBound = (r.nearSide[a] ? node.lo[a] : node.hi[a]) + first;
            const VL t0 = hn::Mul(hn::Sub(hn::LoadU(d, nearBound), r.origin[a]), r.inverseDirection[a]);
            const VL t1 = hn::Mul(hn::Sub(hn::LoadU(d, farBound), r.origin[a]), r.inverseDirection[a]);
            nearT = hn::IfThenElse(hn::Gt(t0, nearT), t0, nearT);  // a NaN t0 leaves nearT as it was
            farT = hn::IfThenElse(hn::Lt(t1, farT), t1, farT);
        }
        hn::StoreU(nearT, d, entry + first);
        uint8_t laneBits = 0;
        hn::StoreMaskBits(d, hn::Le(nearT, hn::Mul(farT, hn::Set(d, 1.0f + 2.0f * roundingGamma(3)))), &laneBits);
        bits |= unsigned(laneBits) << first;
    }
    return bits;
}

/// WatertightRay::intersect on a group's four triangles, a lane each: the lanes whose triangle
/// the ray hits within [tMin, tMax], with each lane's t and weights. Every lane computes the
/// scalar test's operations in its order (no fused multiply-add: Mul then Sub or Add), so each
/// hit, t and weight is the scalar test's bit for bit; edge weights that come out exactly zero
/// are recomputed in double by the scalar routine, as the scalar test does.
HWY_INLINE unsigned hitTriangles(const WatertightRay& ray, const WideBvhTriangles& group, float tMin, float tMax,
                                 float* t, float* u, float* v) {
    const DG d;
    constexpr size_t kLanes = hn::MaxLanes(DG());
    const int axes[3] = {ray.kx, ray.ky, ray.kz};
    unsigned bits = 0;
    for (size_t first = 0; first < kTriangleGroupWidth; first += kLanes) {
        // The vertices relative to the origin, sheared so the ray is the +z axis.
        VG sx[3], sy[3], sz[3];
        const float* const corners[3][3] = {{group.a[0], group.a[1], group.a[2]},
                                            {group.b[0], group.b[1], group.b[2]},
                                            {group.c[0], group.c[1], group.c[2]}};
        for (int k = 0; k < 3; ++k) {
            const VG x = hn::Sub(hn::LoadU(d, corners[k][axes[0]] + first), hn::Set(d, ray.origin[axes[0]]));
            const VG y = hn::Sub(hn::LoadU(d, corners[k][axes[1]] + first), hn::Set(d, ray.origin[axes[1]]));
            const VG z = hn::Sub(hn::LoadU(d, corners[k][axes[2]] + first), hn::Set(d, ray.origin[axes[2]]));
            sx[k] = hn::Sub(x, hn::Mul(hn::Set(d, ray.shearX), z));
            sy[k] = hn::Sub(y, hn::Mul(hn::Set(d, ray.shearY), z));
            sz[k] = z;
        }
        VG eu = hn::Sub(hn::Mul(sx[2], sy[1]), hn::Mul(sy[2], sx[1]));
        VG ev = hn::Sub(hn::Mul(sx[0], sy[2]), hn::Mul(sy[0], sx[2]));
        VG ew = hn::Sub(hn::Mul(sx[1], sy[0]), hn::Mul(sy[1], sx[0]));
        const VG zero = hn::Zero(d);
        if (!hn::AllFalse(d, hn::Or(hn::Or(hn::Eq(eu, zero), hn::Eq(ev, zero)), hn::Eq(ew, zero)))) [[unlikely]] {
            alignas(16) float lanes[9][kTriangleGroupWidth];
            for (int k = 0; k < 3; ++k) hn::StoreU(sx[k], d, lanes[2 * k]), hn::StoreU(sy[k], d, lanes[2 * k + 1]);
            hn::StoreU(eu, d, lanes[6]), hn::StoreU(ev, d, lanes[7]), hn::StoreU(ew, d, lanes[8]);
            for (size_t i = 0; i < kLanes; ++i)
                if (lanes[6][i] == 0.0f || lanes[7][i] == 0.0f || lanes[8][i] == 0.0f)
                    WatertightRay::edgeWeightsInDouble(lanes[0][i], lanes[1][i], lanes[2][i], lanes[3][i], lanes[4][i],
                                                       lanes[5][i], lanes[6][i], lanes[7][i], lanes[8][i]);
            eu = hn::LoadU(d, lanes[6]), ev = hn::LoadU(d, lanes[7]), ew = hn::LoadU(d, lanes[8]);
        }
        const auto anyNegative = hn::Or(hn::Or(hn::Lt(eu, zero), hn::Lt(ev, zero)), hn::Lt(ew, zero));
        const auto anyPositive = hn::Or(hn::Or(hn::Gt(eu, zero), hn::Gt(ev, zero)), hn::Gt(ew, zero));
        const VG det = hn::Add(hn::Add(eu, ev), ew);
        const VG shearZ = hn::Set(d, ray.shearZ);
        const VG az = hn::Mul(shearZ, sz[0]), bz = hn::Mul(shearZ, sz[1]), cz = hn::Mul(shearZ, sz[2]);
        const VG tHit = hn::Div(hn::Add(hn::Add(hn::Mul(eu, az), hn::Mul(ev, bz)), hn::Mul(ew, cz)), det);
        const auto within = hn::And(hn::Ge(tHit, hn::Set(d, tMin)), hn::Le(tHit, hn::Set(d, tMax)));
        const auto hit = hn::AndNot(hn::Or(hn::And(anyNegative, anyPositive), hn::Eq(det, zero)), within);
        uint8_t laneBits = 0;
        hn::StoreMaskBits(d, hit, &laneBits);
        if (laneBits == 0) continue;
        hn::StoreU(tHit, d, t + first);
        hn::StoreU(hn::Div(ev, det), d, u + first);
        hn::StoreU(hn::Div(ew, det), d, v + first);
        bits |= unsigned(laneBits) << first;
    }
    return bits;
}

template <bool kAnyHit>
RayHit traverse(const WideBvh& bvh, const Ray& ray, TraversalCounters* counters, const HitFilter* filter = nullptr) {
    RayHit best;
    best.t = ray.tMax;
    if (bvh.empty()) return best;
    const RayBoxTest boxTest(ray);
    const LaneRay lanes = laneRay(boxTest);
    const WatertightRay triangleTest(ray);
    // Each wide level pops one node and pushes at most kWideBvhWidth children.
    Pending stack[(kWideBvhWidth - 1) * (kMaxBvhDepth + 1) + 1];
    int top = 0;
    stack[top++] = {0u, 0u, ray.tMin};
    alignas(32) float entry[kWideBvhWidth];
    alignas(16) float t[kTriangleGroupWidth], u[kTriangleGroupWidth], v[kTriangleGroupWidth];
    while (top > 0) {
        const Pending p = stack[--top];
        if (p.entry > best.t * kEntrySlack) continue;
        if (p.leafGroups != 0) {
            for (uint32_t g = p.child; g < p.child + p.leafGroups; ++g) {
                const WideBvhTriangles& group = bvh.triangleGroups[g];
                if (counters)
                    for (const uint32_t id : group.triangle) counters->trianglesTested += id != WideBvhTriangles::kNoTriangle;
                // Every lane tests against the best hit as the group began; offering the hits in
                // lane order then keeps the nearest, lower id on a tie: RayHit's order, which
                // does not depend on the order triangles are met in.
                for (unsigned hits = hitTriangles(triangleTest, group, ray.tMin, best.t, t, u, v); hits != 0; hits &= hits - 1) {
                    const int i = __builtin_ctz(hits);
                    RayHit candidate;
                    candidate.t = t[i], candidate.u = u[i], candidate.v = v[i], candidate.triangle = group.triangle[i];
                    const glm::vec3 a(group.a[0][i], group.a[1][i], group.a[2][i]);
                    const glm::vec3 b(group.b[0][i], group.b[1][i], group.b[2][i]);
                    const glm::vec3 c(group.c[0][i], group.c[1][i], group.c[2][i]);
                    if (filter && filter->skips(candidate.triangle)) continue;
                    if (!triangleTest.confirmInOwnBox(a, b, c, ray.tMin, best.t, candidate.t)) [[unlikely]]
                        continue;
                    if (filter && !filter->keepsHit(candidate.triangle, ray, candidate.u, candidate.v)) continue;
                    if (kAnyHit) return candidate;
                    if (candidate.closerThan(best.t, best.triangle)) best = candidate;
                }
            }
            continue;
        }
        const WideBvhNode& node = bvh.nodes[p.child];
        if (counters) ++counters->nodesVisited;
        unsigned hits = hitChildren(lanes, node, ray.tMin, best.t * kEntrySlack, entry);
        // Push the hit children farthest first, so that the nearest is popped next. Any-hit
        // pushes them in lane order: the order only changes which occluder is found first, and
        // sorting cost shadow rays a third of their speed (dragon, bvh_bench). Visiting only the
        // nearest first, the rest unsorted, was measured no faster for closest hits.
        int order[kWideBvhWidth], count = 0;
        for (; hits != 0; hits &= hits - 1) {
            const int i = __builtin_ctz(hits);
            if (node.child[i] == WideBvhNode::kNoChild) continue;  // only a ray from infinity gets here
            int at = count++;
            if (!kAnyHit)
                for (; at > 0 && entry[order[at - 1]] < entry[i]; --at) order[at] = order[at - 1];
            order[at] = i;
        }
        for (int k = 0; k < count; ++k) {
            const int i = order[k];
            stack[top++] = {node.child[i], node.leafGroups[i], entry[i]};
            // Rays that scatter miss the cache at nearly every node (profiled on the dragon: the
            // node's first load was 40% of a shadow ray's time): ask for every hit child now, so
            // the misses overlap instead of following one another.
            const bool leaf = node.leafGroups[i] != 0;
            const char* next = leaf ? reinterpret_cast<const char*>(&bvh.triangleGroups[node.child[i]])
                                    : reinterpret_cast<const char*>(&bvh.nodes[node.child[i]]);
            const size_t bytes = leaf ? sizeof(WideBvhTriangles) : sizeof(WideBvhNode);
            for (size_t line = 0; line < bytes; line += 64) __builtin_prefetch(next + line);
        }
    }
    if (!best.hit()) best.t = std::numeric_limits<float>::infinity();
    return best;
}

}  // namespace

RayHit closestHitOnTarget(const WideBvh& bvh, const Ray& ray, TraversalCounters* counters, const HitFilter* filter) {
    return traverse<false>(bvh, ray, counters, filter);
}

bool anyHitOnTarget(const WideBvh& bvh, const Ray& ray) { return traverse<true>(bvh, ray, nullptr).hit(); }

}  // namespace HWY_NAMESPACE
}  // namespace cuberille::rt
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace cuberille::rt {

HWY_EXPORT(closestHitOnTarget);
HWY_EXPORT(anyHitOnTarget);

RayHit closestHit(const WideBvh& bvh, const Ray& ray) { return HWY_DYNAMIC_DISPATCH(closestHitOnTarget)(bvh, ray, nullptr, nullptr); }

RayHit closestHit(const WideBvh& bvh, const Ray& ray, TraversalCounters& counters) {
    return HWY_DYNAMIC_DISPATCH(closestHitOnTarget)(bvh, ray, &counters, nullptr);
}

RayHit closestHit(const WideBvh& bvh, const Ray& ray, const HitFilter& filter) {
    return HWY_DYNAMIC_DISPATCH(closestHitOnTarget)(bvh, ray, nullptr, &filter);
}

bool anyHit(const WideBvh& bvh, const Ray& ray) { return HWY_DYNAMIC_DISPATCH(anyHitOnTarget)(bvh, ray); }

}  // namespace cuberille::rt
#endif  // HWY_ONCE
