#pragma once
// One triangle against many rays of a grid packet at once (Wald et al. 2006, §2: the packet's
// rays in SIMD lanes, where the rest of the traversal is per packet): the watertight test's
// arithmetic (rt/ray.h, WatertightRay::intersect) across the rays, as a filter in front of it.
//
// Exact by construction: each lane computes the scalar test's operations in its order (no fused
// multiply-add), so a lane rejects exactly where the scalar test would, and every lane it does
// not reject is handed to the scalar test, which then decides the hit as every traversal does
// (the triangle's own box, the filter, the tie rule). A lane whose edge weight comes out exactly
// zero, which the scalar test recomputes in double, is never rejected here.

#include <cstdint>

#include <glm/glm.hpp>

#include "rt/ray.h"

namespace cuberille::rt {

/// The rays of a packet of at most kPacketTriangleLanesRays as the lanes read them; only for
/// packets whose rays all share the watertight test's axis permutation (a coherent packet's rays
/// do: they share the major axis and its sign), which lets a triangle's vertex components be
/// the same in every lane.
inline constexpr int kPacketTriangleLanesRays = 64;

struct PacketTriangleLanes {
    int kx = 0, ky = 1, kz = 2;  // WatertightRay's permutation, the same for every ray
    alignas(64) float originX[kPacketTriangleLanesRays];  // origin[kx]
    alignas(64) float originY[kPacketTriangleLanesRays];  // origin[ky]
    alignas(64) float originZ[kPacketTriangleLanesRays];  // origin[kz]
    alignas(64) float shearX[kPacketTriangleLanesRays], shearY[kPacketTriangleLanesRays], shearZ[kPacketTriangleLanesRays];
    alignas(64) float tMin[kPacketTriangleLanesRays];

    /// Fills the lanes from each ray's WatertightRay; false (and unusable) when the permutations
    /// differ or there are more rays than lanes.
    bool set(const WatertightRay* const* tests, const float* tMins, int count);
};

/// Of the `candidates` (bit i: ray i), those whose watertight test against the triangle (a, b, c)
/// within [tMin, bestT[i]] the lanes do not reject: the scalar test may find a hit for them, and
/// finds none for the others. bestT holds a slot for every lane of the packet.
uint64_t raysTheTriangleMayHit(const PacketTriangleLanes& lanes, const float* bestT, uint64_t candidates,
                               const glm::vec3& a, const glm::vec3& b, const glm::vec3& c);

}  // namespace cuberille::rt
