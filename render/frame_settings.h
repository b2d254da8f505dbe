#pragma once
// What one frame asks of the renderer: its size and samples, the camera, the animation time, the
// shadows, the view and the accuracy knobs. The command line's `render` options are these plus
// what the tool does with files (apps/render_command.h); the Python module's keyword arguments
// are these by the same names (python/).
//
// The parse functions turn the command line's words into these values and throw
// scene::InputError with the message the tool prints, naming the option.

#include <cstdint>
#include <optional>
#include <string>

#include <glm/glm.hpp>

#include "raster/framebuffer.h"
#include "rt/ambient_occlusion.h"
#include "rt/caster_rays.h"
#include "rt/deforming_bvh.h"
#include "rt/shadows.h"
#include "rt/voxel_trees.h"
#include "scene/camera.h"

namespace cuberille::render {

/// --texture-filter: the file's samplers, or one filter for every texture (an accuracy knob).
enum class TextureFilterOverride { File, Nearest, Bilinear, Trilinear };

/// What the image shows: the shaded frame, or one of the pipeline's internals made visible.
enum class View { Color, Depth, Normals, Tiles, Overdraw, Lod, Visibility, ShadowPixels };

/// What finds the surface each sample sees: the rasterizer's depth test, or a ray per sample
/// (rt/primary_rays.h) whose answer the deferred shade stage shades with the same models
/// (raster/visibility_shade.h). Everything after visibility — shading, shadows, occlusion — is
/// the same stage either way.
enum class Renderer { Raster, Raytrace };

/// How a scene is read, fixed for as long as it stays loaded (render/loaded_scene.h).
struct SceneOptions {
    float detail = 1.0f;  // tessellation scale of built-in scenes, (0, 16]
    bool zUp = false;     // --up-axis z: mesh files whose up is +z are turned to +y on load
};

/// Where a shadowed raster frame's visibility comes from. At one sample (standard depth, the
/// colour or shadow-pixels view, no frustum cull) the shadow stage's visibility buffer names, at
/// every pixel, the triangle the frame's depth test would keep, so the frame may shade that buffer
/// (Pipeline::shadeVisible) instead of rasterizing the scene again: the same image bit for bit,
/// one pass over the geometry fewer, but a per-pixel cost the forward path's block lanes do not
/// pay (render/renderer.cpp, kTrianglesPerPixelToShadeShadowVisibility). --frame-visibility.
enum class FrameVisibility {
    Auto,         // the shadow stage's buffer where it serves and the scene is dense enough to pay
    ShadowStage,  // the shadow stage's buffer wherever it serves
    DepthTest,    // always drawn forward
};

struct FrameSettings {
    int width = 1280;
    int height = 720;
    int msaa = 1;
    int threads = 0;  // 0 = all cores
    View view = View::Color;
    float azimuth = 30.0f;    // degrees, for mesh files (which carry no camera)
    float elevation = 20.0f;  // degrees
    int cameraIndex = -1;     // a camera of the file (glTF), instead of framing the model
    std::optional<scene::CameraPlacement> placement;  // --eye, --target, --up, --fov: a camera placed by hand
    /// The camera turned this far about the world's up axis through its target, after every
    /// other choice (a turntable's frames); the light stays where the unturned camera put it.
    float orbitDegrees = 0.0f;
    float timeSeconds = 0.0f; // glTF animation time
    std::string animation;    // --animation NAME|INDEX: the glTF animation posed; empty: the first
    float zoom = 1.0f;        // --zoom F: the view magnified F times (the field of view narrowed)
    /// --orthographic: parallel projection, the target's plane shown at the size the perspective
    /// camera shows it (scene::orthographicView); --zoom then narrows the half height.
    bool orthographic = false;
    bool frustumCull = false; // 3D scenes: cull triangles against the frustum through a BVH
    /// --ground: model files stand on a floor (render/loaded_scene.cpp, groundUnder) that
    /// receives their shadows; the framing is the model's alone, and a model without lights of
    /// its own is lit from beside the camera (scene::ModelSceneOptions::keyLightBesideCamera).
    bool ground = false;
    /// --shadow-catcher: with --ground and --shadows, the floor shows the background wherever it
    /// is lit and only darkens it where a shadow falls (render/loaded_scene.cpp, catcherAlbedo),
    /// so the model and its shadow sit on the page as a product shot's do.
    bool shadowCatcher = false;
    rt::BvhUpdateMethod bvhUpdate = rt::BvhUpdateMethod::Refit;  // how BVHs follow a new pose
    /// --accel: what answers the shadow stage's rays (shadows, ambient occlusion): the BVH, or a
    /// uniform grid rebuilt for every pose (rt/caster_rays.h). The same images either way.
    rt::CasterAccel accel = rt::CasterAccel::Bvh;
    /// --accel for a voxel model's camera rays (--renderer raytrace): a BVH, a kD tree or an
    /// octree over the traced level's voxels (rt/voxel_trees.h). The same images from each.
    rt::VoxelStructure voxelAccel = rt::VoxelStructure::Bvh;
    /// --renderer: raster (the default) or raytrace (3D scenes: camera rays through --accel's
    /// structure, built for the frame, decide visibility).
    Renderer renderer = Renderer::Raster;
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
    /// How a raster frame whose shadow stage drew its own visibility buffer (--shadows, --ao)
    /// finds what each sample shows (docs/ray_tracing.md, "The frame shades what the buffer saw").
    FrameVisibility frameVisibility = FrameVisibility::Auto;
    /// --ao N, --ao-distance D: ambient occlusion by N rays a pixel (rt/ambient_occlusion.h).
    rt::AmbientOcclusionOptions ambientOcclusion;
    /// --environment neutral|FILE: image-based lighting from the built-in studio or an
    /// equirectangular radiance map (scene/environment_map.h); empty: none. It replaces the
    /// ambient term, and the default key light of a model without lights of its own.
    std::string environment;
    float environmentIntensity = 1.0f;  // --environment-intensity: the environment's radiance scaled
    /// --background R,G,B[,A]: display (sRGB) values and opacity in [0, 1], instead of the
    /// scene's own; an opacity below 1 gives the image coverage alpha.
    std::optional<glm::vec4> background;
    /// The tiles, overdraw, lod and visibility views carry a legend of their colours
    /// (render/view_legend.h); --no-legend leaves it out.
    bool legend = true;
};

/// Whether a frame's image carries alpha worth keeping: a background that is not opaque.
inline bool hasAlpha(const FrameSettings& f) { return f.background && f.background->a < 1.0f; }

/// The framebuffer a frame of these settings draws into (its size, samples, depth convention and
/// the records its view needs); the clear colour is the scene's or clearColorFor(background).
raster::FramebufferDesc framebufferDesc(const FrameSettings& settings);

/// The framebuffer's clear colour for a --background: linear and premultiplied by its opacity.
glm::vec4 clearColorFor(const glm::vec4& displayBackground);

/// The frame options every rendering command takes (--width, --height, --msaa, --threads);
/// throws scene::InputError naming the option.
void validateFrameOptions(int width, int height, int msaa, int threads);

View parseView(const std::string& name);
const char* viewName(View view);
/// "X,Y,Z" (three finite numbers) as a vector; `option` names it in the message.
glm::vec3 parseVector3(const std::string& text, const std::string& option);
/// R,G,B or R,G,B,A, each in [0, 1].
glm::vec4 parseBackground(const std::string& text);
TextureFilterOverride parseTextureFilter(const std::string& name);
const char* textureFilterName(TextureFilterOverride filter);
raster::DepthConvention parseDepthConvention(const std::string& name);
rt::BvhUpdateMethod parseBvhUpdate(const std::string& name);
rt::CasterAccel parseAccel(const std::string& name);  // bvh or grid; throws scene::InputError
/// --accel NAME into both fields: bvh (either kind of scene), grid (triangle scenes; voxel models
/// refuse it when they render), kdtree, octree or bvh8 (voxel models). Throws scene::InputError.
void applyAccel(const std::string& name, FrameSettings& f);
const char* accelName(rt::CasterAccel accel);
Renderer parseRenderer(const std::string& name);  // raster or raytrace; throws scene::InputError
const char* rendererName(Renderer renderer);
FrameVisibility parseFrameVisibility(const std::string& name);  // auto, shadow-stage or depth-test; throws scene::InputError
const char* frameVisibilityName(FrameVisibility visibility);

}  // namespace cuberille::render
