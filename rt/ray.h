#pragma once
// Rays and the two tests every traversal is made of: ray against box (robust: conservative and
// NaN-safe, after Ize, "Robust BVH Ray Traversal", 2013) and ray against triangle (watertight,
// after Woop, Benthin and Wald, 2013). Both are exact about the cases that break naive code:
// direction components of +0 or -0, origins on a box face, rays through triangle edges and
// vertices.

#include <cmath>
#include <cstdint>
#include <limits>
#include <span>

#include <glm/glm.hpp>

namespace cuberille::rt {

struct Ray {
    glm::vec3 origin{0.0f};
    glm::vec3 direction{0.0f, 0.0f, 1.0f};  // need not be normalised; t is in its units
    float tMin = 0.0f;                      // the hit interval is [tMin, tMax]; tMin >= 0
    float tMax = std::numeric_limits<float>::infinity();
};

struct RayHit {
    static constexpr uint32_t kNone = ~0u;
    float t = std::numeric_limits<float>::infinity();
    uint32_t triangle = kNone;
    float u = 0.0f, v = 0.0f;  // barycentric weights of the second and third vertex

    bool hit() const { return triangle != kNone; }
    /// The order that makes closest-hit deterministic: nearer first, then the lower triangle id,
    /// so a ray through a shared edge reports the same triangle whatever the traversal order.
    bool closerThan(float otherT, uint32_t otherTriangle) const {
        return t < otherT || (t == otherT && triangle < otherTriangle);
    }
};

/// gamma(n) of Higham (pbrt-v4's `gamma`): a bound on the relative error of n rounded float operations.
constexpr float roundingGamma(int n) {
    constexpr float eps = std::numeric_limits<float>::epsilon() * 0.5f;
    return (float(n) * eps) / (1.0f - float(n) * eps);
}

/// A ray prepared for box tests: reciprocal direction (±inf for zero components) and the sign of
/// each component, which picks the near and far slab without branching on values.
struct RayBoxTest {
    glm::vec3 origin;
    glm::vec3 inverseDirection;
    int farSide[3];  // 1 when the component is negative (signbit, so -0 counts as negative)

    explicit RayBoxTest(const Ray& ray) : origin(ray.origin) {
        for (int a = 0; a < 3; ++a) {
            inverseDirection[a] = 1.0f / ray.direction[a];
            farSide[a] = std::signbit(ray.direction[a]) ? 1 : 0;
        }
    }

    /// Whether the ray meets box [lo, hi] within [tNear, tFar]; *entry gets where it enters.
    ///
    /// NaN arises as 0 x inf when the origin lies on a slab's plane and the direction is parallel
    /// to it. The ordered comparisons below (`candidate > current ? candidate : current`) return
    /// the current value when the candidate is NaN, so such a slab constrains nothing and the ray
    /// lying in the box's face counts as inside: conservative. The far value grows by 2 gamma(3)
    /// because each slab distance carries up to three roundings (Ize 2013).
    bool hits(const glm::vec3& lo, const glm::vec3& hi, float tNear, float tFar, float* entry) const {
        const glm::vec3* bounds[2] = {&lo, &hi};
        for (int a = 0; a < 3; ++a) {
            const float t0 = ((*bounds[farSide[a]])[a] - origin[a]) * inverseDirection[a];
            const float t1 = ((*bounds[1 - farSide[a]])[a] - origin[a]) * inverseDirection[a];
            tNear = t0 > tNear ? t0 : tNear;
            tFar = t1 < tFar ? t1 : tFar;
        }
        *entry = tNear;
        return tNear <= tFar * (1.0f + 2.0f * roundingGamma(3));
    }
};

/// A ray prepared for watertight triangle tests (Woop et al. 2013, section 3): translate to the
/// origin, permute so the largest direction component is z, shear so the ray is the +z axis.
/// Every triangle edge is then a 2D cross product of two sheared vertices, computed the same way
/// for both triangles that share it, so a ray through an edge or vertex cannot slip between them.
///
/// A hit also needs the ray to meet the triangle's own bounding box, and its t is raised to where
/// the ray enters that box (confirmInOwnBox): the watertight t is exact about *whether* the ray
/// crosses the triangle, but its value carries a few ulps of the vertices' distance, which can
/// round a hit just behind the origin (a ray leaving a flat face from within ulps of it, tMin 0)
/// to +-0 or above. A traversal reaches a triangle only through boxes that contain its box, and
/// the slab test is monotone in the bounds, so with the box in the definition every traversal
/// (brute force, the BVHs, the grid's walk and packets) accepts exactly the same hits.
struct WatertightRay {
    glm::vec3 origin;
    int kx, ky, kz;
    float shearX, shearY, shearZ;
    RayBoxTest box;

    explicit WatertightRay(const Ray& ray);

