#pragma once
// `render MODEL.cvox --renderer raytrace`: a voxel model's frame by camera rays through one level's
// voxels (Chajdas 2015, chapter 5), shaded as the rasterizer shades voxel faces.
//
//   gather   the level's voxels into 16-bit grid coordinates (kept with the tree between frames)
//   build    the --accel tree over them: bvh, kdtree or octree (rt/voxel_trees.h), or bvh8
//            (rt/wide_voxel_bvh.h)
//   trace    a ray per sample of the rasterizer's pattern, near plane to far plane, in grid units;
//            each hit is a voxel and the face the ray enters it by
//   light    with --shadows raytraced and --ao: at each pixel centre's face, rays toward the
//            light (N x N toward its disk with --soft) and cosine-distributed about the face
//            through the same tree, into the masks the shade stage multiplies in
//   shade    each face seen becomes the quad the rasterizer would draw for it (its corners, the
//            voxel's normal and colour), and the deferred shade stage (raster/visibility_shade.h)
//            shades the samples that see it with the voxel draws' Lambert lighting, writing depth
//
// What differs from the rasterized frame, and why: the ray tracer sees one level of solid cubes
// (the chapter's setting: no level-of-detail in the traversal, so --voxel-resolution picks the
// level, the finest by default), where the rasterizer draws the blocks its selection picks, each
// voxel's camera-facing *active* faces only (a face is active where the surface faces its way,
// section 3.1.1), and source triangles near the camera. Where the rasterizer draws the same level
// without triangles (--pixel-error 0 --no-hybrid), the two name the same face except where a
// ray meets a face that is not active (the rasterizer shows what lies behind it) and, as for
// triangles, within 1/256 pixel of an edge (VoxelRayFrame tests measure both).
// A ray that starts inside a voxel (the near plane cuts the model) enters no face; its sample
// shows the background and is counted.
//
// Shadow and occlusion rays leave from the face's own plane (the hit rule needs no offset,
// rt/voxel_rays.h) and count only voxels past the few around the one they leave
// (kUnshadowingNeighbourhoodVoxels): its smooth normal, which lights it, may face the light where
// the face the camera sees and the steps beside it do not, a pattern of dark steps no surface
// has. Occlusion rays spread about the face's normal: the open hemisphere above a face.

#include <cstdint>
#include <memory>
#include <optional>
#include <variant>
#include <vector>

#include "raster/draw.h"
#include "raster/pipeline.h"
#include "rt/voxel_trees.h"
#include "rt/wide_voxel_bvh.h"
#include "scene/camera.h"
#include "voxel/voxel_model.h"

namespace cuberille::render {

/// Shadow and occlusion rays start where they leave the cube of voxels this many around the one
/// they leave from. A voxel surface is a staircase, and a ray toward a light low over it meets the
/// steps beside it: dark speckles wherever the smooth normal faces the light but a neighbour stands
/// between. Measured on the bunny at 512³ (1280x720 halved, the default light): with only the
/// voxel itself left out, 8.2% of the covered pixels are shadowed; with its 26 neighbours, 3.1%;
/// with two voxels each way, 1.6%, which is what the ears and head really shade. The price is
/// contact shadow nearer than two voxels, a fraction of a pixel at the framing's resolution.
constexpr int kUnshadowingNeighbourhoodVoxels = 2;

/// The ray-traced effects a voxel frame may ask for (the command line's --shadows raytraced,
/// --soft, --light-radius, --soft-samples, --ao, --ao-distance).
struct VoxelRayEffects {
    bool shadows = false;
    bool soft = false;
    float lightRadius = 0.05f;   // tangent of the directional light's angular radius
    int softSamplesPerSide = 4;  // N x N rays a pixel
    int occlusionRays = 0;       // a pixel; 0: none
    float occlusionDistance = 0; // model units; 0: a tenth of the model's diagonal
};

struct VoxelRayFrameStats {
    rt::VoxelStructure structure = rt::VoxelStructure::Bvh;
    uint32_t level = 0, resolution = 0;  // the level traced and its grid's resolution
    uint64_t voxels = 0;
    uint64_t rays = 0, hits = 0, samplesInside = 0;  // samplesInside: rays starting inside a voxel
    uint64_t facesSeen = 0;
    rt::VoxelTraversalCounters counters;  // camera rays
    uint64_t shadowRays = 0, occlusionRays = 0;
    float occlusionDistance = 0;  // model units
    double gatherMs = 0, buildMs = 0, traceMs = 0, lightMs = 0, shadeMs = 0;  // gather and build: 0 when kept
};

/// One level of a voxel model and a tree over it, kept between frames while both hold.
class VoxelRayScene {
public:
    VoxelRayScene(const voxel::VoxelModel& model, uint32_t level, rt::VoxelStructure structure);
    uint32_t level() const { return level_; }
    rt::VoxelStructure structure() const { return structure_; }

    /// Traces and shades one frame into `pipeline`, begun with beginDeferredFrame (its size and
    /// sample count): the face quads are recorded as its one draw, then shaded. `camera` frames
    /// the model in model units, lit by `lighting`.
    VoxelRayFrameStats drawFrame(raster::Pipeline& pipeline, const scene::Camera& camera, const raster::Lighting& lighting,
                                 int width, int height, int samples, const VoxelRayEffects& effects = {});

private:
    rt::VoxelHit trace(const rt::VoxelRay& ray, const rt::VoxelTraversal& how, rt::VoxelTraversalCounters* counters) const;
    /// Whether anything but `voxel` lies on the ray (grid units): shadow and occlusion rays.
    bool occluded(rt::Ray ray, uint32_t voxel) const;
    /// The shadow and occlusion masks from each pixel centre's face (`centre`: voxel and face key
    /// per pixel, or none), into lighting's visibility pointers.
    void lightFaces(const std::vector<uint64_t>& centre, const std::vector<glm::vec3>& centrePoint, int width, int height,
                    const VoxelRayEffects& effects, raster::Lighting& lighting, VoxelRayFrameStats& stats);

    uint32_t level_;
    rt::VoxelStructure structure_;
    glm::dvec3 origin_{0.0};  // model units: the grid's corner
    double voxelSize_ = 1.0;  // model units at this level
    uint32_t resolution_ = 0;
    uint32_t blockSize_ = voxel::kBlockSize;
    std::vector<rt::VoxelCoord> coords_;
    std::vector<uint32_t> normals_, colors_;  // per voxel, packed as in the .cvox
    std::optional<glm::vec3> uncoloured_;     // a model without colours: the albedo lod::VoxelScene gives it
    std::variant<std::monostate, rt::VoxelBvh, rt::VoxelKdTree, rt::VoxelOctree, rt::WideVoxelBvh> tree_;
    double gatherMs_ = 0, buildMs_ = 0;
    bool reported_ = false;  // gather and build times go to the first frame's stats only
    // The last frame's face quads: the recorded draw points into them until endFrame.
    std::vector<glm::vec3> positions_, normals3_, colors3_;
    std::vector<uint32_t> indices_;
    std::vector<float> shadowMask_, occlusionMask_;  // per pixel; the draw's lighting points at them
    glm::vec3 boundsLo_{0.0f}, boundsHi_{0.0f};      // grid units, of the level's voxels
};

}  // namespace cuberille::render
