#pragma once
// Primary visibility by rays: the camera's ray through every sample position of the frame (the
// rasterizer's own sample pattern, raster/sample_pattern.h), met with the frame's draws gathered
// into one world-space mesh, answers which triangle each sample sees. The answer fills a
// raster::VisibilityBuffer, which the deferred shade stage (raster/visibility_shade.h) shades
// with the rasterizer's shading models: the ray-tracing renderer (`--renderer raytrace`).
//
// Each ray runs from the near plane to the far plane (t in [0, 1]), the clip volume's depth
// range, and its hit is the exact one of the watertight test over every triangle (rt/ray.h):
// the same answer through the BVH or the grid, at any thread count and packet size. A draw's
// culling is a property of the camera, not of the ray: every ray of a pinhole (or orthographic)
// camera sees a plane from the same side, so a culled draw's triangles that face away from the
// eye are left out of the mesh, and brute force over what remains is the reference.
//
// Where the image may differ from the rasterizer's at one sample, and why: the rasterizer snaps
// each vertex to 1/256 pixel before it tests coverage, the rays meet the unsnapped triangles in
// float. A sample within 1/256 pixel (in x or y) of a silhouette or of an edge between two
// surfaces at different depths can be given to the other side; so can a sample where two
// surfaces lie closer in depth than the two paths' roundings (coplanar overlaps). Elsewhere both
// name the same triangle, and the deferred shade gives it the same bits
// (PrimaryRays.PartFromTheDepthTestOnlyWhereSnappingDecides).

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "raster/draw.h"
#include "raster/visibility_shade.h"
#include "rt/caster_rays.h"
#include "rt/ray.h"

namespace cuberille::rt {

struct PrimaryRayCamera {
    glm::dmat4 worldFromClip{1.0};
    bool reversedDepth = false;  // the near plane is clip depth 1
    /// For the facing of culled draws: the eye (perspective), or the direction the camera looks
    /// (orthographic).
    bool orthographic = false;
    glm::vec3 eye{0.0f};
    glm::vec3 viewDirection{0.0f, 0.0f, -1.0f};
};

struct PrimaryRayStats {
    CasterAccel accel = CasterAccel::Bvh;
    size_t triangles = 0;  // in the ray-traced mesh: the traced draws' triangles, less those culled
    uint64_t rays = 0, hits = 0;
    double gatherMs = 0, buildMs = 0, traceMs = 0;
};

/// The ray through window position (x, y) (pixels, y down) of a width x height frame, from the
/// near plane (t = 0) to the far plane (t = 1), computed in double and rounded once.
Ray primaryRay(const PrimaryRayCamera& camera, double x, double y, int width, int height);

/// Fills `out`, already reset to the frame's width, height and sample count, with what each
/// sample's ray sees among the draws with traced[d] != 0 (clip-space draws whose
/// clipFromObject is the camera's clipFromWorld times their worldFromObject). `accel` builds a
/// BVH (eight-wide queries) or a uniform grid (8x8 packets) over them for this frame.
PrimaryRayStats tracePrimaryVisibility(std::span<const raster::DrawCall> draws, std::span<const uint8_t> traced,
                                       const PrimaryRayCamera& camera, CasterAccel accel, raster::VisibilityBuffer& out);

}  // namespace cuberille::rt
