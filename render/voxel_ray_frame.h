#pragma once
// `render MODEL.cvox --renderer raytrace`: a voxel model's frame by camera rays through one level's
// voxels (Chajdas 2015, chapter 5), shaded as the rasterizer shades voxel faces.
//
//   gather   the level's voxels into 16-bit grid coordinates (kept with the tree between frames)
//   build    the --accel tree over them: bvh, kdtree or octree (rt/voxel_trees.h)
//   trace    a ray per sample of the rasterizer's pattern, near plane to far plane, in grid units;
//            each hit is a voxel and the face the ray enters it by
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

#include <cstdint>
#include <memory>
#include <optional>
#include <variant>
#include <vector>

#include "raster/draw.h"
#include "raster/pipeline.h"
#include "rt/voxel_trees.h"
#include "scene/camera.h"
#include "voxel/voxel_model.h"

namespace cuberille::render {

struct VoxelRayFrameStats {
    rt::VoxelStructure structure = rt::VoxelStructure::Bvh;
    uint32_t level = 0, resolution = 0;  // the level traced and its grid's resolution
    uint64_t voxels = 0;
    uint64_t rays = 0, hits = 0, samplesInside = 0;  // samplesInside: rays starting inside a voxel
    uint64_t facesSeen = 0;
    rt::VoxelTraversalCounters counters;
    double gatherMs = 0, buildMs = 0, traceMs = 0, shadeMs = 0;  // gather and build: 0 when kept
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
                                 int width, int height, int samples);

private:
    rt::VoxelHit trace(const rt::VoxelRay& ray, rt::VoxelTraversalCounters* counters) const;

    uint32_t level_;
    rt::VoxelStructure structure_;
    glm::dvec3 origin_{0.0};  // model units: the grid's corner
    double voxelSize_ = 1.0;  // model units at this level
    uint32_t resolution_ = 0;
    uint32_t blockSize_ = voxel::kBlockSize;
    std::vector<rt::VoxelCoord> coords_;
    std::vector<uint32_t> normals_, colors_;  // per voxel, packed as in the .cvox
    std::optional<glm::vec3> uncoloured_;     // a model without colours: the albedo lod::VoxelScene gives it
    std::variant<std::monostate, rt::VoxelBvh, rt::VoxelKdTree, rt::VoxelOctree> tree_;
    double gatherMs_ = 0, buildMs_ = 0;
    bool reported_ = false;  // gather and build times go to the first frame's stats only
    // The last frame's face quads: the recorded draw points into them until endFrame.
    std::vector<glm::vec3> positions_, normals3_, colors3_;
    std::vector<uint32_t> indices_;
};

}  // namespace cuberille::render
