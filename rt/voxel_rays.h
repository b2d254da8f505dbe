#pragma once
// Rays against voxels, the part every voxel acceleration structure shares (Chajdas 2015, chapter
// 5.3: "the same leaf intersection code is shared between all data structures"). Voxels are
// integer cells [x, x+1] x [y, y+1] x [z, z+1] of a grid of at most 65536 a side, stored as three
// 16-bit coordinates, and rays are given in the grid's units, so every plane a traversal meets
// (a voxel's face, a kD split, an octree's mid-plane, a BVH box face) is an integer, exact in float.
//
// What counts as a hit, so that every structure and traversal gives brute force's answer bit for
// bit (VoxelTrees tests):
//   - the ray's segment in a voxel is [enter, exit], each slab's t computed as (plane - origin) *
//     inverseDirection, the one formula every traversal uses for every plane;
//   - a direction component whose reciprocal is not finite is parallel to its axis, and then the
//     slab is half-open, [x, x+1): a ray lying exactly in the plane between two voxels is in the
//     upper one only (a symbolic nudge of the origin), so the cells of a kD tree or octree split
//     there partition it too;
//   - clipped to [tMin, tMax], the segment must have positive length: a ray that only touches a
//     voxel's edge or corner misses it, and a ray leaving a voxel's face from a point on it (a
//     shadow or occlusion ray, tMin 0) does not hit that voxel — no offset constant needed;
//   - the hit's t is where the clipped segment starts; the closest of two is the smaller t, then
//     the smaller coordinate key (a tie needs two voxels' segments to round to one start).
//
// Why it is exact under every traversal: a voxel's planes lie within the planes of every cell,
// node box or half-space containing it, and the slab formula is monotone in the plane, so its
// segment lies within theirs; a traversal that visits every node whose segment has positive
// length and starts no later than the best hit so far cannot miss it. Planes shared between
// neighbouring cells give the same t on both sides, so front-to-back order needs no tolerance.

#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "rt/ray.h"

namespace cuberille::rt {

/// A voxel as the ray tracer stores it (16 bits per axis, §5.3): the cell with this minimum corner.
struct VoxelCoord {
    uint16_t x = 0, y = 0, z = 0;
    bool operator==(const VoxelCoord&) const = default;
};
static_assert(sizeof(VoxelCoord) == 6);

/// The order ties are broken by: z, then y, then x.
inline uint64_t voxelKey(const VoxelCoord& v) { return uint64_t(v.z) << 32 | uint64_t(v.y) << 16 | v.x; }

/// A ray in grid units, prepared for slab tests.
struct VoxelRay {
    glm::vec3 origin{0.0f};
    glm::vec3 direction{0.0f, 0.0f, 1.0f};
    glm::vec3 inverseDirection{0.0f};
    int farSide[3] = {0, 0, 0};  // 1 where the direction component is negative (the far plane is lo)
    bool parallel[3] = {false, false, false};
    float tMin = 0.0f, tMax = std::numeric_limits<float>::infinity();

    explicit VoxelRay(const Ray& gridRay) : origin(gridRay.origin), direction(gridRay.direction), tMin(gridRay.tMin),
                                            tMax(gridRay.tMax) {
        for (int a = 0; a < 3; ++a) {
            inverseDirection[a] = 1.0f / direction[a];
            parallel[a] = !std::isfinite(inverseDirection[a]);
            farSide[a] = std::signbit(direction[a]) ? 1 : 0;
        }
    }

    /// Where the ray crosses the plane at `plane` on `axis` (not for a parallel axis).
    float planeT(int axis, float plane) const { return (plane - origin[axis]) * inverseDirection[axis]; }

    /// The ray's segment in the box [lo, hi] (integer corners), clipped to [tLo, tHi]: whether it
    /// has positive length, its ends in *enter and *exit, and the axis of the plane it enters by
    /// in *enterAxis (-1 when it starts inside, at tLo).
    bool segment(const glm::vec3& lo, const glm::vec3& hi, float tLo, float tHi, float* enter, float* exit,
                 int* enterAxis = nullptr) const {
        const glm::vec3* bounds[2] = {&lo, &hi};
        int axisIn = -1;
        for (int a = 0; a < 3; ++a) {
            if (parallel[a]) {
                if (!(origin[a] >= lo[a] && origin[a] < hi[a])) return false;
                continue;
            }
            const float t0 = planeT(a, (*bounds[farSide[a]])[a]);
            const float t1 = planeT(a, (*bounds[1 - farSide[a]])[a]);
            if (t0 > tLo) {
                tLo = t0;
                axisIn = a;
            }
            if (t1 < tHi) tHi = t1;
        }
        *enter = tLo;
        *exit = tHi;
        if (enterAxis) *enterAxis = axisIn;
        return tLo < tHi;
    }
};

struct VoxelHit {
    static constexpr uint32_t kNone = ~0u;
    float t = std::numeric_limits<float>::infinity();
    uint32_t voxel = kNone;  // index into the voxel array the structure was built from
    int8_t axis = -1;        // axis of the face the ray enters by; -1 when it starts inside the voxel
    uint64_t key = ~0ull;    // voxelKey of the voxel hit

