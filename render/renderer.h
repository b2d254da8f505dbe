#pragma once
// The renderer as a library: a loaded scene (render/loaded_scene.h) and a frame's settings
// (render/frame_settings.h) in, an image and its statistics out. The frame's orchestration lives
// here, stage by stage as a frame runs them:
//   1. pose and frame the scene: the animation time, the camera (file, framing, placement,
//      zoom, orbit), the texture-filter and depth-convention knobs;
//   2. shadows, when asked for: masks per light from a map, rays, or both (render/scene_shadows.h);
//   3. the frustum cull, when asked for (render/scene_culling.h);
//   4. the draws through raster::Pipeline (a voxel model's after block selection, lod/), or with
//      --renderer raytrace, recorded and shaded from what camera rays see (rt/primary_rays.h);
//   5. the resolve of what the view shows.
// Supersampling renders step 1-5 at N x N the size and box-filters down.
//
// Nothing here prints or writes files: errors are exceptions (scene::InputError for what the
// caller asked, with the messages the command line prints), and the statistics are a struct.

#include <optional>
#include <string>
#include <vector>

#include "lod/voxel_scene.h"
#include "raster/resolve.h"
#include "raster/stats.h"
#include "render/frame_settings.h"
#include "render/loaded_scene.h"
#include "render/scene_culling.h"
#include "render/scene_shadows.h"
#include "render/voxel_ray_frame.h"
#include "rt/primary_rays.h"
#include "scene/load_stats.h"

namespace cuberille::render {

/// --renderer raytrace: the camera rays and the deferred shade of what they found.
struct RayTracedFrameStats {
    rt::PrimaryRayStats rays;
    raster::VisibilityShadeStats shade;
    /// --accel bvh keeps its tree across frames: whether this frame brought it to a new pose, and how
    /// (rays.buildMs holds the build or update's time; 0 when the tree was reused as it was).
    bool updated = false;
    rt::BvhUpdateReport update;
    size_t drawsTraced = 0, drawsRasterized = 0;  // see-through draws: rasterized after
};

struct RenderResult {
    /// Linear RGBA, colour premultiplied by alpha; for the depth view of a 3D scene, the distance
    /// from the eye in scene units (render/display_image.h makes it legible).
    raster::Image image;
    raster::PipelineStats stats;
    size_t sceneTriangles = 0;
    int threadsRan = 0;  // the most threads that ran one parallel step (raster::threadsThatRan)
    double loadMs = 0;   // reading and posing the scene for this frame (0 when the pose was kept)
    scene::LoadStats load;
    std::optional<lod::VoxelFrameStats> voxel;  // voxel models only
    uint32_t voxelResolution = 0;               // voxel models: the finest level's
    std::optional<ShadowFrameStats> shadows;    // when a shadow mode was asked for
    std::optional<FrustumCullStats> culling;    // with frustumCull
    std::optional<RayTracedFrameStats> rayTraced;  // with Renderer::Raytrace, 3D scenes
    /// A raster frame that shaded the shadow stage's visibility buffer instead of rasterizing its
    /// opaque draws a second time (FrameSettings::frameVisibility): what that cost.
    std::optional<raster::VisibilityShadeStats> shadedShadowStageVisibility;
    std::optional<VoxelRayFrameStats> voxelRays;   // with Renderer::Raytrace, voxel models
};

/// One frame. Throws scene::InputError for settings the scene cannot honour (an option it has no
/// use for is refused, not ignored), with the message the command line prints.
RenderResult render(const LoadedScene& scene, const FrameSettings& settings);

/// A glTF's cameras (render with FrameSettings::cameraIndex below this), at the pose last rendered
/// (at time 0 of the first animation before any); 0 for other scenes.
size_t cameraCount(const LoadedScene& scene);

/// The image an 8-bit file shows (render/display_image.h): four sRGB samples a pixel, alpha 255
/// unless the background is not opaque. Exactly the pixels `cuberille render` writes to a PNG.
std::vector<uint8_t> displayPixels(const LoadedScene& scene, const FrameSettings& settings, const RenderResult& result);
/// The image a display-referred file shows, as floats: the depth view made legible.
raster::Image displayImage(const LoadedScene& scene, const FrameSettings& settings, const RenderResult& result);

/// The frame's statistics as the JSON object `cuberille render --stats` writes; `sceneName` is
/// LoadedScene::name().
std::string statsJson(const std::string& sceneName, const FrameSettings& settings, const RenderResult& result);

}  // namespace cuberille::render
