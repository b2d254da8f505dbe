// One triangle against a grid packet's rays in vector lanes (rt/packet_triangle_lanes.h).

#include "rt/packet_triangle_lanes.h"

#include <cstring>

// Compiled once per instruction set (see raster/tile_raster.cpp for how foreach_target.h works).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "rt/packet_triangle_lanes.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace cuberille::rt {
namespace HWY_NAMESPACE {
namespace {

namespace hn = hwy::HWY_NAMESPACE;
// As many rays as the target has float lanes, up to 16 (AVX-512); Highway's scalar target, the
// baseline of this Highway version, takes them one at a time with the same operations.
using D = hn::CappedTag<float, 16>;
using V = hn::Vec<D>;

}  // namespace

/// WatertightRay::intersect's arithmetic, a ray a lane, over the groups of lanes that hold a
/// candidate: the vertices relative to each origin and sheared, the edge weights, their signs,
/// the determinant, and t against [tMin, bestT]. A lane is kept unless that test rejects it; a
/// lane with a zero edge weight is kept whatever its signs (the scalar test decides it in double).
uint64_t raysTheTriangleMayHitOnTarget(const PacketTriangleLanes& l, const float* bestT, uint64_t candidates,
                                       const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
    const D d;
    const size_t lanes = hn::Lanes(d);
    const uint64_t groupBits = lanes >= 64 ? ~uint64_t(0) : (uint64_t(1) << lanes) - 1;
    const glm::vec3* const vertices[3] = {&a, &b, &c};
    const V zero = hn::Zero(d);
    uint64_t kept = 0;
    for (size_t first = 0; first < size_t(kPacketTriangleLanesRays); first += lanes) {
        const uint64_t wanted = (candidates >> first) & groupBits;
        if (!wanted) continue;
        const V originX = hn::LoadU(d, l.originX + first), originY = hn::LoadU(d, l.originY + first);
        const V originZ = hn::LoadU(d, l.originZ + first);
        const V shearX = hn::LoadU(d, l.shearX + first), shearY = hn::LoadU(d, l.shearY + first);
        V sx[3], sy[3], z[3];
        for (int k = 0; k < 3; ++k) {
            const glm::vec3& p = *vertices[k];
            const V x = hn::Sub(hn::Set(d, p[l.kx]), originX);  // (p - origin)[kx]
            const V y = hn::Sub(hn::Set(d, p[l.ky]), originY);
            z[k] = hn::Sub(hn::Set(d, p[l.kz]), originZ);
            sx[k] = hn::Sub(x, hn::Mul(shearX, z[k]));
            sy[k] = hn::Sub(y, hn::Mul(shearY, z[k]));
        }
        const V u = hn::Sub(hn::Mul(sx[2], sy[1]), hn::Mul(sy[2], sx[1]));
        const V v = hn::Sub(hn::Mul(sx[0], sy[2]), hn::Mul(sy[0], sx[2]));
        const V w = hn::Sub(hn::Mul(sx[1], sy[0]), hn::Mul(sy[1], sx[0]));
        const auto anyZero = hn::Or(hn::Or(hn::Eq(u, zero), hn::Eq(v, zero)), hn::Eq(w, zero));
        const auto anyNegative = hn::Or(hn::Or(hn::Lt(u, zero), hn::Lt(v, zero)), hn::Lt(w, zero));
        const auto anyPositive = hn::Or(hn::Or(hn::Gt(u, zero), hn::Gt(v, zero)), hn::Gt(w, zero));
        const V det = hn::Add(hn::Add(u, v), w);
        const V shearZ = hn::LoadU(d, l.shearZ + first);
        const V az = hn::Mul(shearZ, z[0]), bz = hn::Mul(shearZ, z[1]), cz = hn::Mul(shearZ, z[2]);
        const V t = hn::Div(hn::Add(hn::Add(hn::Mul(u, az), hn::Mul(v, bz)), hn::Mul(w, cz)), det);
        const auto within = hn::And(hn::Ge(t, hn::LoadU(d, l.tMin + first)), hn::Le(t, hn::LoadU(d, bestT + first)));
        const auto rejected = hn::Or(hn::And(anyNegative, anyPositive), hn::Eq(det, zero));
        const auto keep = hn::Or(anyZero, hn::AndNot(rejected, within));
        uint8_t bytes[8] = {};
        hn::StoreMaskBits(d, keep, bytes);
        uint64_t bits;
        std::memcpy(&bits, bytes, sizeof bits);
        kept |= (bits & wanted) << first;
    }
    return kept;
}

}  // namespace HWY_NAMESPACE
}  // namespace cuberille::rt
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace cuberille::rt {

HWY_EXPORT(raysTheTriangleMayHitOnTarget);

bool PacketTriangleLanes::set(const WatertightRay* const* tests, const float* tMins, int count) {
    if (count <= 0 || count > kPacketTriangleLanesRays) return false;
    kx = tests[0]->kx, ky = tests[0]->ky, kz = tests[0]->kz;
    for (int i = 0; i < kPacketTriangleLanesRays; ++i) {
        if (i >= count) {  // lanes past the packet: read with their group, never wanted
            originX[i] = originY[i] = originZ[i] = shearX[i] = shearY[i] = shearZ[i] = tMin[i] = 0.0f;
            continue;
        }
        const WatertightRay& r = *tests[i];
        if (r.kx != kx || r.ky != ky || r.kz != kz) return false;
        originX[i] = r.origin[kx], originY[i] = r.origin[ky], originZ[i] = r.origin[kz];
        shearX[i] = r.shearX, shearY[i] = r.shearY, shearZ[i] = r.shearZ;
        tMin[i] = tMins[i];
    }
    return true;
}

uint64_t raysTheTriangleMayHit(const PacketTriangleLanes& lanes, const float* bestT, uint64_t candidates,
                               const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
    return HWY_DYNAMIC_DISPATCH(raysTheTriangleMayHitOnTarget)(lanes, bestT, candidates, a, b, c);
}

}  // namespace cuberille::rt
#endif  // HWY_ONCE
