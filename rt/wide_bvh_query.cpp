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

#include <bit>
#include <cmath>
#include <optional>


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

/// The slab test of a node's eight children, lanes at a time: each axis's distances to the near
/// and the far bound come from distances(axis, nearBound, farBound, t0, t1); a bit per child met
/// within [tNear, tFar] (a NaN near distance constrains nothing), and each child's entry.
template <class Distances>
HWY_INLINE unsigned childrenMet(const WideBvhNode& node, const int (&nearSide)[3], float tNear, float tFar, float* entry,
                                Distances&& distances) {
    const DL d;
    constexpr size_t kLanes = hn::MaxLanes(DL());
    unsigned bits = 0;
    for (size_t first = 0; first < kWideBvhWidth; first += kLanes) {
        VL nearT = hn::Set(d, tNear), farT = hn::Set(d, tFar);
        for (int a = 0; a < 3; ++a) {
            const VL nearBound = hn::LoadU(d, (nearSide[a] ? node.hi[a] : node.lo[a]) + first);
            const VL farBound = hn::LoadU(d, (nearSide[a] ? node.lo[a] : node.hi[a]) + first);
            VL t0, t1;
            distances(a, nearBound, farBound, t0, t1);
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

/// RayBoxTest::hits for the node's eight children at once: a bit per child that the ray meets
/// within [tNear, tFar], and each child's entry.
HWY_INLINE unsigned hitChildren(const LaneRay& r, const WideBvhNode& node, float tNear, float tFar, float* entry) {
    return childrenMet(node, r.nearSide, tNear, tFar, entry, [&](int a, VL nearBound, VL farBound, VL& t0, VL& t1) {
        t0 = hn::Mul(hn::Sub(nearBound, r.origin[a]), r.inverseDirection[a]);
        t1 = hn::Mul(hn::Sub(farBound, r.origin[a]), r.inverseDirection[a]);
    });
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

/// A group's lane that hitTriangles found hit, made a hit as every traversal makes one: not a
/// skipped triangle, in its own box (WatertightRay::confirmInOwnBox), and past any alpha test.
HWY_INLINE bool laneHit(const WatertightRay& test, const WideBvhTriangles& group, int lane, const Ray& ray, float bestT,
                        const float* t, const float* u, const float* v, const HitFilter* filter, RayHit& candidate) {
    candidate.t = t[lane], candidate.u = u[lane], candidate.v = v[lane], candidate.triangle = group.triangle[lane];
    if (filter && filter->skips(candidate.triangle)) return false;
    const glm::vec3 a(group.a[0][lane], group.a[1][lane], group.a[2][lane]);
    const glm::vec3 b(group.b[0][lane], group.b[1][lane], group.b[2][lane]);
    const glm::vec3 c(group.c[0][lane], group.c[1][lane], group.c[2][lane]);
    if (!test.confirmInOwnBox(a, b, c, ray.tMin, bestT, candidate.t)) [[unlikely]]
        return false;
    return !filter || filter->keepsHit(candidate.triangle, ray, candidate.u, candidate.v);
}

/// Asks for a child's node or triangle groups ahead of its pop, so that a packet's cache misses
/// overlap.
HWY_INLINE void prefetchChild(const WideBvh& bvh, const WideBvhNode& node, int c) {
    const bool leaf = node.leafGroups[c] != 0;
    const char* next = leaf ? reinterpret_cast<const char*>(&bvh.triangleGroups[node.child[c]])
                            : reinterpret_cast<const char*>(&bvh.nodes[node.child[c]]);
    const size_t bytes = leaf ? sizeof(WideBvhTriangles) : sizeof(WideBvhNode);
    for (size_t line = 0; line < bytes; line += 64) __builtin_prefetch(next + line);
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
                    RayHit candidate;
                    if (!laneHit(triangleTest, group, __builtin_ctz(hits), ray, best.t, t, u, v, filter, candidate)) continue;
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
            prefetchChild(bvh, node, i);
        }
    }
    if (!best.hit()) best.t = std::numeric_limits<float>::infinity();
    return best;
}

/// A packet's rays as intervals, in every lane: the box of their origins and of their reciprocal
/// directions (which, all of one sign per axis, are finite), and per axis which bound is near.
struct PacketBounds {
    VL originLo[3], originHi[3], inverseLo[3], inverseHi[3];
    int nearSide[3];  // as LaneRay's, the same for every ray of the packet
};

/// hitChildren for a whole packet, conservatively: a bit per child that some ray of the packet
/// may meet within [tNear, tFar], and each child's lowest possible entry. Per axis a ray's slab
/// distances are fl(fl(bound - o) x inv); rounding is monotone, so over origins in [lo, hi] and
/// reciprocals in [lo, hi] each lies between the least and the greatest of the four corners'
/// values computed the same way. The packet's near value is then at most every ray's and its far
/// value at least every ray's, so a child every ray's own test (hitChildren) would open is opened
/// here: a skipped child is one no ray of the packet can enter.
HWY_INLINE unsigned packetHitsChildren(const PacketBounds& p, const WideBvhNode& node, float tNear, float tFar, float* entry) {
    return childrenMet(node, p.nearSide, tNear, tFar, entry, [&](int a, VL nearBound, VL farBound, VL& t0, VL& t1) {
        const VL n0 = hn::Sub(nearBound, p.originHi[a]), n1 = hn::Sub(nearBound, p.originLo[a]);
        const VL f0 = hn::Sub(farBound, p.originHi[a]), f1 = hn::Sub(farBound, p.originLo[a]);
        t0 = hn::Min(hn::Min(hn::Mul(n0, p.inverseLo[a]), hn::Mul(n0, p.inverseHi[a])),
                     hn::Min(hn::Mul(n1, p.inverseLo[a]), hn::Mul(n1, p.inverseHi[a])));
        t1 = hn::Max(hn::Max(hn::Mul(f0, p.inverseLo[a]), hn::Mul(f0, p.inverseHi[a])),
                     hn::Max(hn::Mul(f1, p.inverseLo[a]), hn::Mul(f1, p.inverseHi[a])));
    });
}

/// A child waiting on a packet's stack, with the rays that may enter it: for a leaf, those whose
/// own test of its box passed; for an inner node in the upper levels, its parent's; below them,
/// those whose own test passed (kIntervalLevels).
struct PendingForPacket {
    uint32_t child;
    uint32_t leafGroups;
    float entry;
    uint32_t depth;  // of the node, in wide levels
    uint64_t rays;
};

/// The levels whose nodes a packet tests as a whole, by intervals; below them each ray tests each
/// node's eight children itself (hitChildren) and hands each child only the rays that enter it.
/// Upper boxes are large beside a tile's spread of rays, so one interval test stands for all of
/// them; lower boxes of a dense mesh are as small as the pixels, and carrying rays that miss them
/// costs more than testing each. Measured on the camera rays of `render --renderer raytrace`
/// (1280x720, two threads, trace ms, medians of three alternating runs): intervals at every level
/// (while 16 rays or more remained) DamagedHelmet 23.4 against single rays' 33.8, but the dragon
/// 62.7 against 40.1; each ray's own tests at every level 29.6 and 40.4; intervals on the upper
/// three levels 27.8 against 30.6, and 36.9 against 39.2.
constexpr uint32_t kIntervalLevels = 3;

// One packet (closestHits' preconditions hold): the traversal the header describes. Exactness:
// every leaf holding a triangle a ray's closest hit can lie on is reached for that ray — its
// ancestors pass the packet test because they pass the ray's own (the packet's far value is the
// greatest of the rays' best hits, each no nearer than its final one), and the leaf's own box
// passes the ray's exact test with a far value no nearer than its final best — and extra triangle
// tests cannot change a closest hit whose ties go to the lower id.
/// Below the interval levels: each ray of `rays` (a bit per ray) tests the node's children itself,
/// within [its tMin, farOf(i)], and is handed to each open child it enters (childRays, a mask per
/// child).
template <class FarOf>
HWY_INLINE void raysEnteringChildren(const LaneRay* lanes, const Ray* rays, const WideBvhNode& node, uint64_t raysIn, unsigned open,
                                     FarOf&& farOf, uint64_t (&childRays)[kWideBvhWidth]) {
    alignas(32) float rayEntry[kWideBvhWidth];
    for (uint64_t each = raysIn; each != 0; each &= each - 1) {
        const int i = std::countr_zero(each);
        for (unsigned in = hitChildren(lanes[i], node, rays[i].tMin, farOf(i), rayEntry) & open; in != 0; in &= in - 1)
            childRays[__builtin_ctz(in)] |= uint64_t(1) << i;
    }
}

/// A packet's rays prepared: each ray's own tests and the packet's intervals.
struct PacketRays {
    std::optional<WatertightRay> tests[kMaxWidePacketRays];
    LaneRay lanes[kMaxWidePacketRays];
    PacketBounds bounds;
    float tNear = std::numeric_limits<float>::infinity();
    uint64_t all = 0;  // a bit per ray

    PacketRays(const Ray* rays, int n) {
        const DL d;
        glm::vec3 originLo(std::numeric_limits<float>::infinity()), originHi(-std::numeric_limits<float>::infinity());
        glm::vec3 inverseLo = originLo, inverseHi = originHi;
        for (int i = 0; i < n; ++i) {
            tests[i].emplace(rays[i]);
            lanes[i] = laneRay(tests[i]->box);
            tNear = std::min(tNear, rays[i].tMin);
            originLo = glm::min(originLo, rays[i].origin), originHi = glm::max(originHi, rays[i].origin);
            inverseLo = glm::min(inverseLo, tests[i]->box.inverseDirection), inverseHi = glm::max(inverseHi, tests[i]->box.inverseDirection);
        }
        for (int a = 0; a < 3; ++a) {
            bounds.originLo[a] = hn::Set(d, originLo[a]), bounds.originHi[a] = hn::Set(d, originHi[a]);
            bounds.inverseLo[a] = hn::Set(d, inverseLo[a]), bounds.inverseHi[a] = hn::Set(d, inverseHi[a]);
            bounds.nearSide[a] = tests[0]->box.farSide[a];
        }
        all = n == 64 ? ~uint64_t(0) : (uint64_t(1) << n) - 1;
    }
};


void packetClosestHits(const WideBvh& bvh, const Ray* rays, RayHit* hits, int n, const HitFilter* filter,
                       TraversalCounters* counters) {
    const PacketRays packet(rays, n);
    const auto& tests = packet.tests;
    const auto& lanes = packet.lanes;
    const PacketBounds& bounds = packet.bounds;
    const float tNear = packet.tNear;
    for (int i = 0; i < n; ++i) {
        hits[i] = RayHit{};
        hits[i].t = rays[i].tMax;
    }
    const auto packetFar = [&] {
        float far = -std::numeric_limits<float>::infinity();
        for (int i = 0; i < n; ++i) far = std::max(far, hits[i].t);
        return far * kEntrySlack;
    };
    PendingForPacket stack[(kWideBvhWidth - 1) * (kMaxBvhDepth + 1) + 1];
    int top = 0;
    if (!bvh.empty()) stack[top++] = {0u, 0u, tNear, 0u, packet.all};
    alignas(32) float entry[kWideBvhWidth];
    alignas(16) float t[kTriangleGroupWidth], u[kTriangleGroupWidth], v[kTriangleGroupWidth];
    float far = packetFar();  // the packet's far value, found again after each leaf (hits only come nearer)
    while (top > 0) {
        const PendingForPacket p = stack[--top];
        if (p.entry > far) continue;
        if (p.leafGroups != 0) {
            for (uint64_t each = p.rays; each != 0; each &= each - 1) {
                const int i = std::countr_zero(each);
                const Ray& ray = rays[i];
                RayHit& best = hits[i];
                for (uint32_t g = p.child; g < p.child + p.leafGroups; ++g) {
                    const WideBvhTriangles& group = bvh.triangleGroups[g];
                    if (counters)
                        for (const uint32_t id : group.triangle) counters->trianglesTested += id != WideBvhTriangles::kNoTriangle;
                    for (unsigned found = hitTriangles(*tests[i], group, ray.tMin, best.t, t, u, v); found != 0; found &= found - 1) {
                        RayHit candidate;
                        if (!laneHit(*tests[i], group, __builtin_ctz(found), ray, best.t, t, u, v, filter, candidate)) continue;
                        if (candidate.closerThan(best.t, best.triangle)) best = candidate;
                    }
                }
            }
            far = packetFar();
            continue;
        }
        const WideBvhNode& node = bvh.nodes[p.child];
        if (counters) ++counters->nodesVisited;
        unsigned open = packetHitsChildren(bounds, node, tNear, far, entry);
        int order[kWideBvhWidth], count = 0;
        uint64_t childRays[kWideBvhWidth] = {};
        const bool exact = p.depth >= kIntervalLevels;
        if (exact)  // each ray's own test of the eight children
            raysEnteringChildren(lanes, rays, node, p.rays, open, [&](int i) { return hits[i].t * kEntrySlack; }, childRays);
        for (; open != 0; open &= open - 1) {
            const int c = __builtin_ctz(open);
            if (node.child[c] == WideBvhNode::kNoChild) continue;
            if (!exact) {
                childRays[c] = p.rays;
                if (node.leafGroups[c] != 0) {  // the rays whose own test opens the leaf
                    const glm::vec3 lo(node.lo[0][c], node.lo[1][c], node.lo[2][c]), hi(node.hi[0][c], node.hi[1][c], node.hi[2][c]);
                    uint64_t in = 0;
                    float rayT = 0.0f;
                    for (uint64_t each = p.rays; each != 0; each &= each - 1) {
                        const int i = std::countr_zero(each);
                        if (tests[i]->box.hits(lo, hi, rays[i].tMin, hits[i].t * kEntrySlack, &rayT)) in |= uint64_t(1) << i;
                    }
                    childRays[c] = in;
                }
            }
            if (childRays[c] == 0) continue;
            int at = count++;
            for (; at > 0 && entry[order[at - 1]] < entry[c]; --at) order[at] = order[at - 1];
            order[at] = c;
        }
        for (int k = 0; k < count; ++k) {
            const int c = order[k];
            stack[top++] = {node.child[c], node.leafGroups[c], entry[c], p.depth + 1, childRays[c]};
            prefetchChild(bvh, node, c);
        }
    }
    for (int i = 0; i < n; ++i)
        if (!hits[i].hit()) hits[i].t = std::numeric_limits<float>::infinity();
}

// One packet of shadow or occlusion rays: packetClosestHits' traversal, with a ray leaving the
// packet at its first hit and the packet's far value the greatest tMax of the rays still in it.
// Exact as any-hit is: a ray is occluded when some triangle it reaches is hit, and every leaf a
// hit of the ray lies in is reached for it while it is in the packet (its ancestors pass the packet
// test because they pass its own, with a far value no nearer than its tMax).
void packetAnyHits(const WideBvh& bvh, const Ray* rays, uint8_t* occluded, int n, const HitFilter* filter) {
    const PacketRays packet(rays, n);
    uint64_t active = packet.all;
    const auto packetFar = [&] {
        float far = -std::numeric_limits<float>::infinity();
        for (uint64_t each = active; each != 0; each &= each - 1) far = std::max(far, rays[std::countr_zero(each)].tMax);
        return far * kEntrySlack;
    };
    for (int i = 0; i < n; ++i) occluded[i] = 0;
    PendingForPacket stack[(kWideBvhWidth - 1) * (kMaxBvhDepth + 1) + 1];
    int top = 0;
    if (!bvh.empty()) stack[top++] = {0u, 0u, packet.tNear, 0u, packet.all};
    alignas(32) float entry[kWideBvhWidth];
    alignas(16) float t[kTriangleGroupWidth], u[kTriangleGroupWidth], v[kTriangleGroupWidth];
    float far = packetFar();
    while (top > 0 && active != 0) {
        const PendingForPacket p = stack[--top];
        const uint64_t pending = p.rays & active;
        if (pending == 0 || p.entry > far) continue;
        if (p.leafGroups != 0) {
            for (uint64_t each = pending; each != 0; each &= each - 1) {
                const int i = std::countr_zero(each);
                const Ray& ray = rays[i];
                for (uint32_t g = p.child; g < p.child + p.leafGroups && !occluded[i]; ++g) {
                    const WideBvhTriangles& group = bvh.triangleGroups[g];
                    for (unsigned found = hitTriangles(*packet.tests[i], group, ray.tMin, ray.tMax, t, u, v); found != 0;
                         found &= found - 1) {
                        RayHit candidate;
                        if (!laneHit(*packet.tests[i], group, __builtin_ctz(found), ray, ray.tMax, t, u, v, filter, candidate)) continue;
                        occluded[i] = 1;
                        active &= ~(uint64_t(1) << i);
                        break;
                    }
                }
            }
            far = packetFar();
            continue;
        }
        const WideBvhNode& node = bvh.nodes[p.child];
        unsigned open = packetHitsChildren(packet.bounds, node, packet.tNear, far, entry);
        uint64_t childRays[kWideBvhWidth] = {};
        if (p.depth >= kIntervalLevels) {
            raysEnteringChildren(packet.lanes, rays, node, pending, open, [&](int i) { return rays[i].tMax * kEntrySlack; }, childRays);
        } else {
            for (unsigned in = open; in != 0; in &= in - 1) childRays[__builtin_ctz(in)] = pending;
        }
        // Children in lane order, as a single any-hit ray takes them (rt/wide_bvh_query.cpp, traverse).
        for (; open != 0; open &= open - 1) {
            const int c = __builtin_ctz(open);
            if (node.child[c] == WideBvhNode::kNoChild || childRays[c] == 0) continue;
            stack[top++] = {node.child[c], node.leafGroups[c], entry[c], p.depth + 1, childRays[c]};
            prefetchChild(bvh, node, c);
        }
    }
}

}  // namespace

void closestHitsOnTarget(const WideBvh& bvh, const Ray* rays, RayHit* hits, int n, const HitFilter* filter,
                         TraversalCounters* counters) {
    packetClosestHits(bvh, rays, hits, n, filter, counters);
}

RayHit closestHitOnTarget(const WideBvh& bvh, const Ray& ray, TraversalCounters* counters, const HitFilter* filter) {
    return traverse<false>(bvh, ray, counters, filter);
}

bool anyHitOnTarget(const WideBvh& bvh, const Ray& ray, const HitFilter* filter) { return traverse<true>(bvh, ray, nullptr, filter).hit(); }

void anyHitsOnTarget(const WideBvh& bvh, const Ray* rays, uint8_t* occluded, int n, const HitFilter* filter) {
    packetAnyHits(bvh, rays, occluded, n, filter);
}

}  // namespace HWY_NAMESPACE
}  // namespace cuberille::rt
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace cuberille::rt {

HWY_EXPORT(closestHitOnTarget);
HWY_EXPORT(closestHitsOnTarget);
HWY_EXPORT(anyHitOnTarget);
HWY_EXPORT(anyHitsOnTarget);

RayHit closestHit(const WideBvh& bvh, const Ray& ray) { return HWY_DYNAMIC_DISPATCH(closestHitOnTarget)(bvh, ray, nullptr, nullptr); }

RayHit closestHit(const WideBvh& bvh, const Ray& ray, TraversalCounters& counters) {
    return HWY_DYNAMIC_DISPATCH(closestHitOnTarget)(bvh, ray, &counters, nullptr);
}

RayHit closestHit(const WideBvh& bvh, const Ray& ray, const HitFilter& filter) {
    return HWY_DYNAMIC_DISPATCH(closestHitOnTarget)(bvh, ray, nullptr, &filter);
}

bool anyHit(const WideBvh& bvh, const Ray& ray, const HitFilter* filter) {
    return HWY_DYNAMIC_DISPATCH(anyHitOnTarget)(bvh, ray, filter);
}

namespace {

// Whether the rays may go as one packet: the same direction sign on every axis, no zero component
// (the packet test's reciprocal intervals must be finite and of one sign).
bool travelsAsOnePacket(std::span<const Ray> rays) {
    for (int a = 0; a < 3; ++a) {
        const bool negative = std::signbit(rays[0].direction[a]);
        for (const Ray& r : rays) {
            const float inverse = 1.0f / r.direction[a];
            if (std::signbit(r.direction[a]) != negative || !std::isfinite(inverse)) return false;
        }
    }
    return true;
}

}  // namespace

void closestHits(const WideBvh& bvh, std::span<const Ray> rays, std::span<RayHit> hits, const HitFilter* filter,
                 TraversalCounters* counters) {
    for (size_t first = 0; first < rays.size(); first += kMaxWidePacketRays) {
        const size_t count = std::min(rays.size() - first, size_t(kMaxWidePacketRays));
        const std::span<const Ray> packet = rays.subspan(first, count);
        if (travelsAsOnePacket(packet)) {
            HWY_DYNAMIC_DISPATCH(closestHitsOnTarget)(bvh, packet.data(), hits.data() + first, int(count), filter, counters);
            continue;
        }
        for (size_t i = 0; i < count; ++i)
            hits[first + i] = HWY_DYNAMIC_DISPATCH(closestHitOnTarget)(bvh, packet[i], counters, filter);
    }
}

void anyHits(const WideBvh& bvh, std::span<const Ray> rays, std::span<uint8_t> occluded, const HitFilter* filter) {
    for (size_t first = 0; first < rays.size(); first += kMaxWidePacketRays) {
        const size_t count = std::min(rays.size() - first, size_t(kMaxWidePacketRays));
        const std::span<const Ray> packet = rays.subspan(first, count);
        if (travelsAsOnePacket(packet)) {
            HWY_DYNAMIC_DISPATCH(anyHitsOnTarget)(bvh, packet.data(), occluded.data() + first, int(count), filter);
            continue;
        }
        for (size_t i = 0; i < count; ++i) occluded[first + i] = HWY_DYNAMIC_DISPATCH(anyHitOnTarget)(bvh, packet[i], filter);
    }
}

}  // namespace cuberille::rt
#endif  // HWY_ONCE
