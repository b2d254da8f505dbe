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
// culling is the rasterizer's: a hit on a culled side does not count. Every ray of a pinhole (or
// orthographic) camera sees a plane from the same side, so culling is decided once per triangle
// and view, by one test (the side of its plane the eye lies on): the grid, rebuilt for every frame
// anyway, is built over the triangles that remain; the BVH holds every triangle and its traversal
// skips the view's culled ones (HitFilter), so one tree serves every view and follows an
// animation's poses (PrimaryRayHierarchy). An alpha-tested draw's hit counts only where its
// material's alpha passes the cutoff, tested as the rasterizer tests it: once a pixel, at its
// centre (so every sample of a pixel on the triangle passes or fails together), the base colour
// texture sampled at the level of detail the rasterizer takes there, its derivatives from the
// rays through the next pixels met with the triangle's plane. Both
// structures then answer as brute force over what remains, with the same tie rule (ids keep
// their order), so their images are the same bits.
//
// Where the image may differ from the rasterizer's at one sample, and why: the rasterizer snaps
// each vertex to 1/256 pixel before it tests coverage, the rays meet the unsnapped triangles in
// float. A sample within 1/256 pixel (in x or y) of a silhouette or of an edge between two
// surfaces at different depths can be given to the other side; so can a sample where two
// surfaces lie closer in depth than the two paths' roundings (coplanar overlaps). Elsewhere both
// name the same triangle, and the deferred shade gives it the same bits
// (PrimaryRays.PartFromTheDepthTestOnlyWhereSnappingDecides).

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "raster/draw.h"
#include "raster/visibility_shade.h"
#include "rt/caster_rays.h"
#include "rt/deforming_bvh.h"
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

/// The traced draws as one world-space mesh, each triangle with its draw's culling.
struct TracedMesh {
    std::vector<glm::vec3> positions;
    std::vector<uint32_t> indices;
    std::vector<uint32_t> draw, triangle;  // per mesh triangle: its draw and its index there
    std::vector<raster::CullMode> cull;    // per mesh triangle
    std::vector<uint8_t> alphaTested;      // per mesh triangle: its draw is alpha-tested (AlphaMode::Mask)

    TriangleMeshView view() const { return {positions, indices}; }
};

/// A BVH over the traced draws kept from frame to frame, the way the shadow stage keeps its own:
/// built once, reused by every view of the same geometry (a turntable, a batch of views), and
/// made to follow each new pose of an animation by refitting, lazily updating or rebuilding
/// (`--bvh-update`, rt/deforming_bvh.h), so the seeds' answers to animation can be compared on
/// the camera rays too.
class PrimaryRayHierarchy {
public:
    PrimaryRayHierarchy(std::span<const raster::DrawCall> draws, std::span<const uint8_t> traced, BvhUpdateMethod method);

    /// Whether `draws` are the ones it was built over: as many vertices, the same triangles (index
    /// lists compared by content), transforms and culling. Their vertices may have moved (a new
    /// pose, or the same one in new arrays): update() brings the tree to them.
    bool sameDraws(std::span<const raster::DrawCall> draws, std::span<const uint8_t> traced) const;
    /// Whether the draws' vertex arrays are the ones last gathered (where they lie): with the pose
    /// unchanged, the tree is current.
    bool sameVertexArrays(std::span<const raster::DrawCall> draws) const;
    /// The draws' vertices moved (the same draws, a new pose): gathered again, the tree follows.
    BvhUpdateReport update(std::span<const raster::DrawCall> draws);
    /// One frame's camera rays through the kept tree (the draws it was built over, sameDraws, for
    /// their materials' alpha); buildMs is the build or update since the last trace (0 when the
    /// tree was reused as it was).
    PrimaryRayStats trace(std::span<const raster::DrawCall> draws, const PrimaryRayCamera& camera, raster::VisibilityBuffer& out);
    /// trace() through the centres of the listed pixels (y x width + x) only, into a one-sample
    /// buffer whose other pixels are left as they are: the pixels the shadow stage's receivers
    /// still need after the frame's own samples (rt::centresWhereSamplesAgree). Call after trace()
    /// with the same camera: its view's culling is reused.
    PrimaryRayStats traceCentres(std::span<const raster::DrawCall> draws, const PrimaryRayCamera& camera,
                                 std::span<const uint32_t> pixels, raster::VisibilityBuffer& out);
    /// The tree, at the pose of the last update, and the world-space mesh it is over (the traced
    /// draws' triangles in draw order): for other queries about the same triangles to share
    /// instead of building a tree of their own (the ray-traced frame's shadow stage).
    const DeformingBvh& bvh() const { return *bvh_; }
    const TracedMesh& mesh() const { return mesh_; }

private:
    struct DrawKey {
        uint32_t draw;
        size_t vertexCount;
        size_t indexCount;
        glm::mat4 worldFromObject;
        raster::CullMode cull;
        bool operator==(const DrawKey&) const = default;
    };
    static DrawKey keyOf(uint32_t draw, const raster::DrawCall& call);
    std::vector<DrawKey> keys_;
    std::vector<uint32_t> sourceIndices_;           // the traced draws' index lists, concatenated
    std::vector<const glm::vec3*> vertexArrays_;    // per traced draw, as last gathered
    TracedMesh mesh_;
    std::optional<DeformingBvh> bvh_;
    std::vector<uint8_t> filter_;  // per triangle, this view's HitFilter entry
    double pendingBuildMs_ = 0;
};

}  // namespace cuberille::rt
