#pragma once
// What the camera sees at each pixel centre, for the shadow stage: a visibility buffer (Burns
// and Hunt, 2013). The casters are drawn once through the software GPU with one sample per pixel
// at its centre (the position the shade stage evaluates), each triangle writing its own id as a
// flat colour (an alpha-tested caster through the frame's own alpha test, so its holes are seen
// through: CasterAlphaTest). A pixel's surface is then recovered on demand: the camera ray
// through its centre met with that triangle's plane, and the triangle's normal turned toward the
// camera. Drawn with
// the scene's own order, culling and depth test, so the surface found is the one the frame shades.
//
// Only the ids are stored (4 bytes a pixel), with each triangle's plane: positions and normals
// computed where they are read cost a few dozen flops, while storing them would move 24 bytes a
// pixel through memory twice.

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "raster/draw.h"
#include "raster/pipeline.h"
#include "raster/visibility_shade.h"
#include "rt/caster_alpha_test.h"
#include "rt/triangle_mesh.h"

namespace cuberille::rt {

/// A texture's copy with every texel's colour white and its alpha kept, every level: what an
/// alpha-tested range's id draw samples, so the alpha test sees the material's alpha while the
/// id colour passes through unchanged (multiplied by exactly 1).
std::shared_ptr<const raster::Texture> alphaTestTexture(const raster::Texture& texture);

/// A surface point seen at a pixel, in world space.
struct Surface {
    glm::vec3 position{0.0f};
    glm::vec3 normal{0.0f};  // unit, facing the camera
};

/// A caster triangle's plane: unit normal (zero for a degenerate triangle) and n . p on it.
struct TrianglePlane {
    glm::vec3 normal{0.0f};
    float offset = 0.0f;
};

struct ScreenSurfaces {
    int width = 0, height = 0;
    std::vector<uint32_t> triangle;      // per pixel; kNone where no caster is seen
    std::vector<TrianglePlane> planes;   // per caster triangle, computed once a frame
    glm::mat4 worldFromClip{1.0f};
    /// Every surface seen lies in the hull of these points: the view frustum cut at the farthest
    /// depth drawn (none when nothing is seen). What a shadow map has to cover.
    std::vector<glm::vec3> seenHull;

    static constexpr uint32_t kNone = ~0u;
    bool covered(size_t pixel) const { return triangle[pixel] != kNone; }

    /// The camera rays through one row's pixel centres, as homogeneous world points: the ray of
    /// pixel x runs from near = nearAtLeft + x nearPerPixel (clip-space (nx, ny, 0, 1)) to
    /// near + nearToFar (clip-space depth 1). What surfaceAt needs of a row, found once for it.
    struct CameraRow {
        size_t firstPixel = 0;
        glm::vec4 nearAtLeft{0.0f}, nearPerPixel{0.0f}, nearToFar{0.0f};
    };
    CameraRow cameraRow(int y) const;
    /// The surface at a covered pixel of the row; false where its triangle is degenerate or seen
    /// exactly edge-on (no point to shade: the pixel is left unshadowed).
    bool surfaceAt(const CameraRow& row, int x, Surface& out) const;
    bool surfaceAt(int x, int y, Surface& out) const { return surfaceAt(cameraRow(y), x, out); }
    /// Starts reading the plane of the triangle seen at `pixel`. A scan's triangles are nearly as
    /// many as the pixels they cover, so each pixel's plane is a cache miss in a table of
    /// megabytes; a row's readers ask for the plane kPlanePrefetchPixels ahead of the one they
    /// use, so the misses overlap instead of stalling one after another.
    void prefetchPlane(size_t pixel) const {
        const uint32_t t = triangle[pixel];
        if (t != kNone) __builtin_prefetch(&planes[t]);
    }
    /// Calls f(x, pixel, surface) for each pixel of row y with a surface to shade (surfaceAt), the
    /// planes asked for kPlanePrefetchPixels ahead: the loop every reader of the buffer runs.
    template <class F>
    void forEachSurfaceInRow(int y, F&& f) const {
        const CameraRow row = cameraRow(y);
        for (int x = 0; x < width; ++x) {
            const size_t i = row.firstPixel + size_t(x);
            if (x + kPlanePrefetchPixels < width) prefetchPlane(i + kPlanePrefetchPixels);
            Surface surface;
            if (covered(i) && surfaceAt(row, x, surface)) f(x, i, surface);
        }
    }
    /// Far enough ahead to cover a miss to memory (a few hundred cycles) at the few dozen cycles a
    /// pixel takes; measured on the dragon, 8 to 32 pixels ahead made no difference.
    static constexpr int kPlanePrefetchPixels = 16;
};

// The plane (n, -d) meets the segment between the homogeneous points near and far where its
// homogeneous distances there, a and c, cancel: at a far - c near. One division takes that point
// to the world, where carrying both ends there and then finding the crossing would take three.
// Its w is zero exactly when the crossing is at infinity (the ray runs along the plane) or the
// plane is degenerate (n = 0, so a = c = 0); the ray runs with the normal when w < 0 (near and
// far have w of one sign, in front of the camera).
inline bool ScreenSurfaces::surfaceAt(const CameraRow& row, int x, Surface& out) const {
    const TrianglePlane& plane = planes[triangle[row.firstPixel + size_t(x)]];
    const glm::vec4 near = row.nearAtLeft + float(x) * row.nearPerPixel, far = near + row.nearToFar;
    const glm::vec4 homogeneousPlane(plane.normal, -plane.offset);
    const float a = glm::dot(homogeneousPlane, near), c = glm::dot(homogeneousPlane, far);
    const glm::vec4 crossing = a * far - c * near;
    if (crossing.w == 0.0f) return false;
    out.position = glm::vec3(crossing) * (1.0f / crossing.w);
    out.normal = crossing.w < 0.0f ? -plane.normal : plane.normal;
    return true;
}

/// Visibility buffers of one set of casters, frame after frame. What depends on the casters alone
/// — each triangle's plane and its id as a flat colour, the indices rebased to each range's first
/// vertex — is made once per pose (setCasters), not once per frame, and the per-pixel storage is
/// reused: a static scene seen from a moving camera pays for the draw and the ids alone.
class VisibilityBuffer {
public:
    /// The casters of the frames to come. They must stay alive until the next call, moved only
    /// as moveCasters() is told.
    void setCasters(const TriangleMeshView& casters, std::span<const CasterRange> ranges);
    /// A new pose of the same casters (same indices and ranges, moved positions): only the
    /// planes are found again.
    void moveCasters(const TriangleMeshView& casters);

