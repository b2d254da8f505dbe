#pragma once
// Clip stage: homogeneous clipping against near and far, and against the guard band for x
// and y. Triangles inside the guard band are never cut (the scissor and the fill rule handle
// the viewport edges exactly); only those that leave it are clipped, which is what bounds the
// window coordinates for the integer set-up (raster/limits.h).
//
// Consumes clip-space vertices with their varyings; produces a convex polygon (as a fan, in a
// fixed order) whose vertices interpolate the varyings linearly in clip space.

#include <array>
#include <cstdint>

#include <glm/glm.hpp>

#include "raster/limits.h"

namespace cuberille::raster {

struct ClipVertex {
    glm::vec4 position;  // clip space
    std::array<float, kMaxVaryings> varyings;
};

/// Smallest w a vertex may keep (ClipVolume::kMinWPlane is w >= kMinClipW): keeps 1/w finite
/// for any projection, including odd ones where z >= 0 does not imply w > 0.
inline constexpr float kMinClipW = 1e-20f;

/// The clip volume of one viewport, as planes dot(plane, p) >= 0 in clip space.
struct ClipVolume {
    static constexpr int kPlaneCount = 7;  // near, far, w > 0, left, right, top, bottom
    static constexpr int kMinWPlane = 2;   // w >= kMinClipW: its distance is taken less kMinClipW
    std::array<glm::vec4, kPlaneCount> planes;

    /// For clip-space draws into a width x height viewport.
    static ClipVolume forViewport(int widthPixels, int heightPixels);
    /// For window-space draws (w = 1): the guard band around [0, width) x [0, height).
    static ClipVolume forWindowSpace(int widthPixels, int heightPixels);
};

enum class ClipOutcome : uint8_t {
    Inside,    // no plane cuts it: use the triangle as it is
    Rejected,  // wholly outside one plane
    Clipped,   // cut: use the polygon
};

/// Up to 3 + one vertex per plane.
inline constexpr int kMaxClippedVertices = 3 + ClipVolume::kPlaneCount;

struct ClippedPolygon {
    int count = 0;
    std::array<ClipVertex, kMaxClippedVertices> vertices;
};

/// Bit k set when the vertex is outside plane k.
uint32_t outcode(const ClipVolume& volume, const glm::vec4& position);

ClipOutcome classifyTriangle(uint32_t code0, uint32_t code1, uint32_t code2);

/// Sutherland-Hodgman against the planes the triangle crosses. An edge's intersection is
/// always computed from its inside endpoint, so two triangles sharing a clipped edge get the
/// same new vertex bit for bit (watertightness survives clipping).
void clipTriangle(const ClipVolume& volume, uint32_t crossedPlanes, const ClipVertex& v0,
                  const ClipVertex& v1, const ClipVertex& v2, int varyingCount,
                  ClippedPolygon& out);

}  // namespace cuberille::raster
