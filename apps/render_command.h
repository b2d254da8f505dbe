#pragma once
// `cuberille render`: one frame of a scene (a `.tri` file or a built-in scene) to an image.
// Also the library entry point tests and benchmarks call, so they exercise the tool's path.

#include <filesystem>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "apps/image_io.h"
#include "raster/framebuffer.h"
#include "raster/resolve.h"
#include "raster/stats.h"
#include "apps/scene_culling.h"
#include "apps/scene_shadows.h"
#include "lod/voxel_scene.h"
#include "rt/shadows.h"
#include "scene/camera.h"
#include "scene/load_stats.h"

namespace cuberille::apps {

/// --texture-filter: the file's samplers, or one filter for every texture (an accuracy knob).
enum class TextureFilterOverride { File, Nearest, Bilinear, Trilinear };

enum class View { Color, Depth, Tiles, Overdraw, Lod, Visibility, ShadowPixels };

struct RenderOptions {
    std::string scene;  // a .tri, .ply, .ply.gz or .obj path, or a built-in scene name
    int width = 1280;
    int height = 720;
    int msaa = 1;
    int threads = 0;  // 0 = all cores
    View view = View::Color;
    float detail = 1.0f;  // tessellation scale of built-in scenes
    float azimuth = 30.0f;    // degrees, for mesh files (which carry no camera)
    float elevation = 20.0f;  // degrees
    int cameraIndex = -1;     // a camera of the file (glTF), instead of framing the model
    std::optional<scene::CameraPlacement> placement;  // --eye, --target, --up, --fov: a camera placed by hand
    bool zUp = false;         // --up-axis z: mesh files whose up is +z are turned to +y on load
    float timeSeconds = 0.0f; // glTF animation time
    std::string animation;    // --animation NAME|INDEX: the glTF animation posed; empty: the first
    float zoom = 1.0f;        // --zoom F: the view magnified F times (the field of view narrowed)
    int turntable = 0;        // > 0: that many frames around the scene, OUT_000.ext ...
    int animate = 0;          // glTF, > 0: that many frames of the animation from --time, OUT_000.ext ...
    float fps = 30.0f;        // --animate: frames a second of animation time
    bool frustumCull = false; // 3D scenes: cull triangles against the frustum through a BVH
    rt::BvhUpdateMethod bvhUpdate = rt::BvhUpdateMethod::Refit;  // --animate: how BVHs follow each pose
    int supersample = 1;      // N: render N x N times the pixels and box-filter down (N² samples on a grid)
    TextureFilterOverride textureFilter = TextureFilterOverride::File;
    raster::DepthConvention depth = raster::DepthConvention::Standard;  // --depth standard|reversed
    float pixelError = 1.0f;  // voxel models: largest projected voxel in pixels (0: finest level)
    uint32_t voxelResolution = 0; // voxel models: render at most at this resolution (0: the model's)
    bool noHybrid = false;    // voxel models: never draw source triangles
    bool noOcclusion = false; // voxel models: no occlusion culling
    int warmup = 2;           // voxel models: frames drawn first so occlusion culling converges
    bool debugCamera = false; // voxel models: show the frame's selection from behind and above
    rt::ShadowOptions shadows; // --shadows, --soft, --light-radius, --shadow-map-size, --soft-samples
    std::filesystem::path out;
    std::filesystem::path statsPath;
    bool quiet = false;
    /// --background R,G,B[,A]: display (sRGB) values and opacity in [0, 1], instead of the
    /// scene's own; an opacity below 1 writes the image's alpha (PNG with alpha, EXR).
    std::optional<glm::vec4> background;
    int pngBits = 8;  // --png-bits 8|16
};

/// The framebuffer's clear colour for a --background: linear and premultiplied by its opacity.
glm::vec4 clearColorFor(const glm::vec4& displayBackground);

/// How a render's images are written: alpha when the background is not opaque, --png-bits.
ImageWriteOptions imageWriteOptions(const RenderOptions& o);

/// The depth view's greys in an 8-bit file: the nearest covered pixel this display value, the
/// farthest this one, evenly spaced between (a 1920x1080 view of a deep scene uses every code
/// between), uncovered pixels black. EXR keeps the distances themselves.
inline constexpr double kNearestGrey = 1.0, kFarthestGrey = 0.15;

/// The depth view's distances (resolveViewDistance) as greys an 8-bit file can show.
raster::Image legibleDepth(const raster::Image& distances);

/// R,G,B or R,G,B,A, each in [0, 1]; throws scene::InputError naming the option.
glm::vec4 parseBackground(const std::string& text);

struct RenderResult {
    raster::Image image;
    raster::PipelineStats stats;
    size_t sceneTriangles = 0;
    int threadsRan = 0;  // the most threads that ran one parallel step (raster::threadsThatRan)
    double loadMs = 0;
    scene::LoadStats load;
    std::optional<lod::VoxelFrameStats> voxel;  // voxel models only
    uint32_t voxelResolution = 0;               // voxel models: the finest level's
    std::optional<ShadowFrameStats> shadows;    // when a shadow mode was asked for
    std::optional<FrustumCullStats> culling;    // with --frustum-cull
};

View parseView(const std::string& name);  // throws scene::InputError
/// "X,Y,Z" (three finite numbers) as a vector; throws scene::InputError naming the option.
glm::vec3 parseVector3(const std::string& text, const std::string& option);
TextureFilterOverride parseTextureFilter(const std::string& name);  // throws scene::InputError
const char* textureFilterName(TextureFilterOverride filter);
raster::DepthConvention parseDepthConvention(const std::string& name);  // throws scene::InputError
rt::BvhUpdateMethod parseBvhUpdate(const std::string& name);             // throws scene::InputError
/// The frame options every rendering command takes (--width, --height, --msaa, --threads);
/// throws scene::InputError naming the option.
void validateFrameOptions(int width, int height, int msaa, int threads);
/// Loads the scene and renders it; throws scene::InputError for bad input.
RenderResult renderScene(const RenderOptions& options);

nlohmann::json statsToJson(const RenderOptions& options, const RenderResult& result);

/// The whole subcommand: render, write the image and stats, print a summary. Returns the
/// exit code.
int runRenderCommand(const RenderOptions& options);

}  // namespace cuberille::apps