    /// Draws this frame's visibility buffer with `gpu`, whose render targets are reused from frame
    /// to frame. The surfaces are valid until the next draw() or setCasters().
    const ScreenSurfaces& draw(const glm::mat4& clipFromWorld, int width, int height, raster::Pipeline& gpu);

    /// The last draw()'s pixels as the deferred shade stage reads them (raster/visibility_shade.h):
    /// each pixel's caster triangle named by its range and its index within the range — the draw
    /// and triangle of a frame that records one draw per range, in the ranges' order, over the
    /// same triangles. One sample a pixel, at its centre.
    void seenByRange(raster::VisibilityBuffer& out) const;

private:
    /// An alpha-tested range drawn through the Unlit shade stage, its triangles unindexed so each
    /// vertex carries its triangle's id as a colour (interpolating three equal values, rounded
    /// back when read).
    struct MaskedRange {
        size_t range = 0;
        std::vector<glm::vec3> positions, ids;
        std::vector<float> alphas;
        std::vector<glm::vec2> texCoords;
    };
    void expandMaskedPositions();
    raster::DrawCall maskedDraw(const MaskedRange& m, const glm::mat4& clipFromWorld) const;

    TriangleMeshView casters_;
    std::vector<CasterRange> ranges_;
    std::vector<MaskedRange> masked_;
    std::vector<uint32_t> rangeIndices_;  // the casters' indices, rebased to each range's first vertex
    std::vector<glm::vec4> idColors_;     // per triangle, its id as ConstantColor draws it
    ScreenSurfaces surfaces_;             // planes set per pose, the rest per frame
};

/// The surfaces a visibility buffer of one sample a pixel names, found by something other than
/// drawing the casters: the camera rays of the ray-tracing renderer through pixel centres
/// (rt/primary_rays.h), so its shadows and occlusion start from what its rays saw instead of from
/// a second, rasterized look at the scene. `draws` are what the buffer indexes; each covered pixel
/// gets a plane entry of its own (triangle[pixel] = pixel), the plane of the triangle it sees in
/// world space, computed as moveCasters computes a caster's: where a draw's positions are world
/// space (worldFromObject the identity, as scene::Scene draws), the same bits as that caster's
/// plane. `clipFromWorld`: the camera in the standard depth convention, as draw() takes it.
void surfacesFromVisibility(const raster::VisibilityBuffer& centres, std::span<const raster::DrawCall> draws,
                            const glm::mat4& clipFromWorld, ScreenSurfaces& out);

/// The one-sample buffer surfacesFromVisibility takes, from a multisampled one where it can be:
/// a pixel all of whose samples see one triangle (or nothing) gets it at its centre, and the
/// pixels whose samples part are listed in `open` (in row order) for a ray through the centre.
/// A triangle every sample sees contains the centre: the standard patterns' samples surround it
/// and a triangle's image is convex. It is the centre's surface unless a nearer triangle lies
/// wholly between the samples; then the receiver is still a surface the pixel shows.
void centresWhereSamplesAgree(const raster::VisibilityBuffer& samples, raster::VisibilityBuffer& centres,
                              std::vector<uint32_t>& open);

/// One visibility buffer, drawn with `gpu` (a VisibilityBuffer used once).
ScreenSurfaces findScreenSurfaces(const TriangleMeshView& casters, std::span<const CasterRange> ranges,
                                  const glm::mat4& clipFromWorld, int width, int height, raster::Pipeline& gpu);

}  // namespace cuberille::rt