    /// Hit with t in [tMin, tMax]: writes t and barycentrics into *hit (not its triangle).
    /// Both windings hit; degenerate triangles never do. Inline: it is the inner loop of every
    /// traversal (out of line, the call was a quarter of a grid or BVH ray's time).
    bool intersect(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, float tMin, float tMax,
                   RayHit* hit) const {
        const glm::vec3 A = a - origin, B = b - origin, C = c - origin;
        const float ax = A[kx] - shearX * A[kz], ay = A[ky] - shearY * A[kz];
        const float bx = B[kx] - shearX * B[kz], by = B[ky] - shearY * B[kz];
        const float cx = C[kx] - shearX * C[kz], cy = C[ky] - shearY * C[kz];
        float u = cx * by - cy * bx;
        float v = ax * cy - ay * cx;
        float w = bx * ay - by * ax;
        // Exactly zero in float may be a rounded sign: decide edge hits in double, where the
        // products of two floats are exact (section 3.3 of the paper).
        if (u == 0.0f || v == 0.0f || w == 0.0f) [[unlikely]]
            edgeWeightsInDouble(ax, ay, bx, by, cx, cy, u, v, w);
        if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) return false;
        const float det = u + v + w;
        if (det == 0.0f) return false;
        const float az = shearZ * A[kz], bz = shearZ * B[kz], cz = shearZ * C[kz];
        const float t = (u * az + v * bz + w * cz) / det;
        if (!(t >= tMin && t <= tMax)) return false;
        float tInBox = t;
        if (!confirmInOwnBox(a, b, c, tMin, tMax, tInBox)) [[unlikely]]
            return false;
        hit->t = tInBox;
        hit->u = v / det;
        hit->v = w / det;
        return true;
    }

    /// The second half of a hit's definition, for a t the watertight test found in [tMin, tMax]:
    /// the ray meets the triangle's bounding box at or after tMin, and t becomes at least that
    /// box's entry (at most ulps of a change) and still no more than tMax. The wide BVH's lanes
    /// call it for each lane they hit. Only hits pay for it, not every triangle tested.
    bool confirmInOwnBox(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, float tMin, float tMax, float& t) const {
        float entry = 0.0f;
        if (!box.hits(glm::min(a, glm::min(b, c)), glm::max(a, glm::max(b, c)), tMin, std::numeric_limits<float>::infinity(),
                      &entry))
            return false;
        t = entry > t ? entry : t;
        return t <= tMax;
    }

    /// The edge weights u, v, w recomputed in double and rounded once.
    static void edgeWeightsInDouble(float ax, float ay, float bx, float by, float cx, float cy, float& u, float& v, float& w);
};

/// What a closest-hit search leaves out, for camera rays (rt/primary_rays.h): triangles by id —
/// what the rasterizer's face culling removes for one view — and, on alpha-tested triangles, the
/// hits where the material's alpha falls below its cutoff (an any-hit shader's work). Every
/// traversal (brute force, the binary and wide BVHs, lazily updated or not, the grid's walk and
/// packets) applies it to the same hits, so they stay exact against one another and against
/// brute force over what it keeps.
struct HitFilter {
    static constexpr uint8_t kKept = 0, kSkipped = 1, kAlphaTested = 2;
    std::span<const uint8_t> triangle;  // per triangle id: kKept, kSkipped or kAlphaTested
    /// For kAlphaTested triangles: whether the hit at weights (u, v) of the second and third vertex
    /// survives the alpha test. Called only for hits nearer than the best so far.
    bool (*passes)(const void* context, uint32_t triangle, const Ray& ray, float u, float v) = nullptr;
    const void* context = nullptr;

    bool skips(uint32_t t) const { return triangle[t] == kSkipped; }
    bool alphaTests(uint32_t t) const { return triangle[t] == kAlphaTested; }
    bool keepsHit(uint32_t t, const Ray& ray, float u, float v) const {
        return !alphaTests(t) || passes(context, t, ray, u, v);
    }
};

/// One triangle offered to a closest-hit or any-hit search, as every traversal does it (the BVH's,
/// the grid's walk and packets, brute force): a hit within [tMin, best.t] replaces `best` when it
/// is closer by RayHit's order. Returns whether the ray hit the triangle at all, which ends an
/// any-hit search (its first hit always replaces `best`, whose triangle is still kNone). With a
/// `filter` (and the `ray` its alpha test reads), a skipped triangle is not tested and an
/// alpha-tested one's hit counts only where it passes.
inline bool offerHit(const WatertightRay& test, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, uint32_t triangle,
                     float tMin, RayHit& best, const HitFilter* filter = nullptr, const Ray* ray = nullptr) {
    if (filter && filter->skips(triangle)) return false;
    RayHit candidate;
    if (!test.intersect(a, b, c, tMin, best.t, &candidate)) return false;
    if (filter && !filter->keepsHit(triangle, *ray, candidate.u, candidate.v)) return false;
    candidate.triangle = triangle;
    if (candidate.closerThan(best.t, best.triangle)) best = candidate;
    return true;
}

}  // namespace cuberille::rt