    bool hit() const { return voxel != kNone; }
    /// The voxel face the ray enters by, as a unit normal (zero when it starts inside).
    glm::vec3 faceNormal(const VoxelRay& ray) const {
        glm::vec3 n(0.0f);
        if (axis >= 0) n[axis] = ray.farSide[axis] ? 1.0f : -1.0f;
        return n;
    }
    /// Where the ray enters `voxel` (the voxel hit), put exactly on the entered face's plane: the
    /// origin a shadow or occlusion ray leaves from, which the hit rule lets leave without an offset.
    glm::vec3 entryPoint(const VoxelRay& ray, const VoxelCoord& voxel) const {
        glm::vec3 p = ray.origin + t * ray.direction;
        if (axis >= 0) {
            const float lo = axis == 0 ? voxel.x : axis == 1 ? voxel.y : voxel.z;
            p[axis] = ray.farSide[axis] ? lo + 1.0f : lo;
        }
        return p;
    }
};

/// What a traversal did, summed over rays: the measures of Chajdas's Tables 10-13 that a CPU can
/// count exactly (nodes visited, leaves, voxels tested, restarts of a short stack that ran dry).
struct VoxelTraversalCounters {
    uint64_t rays = 0, hits = 0;
    uint64_t interiorSteps = 0;  // interior nodes visited
    uint64_t leafSteps = 0;      // leaves visited, empty ones included (§5.3: they take the leaf path)
    uint64_t voxelTests = 0;
    uint64_t restarts = 0;
    void add(const VoxelTraversalCounters& o) {
        rays += o.rays;
        hits += o.hits;
        interiorSteps += o.interiorSteps;
        leafSteps += o.leafSteps;
        voxelTests += o.voxelTests;
        restarts += o.restarts;
    }
};

/// The step kinds of one ray's traversal loop, in order, for simulating lanes that run it in
/// lockstep (voxelLaneOccupancy). Only filled when a traversal is handed one.
enum VoxelStep : uint8_t { kInteriorStep = 0, kLeafStep = 1 };
using VoxelStepTrace = std::vector<uint8_t>;

/// How a traversal keeps the nodes it must come back to (§5.4.4): a short stack of this many
/// entries, a ring whose oldest entry is overwritten when full; when it runs dry after losing one,
/// the traversal restarts from the root past the last leaf it finished. 0 entries: restart every
/// time (kd-restart); kFullStack: never overflows, no restarts.
struct VoxelTraversal {
    static constexpr int kFullStack = 64;
    int stackEntries = kFullStack;  // 0, or a power of two up to kFullStack
    bool anyHit = false;            // stop at the first voxel hit (shadow and occlusion rays)
};

/// The shared leaf routine: the voxel's segment against the ray's [tMin, tMax]; a hit replaces
/// `best` when closer by VoxelHit's order. Returns whether the ray hit the voxel at all.
inline bool offerVoxel(const VoxelRay& ray, const VoxelCoord& v, uint32_t id, VoxelHit& best) {
    const glm::vec3 lo(v.x, v.y, v.z);
    float enter, exit;
    int axis;
    if (!ray.segment(lo, lo + 1.0f, ray.tMin, ray.tMax, &enter, &exit, &axis)) return false;
    const uint64_t key = voxelKey(v);
    if (enter < best.t || (enter == best.t && key < best.key)) best = {enter, id, int8_t(axis), key};
    return true;
}

/// The reference: every voxel offered.
VoxelHit closestVoxelBruteForce(std::span<const VoxelCoord> voxels, const VoxelRay& ray);

/// Lockstep lanes, simulated: `lanes` rays run the while-if traversal loop together, each
/// iteration issuing the interior branch for the lanes at an interior step and the leaf branch
/// for those at a leaf (both when both are present); a lane that has finished idles. The share of
/// lane slots doing useful work, the CPU's counterpart of the GPU's "coherency" (§5.5, Table 12),
/// summed over groups of `lanes` consecutive rays: returns {useful slots, issued slots x lanes}.
struct LaneOccupancy {
    uint64_t usefulSlots = 0, laneSlots = 0;
    void add(const LaneOccupancy& o) {
        usefulSlots += o.usefulSlots;
        laneSlots += o.laneSlots;
    }
    double share() const { return laneSlots ? double(usefulSlots) / double(laneSlots) : 0.0; }
};
LaneOccupancy voxelLaneOccupancy(std::span<const VoxelStepTrace> rayTraces, int lanes);

}  // namespace cuberille::rt
