#pragma once
// Ambient occlusion by rays: how open the hemisphere above the surface seen at each pixel is,
// within a distance. An effect only ray tracing gives (a rasterizer sees one view; the geometry
// around a point is what hides its sky), so it runs beside the shadow stage on the same
// visibility buffer and BVH (render/scene_shadows.h), as a screen-space mask the shade stage
// multiplies into the ambient and environment terms (raster::Lighting::ambientVisibility), exactly
// where a material's occlusion texture goes: the same quantity, found from the scene itself.
//
// Estimator. N rays a pixel, cosine-weighted about the surface's normal, each asking whether
// anything lies within `distance`: the share that escapes estimates (1/pi) * integral of
// V(w) cos(theta) dw, the occlusion that scales a Lambertian ambient term (Zhukov, Iones and
// Kronin 1998, with a step for their attenuation function). The directions are one fixed
// low-discrepancy set — Malley's method on a golden-ratio point set: stratified in sin^2(theta)
// — turned about the normal by an angle hashed from the pixel's coordinates, so neighbours
// sample different directions (noise rather than banding), and every pixel's value is a pure
// function of its surface, its coordinates and the BVH: the same bits at any thread count.
//
// Exact where it can be: each ray's answer is the BVH's any-hit query, which is brute force's
// (rt/ray_query.h), so the mask equals one computed by testing every triangle
// (AmbientOcclusion.MatchesBruteForceRaysBitForBit).

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "rt/caster_rays.h"
#include "rt/ray.h"
#include "rt/screen_surfaces.h"

namespace cuberille::rt {

struct AmbientOcclusionOptions {
    int raysPerPixel = 0;      // --ao N; 0: no stage
    float maxDistance = 0.0f;  // --ao-distance, world units; 0: kDefaultOcclusionDistanceOfBounds
};

/// The default reach of the rays, as a share of the casters' bounding-box diagonal. AO's distance
/// is a scale choice, not a physical constant: too short and only creases darken, too long and a
/// model's whole underside goes dark under a ground plane as if it were indoors. A tenth of the
/// model's size is what model viewers' defaults amount to (three.js' SAO and Blender's Eevee AO
/// are set by hand per scene; a tenth darkens contact and concavities and leaves open faces
/// white), and it makes a render independent of the file's units.
inline constexpr float kDefaultOcclusionDistanceOfBounds = 0.1f;

struct AmbientOcclusionStats {
    int raysPerPixel = 0;     // 0: the stage did not run
    float distance = 0.0f;    // the reach used, world units
    uint64_t pixels = 0;      // pixels with a surface
    uint64_t rays = 0;
    double ms = 0.0;
};

/// The N cosine-weighted directions about +z every pixel turns about its normal.
std::vector<glm::vec3> occlusionDirections(int count);

/// The angle (radians, [0, 2 pi)) pixel (x, y) turns the directions by: a hash of its coordinates.
float occlusionTurnRadians(int x, int y);

/// The share of `directions` (turned by `turnRadians` about the normal) along which `occluded`
/// finds nothing within `distance` of the surface, each ray starting `rayOffset` off it along the
/// normal. `occluded(ray)` answers one ray: the BVH's any hit, or brute force's in the tests (bvh_bench
/// records the rays through it).
template <class Occluded>
float openShare(const Surface& surface, const std::vector<glm::vec3>& directions, float turnRadians, float distance,
                float rayOffset, Occluded&& occluded);

/// The mask: per pixel of `surfaces`, openShare() over the casters with rays of `options`; 1 where no
/// surface is seen. `rayOffset` is the shadow stage's (surfaceRayOffset).
void computeAmbientOcclusion(const ScreenSurfaces& surfaces, const CasterRays& casters, float distance, float rayOffset,
                             const AmbientOcclusionOptions& options, std::vector<float>& mask,
                             AmbientOcclusionStats& stats);

// ---- details -------------------------------------------------------------------------------

/// A unit normal's tangent frame (u, v, n), the one the directions are expressed in.
void tangentFrame(const glm::vec3& n, glm::vec3& u, glm::vec3& v);

template <class Occluded>
float openShare(const Surface& surface, const std::vector<glm::vec3>& directions, float turnRadians, float distance,
                float rayOffset, Occluded&& occluded) {
    if (directions.empty()) return 1.0f;
    glm::vec3 u, v;
    tangentFrame(surface.normal, u, v);
    const float c = std::cos(turnRadians), s = std::sin(turnRadians);
    const glm::vec3 turnedU = c * u + s * v, turnedV = c * v - s * u;
    const glm::vec3 origin = surface.position + surface.normal * rayOffset;
    int open = 0;
    for (const glm::vec3& d : directions) {
        const Ray ray{origin, d.x * turnedU + d.y * turnedV + d.z * surface.normal, 0.0f, distance};
        open += !occluded(ray);
    }
    return float(open) / float(directions.size());
}

}  // namespace cuberille::rt
