#pragma once
// Inside a LoadedScene (render/loaded_scene.h): what was read, the pose it holds and what is kept
// between frames. Only render/ includes this; it is not installed.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "lod/voxel_scene.h"
#include "render/frame_settings.h"
#include "render/loaded_scene.h"
#include "render/scene_culling.h"
#include "render/scene_shadows.h"
#include "render/voxel_ray_frame.h"
#include "rt/primary_rays.h"
#include "scene/environment_map.h"
#include "scene/gltf_loader.h"
#include "scene/scene.h"
#include "scene/tri_scene.h"

namespace cuberille::render {

struct LoadedScene::State {
    std::string name;
    SceneOptions options;
    scene::WarningSink warn;
    scene::FileKind kind = scene::FileKind::Unknown;
    bool procedural = false;
    double loadMs = 0.0;

    scene::TriScene tri;                       // a .tri file
    std::unique_ptr<lod::VoxelScene> voxel;    // a .cvox model
    std::unique_ptr<VoxelRayScene> voxelRays;  // its --renderer raytrace level and tree, kept

    // A 3D scene: the meshes at the pose held; camera and lighting are set per frame.
    std::optional<scene::GltfDocument> gltf;
    scene::Scene posed;
    bool hasPose = false;          // glTF: whether `posed` holds a pose yet (posed on first use)
    float poseTimeSeconds = 0.0f;  // glTF: the pose held
    std::string poseAnimation;
    std::vector<scene::Camera> fileCameras;
    std::vector<raster::Light> fileLights;
    scene::Bounds bounds;
    scene::Camera ownCamera;       // a built-in scene's own camera and lighting
    raster::Lighting ownLighting;
    std::shared_ptr<const raster::EnvironmentLight> environment;  // the frame's --environment, or null
    bool groundHeld = false;       // posed.meshes ends with the --ground floor for the pose held
    bool groundAsked = false;      // what the last frame asked (the hierarchies were built for it)

    // Kept between frames while the settings that shaped them hold (render/loaded_scene.h).
    std::optional<SceneShadows> shadows;
    rt::ShadowOptions shadowsOptions;
    rt::AmbientOcclusionOptions occlusionOptions;
    rt::BvhUpdateMethod shadowsMethod = rt::BvhUpdateMethod::Refit;
    rt::CasterAccel shadowsAccel = rt::CasterAccel::Bvh;
    bool shadowsShareCameraRays = false;  // built to take the camera rays' tree (SceneShadows)
    bool shadowsPoseStale = false;  // the pose changed since they were built or updated
    std::optional<SceneFrustumCull> culling;
    rt::BvhUpdateMethod cullingMethod = rt::BvhUpdateMethod::Refit;
    bool cullingPoseStale = false;
    /// --renderer raytrace --accel bvh: the camera rays' tree over the traced draws, kept while
    /// they are the same draws (rt::PrimaryRayHierarchy::sameDraws) and brought to each new pose.
    std::optional<rt::PrimaryRayHierarchy> primaryRays;
    rt::BvhUpdateMethod primaryRaysMethod = rt::BvhUpdateMethod::Refit;
    bool primaryRaysPoseStale = false;
    /// --renderer raytrace with shadows or --ao: the surfaces its camera rays met at pixel
    /// centres, handed to the shadow stage (storage reused from frame to frame).
    rt::ScreenSurfaces tracedSurfaces;
    /// The software GPU of the deferred frames (the ray-traced renderer's, and raster frames that
    /// shade the shadow stage's visibility buffer): kept, so each frame reuses the framebuffer and
    /// the shade stage's tables and vertex outputs of the one before instead of faulting in fresh
    /// memory (raster::VisibilityShadeStorage).
    raster::Pipeline deferredFrames;

    /// A 3D scene at the frame's pose (glTF: its animation and time; posed again only when they
    /// differ from the pose held). Returns the milliseconds spent posing.
    double poseFor(const FrameSettings& f);
    /// The frame's camera and lights on `posed` (render/renderer.cpp applies zoom and orbit),
    /// with the frame's environment (environmentFor).
    void frameFor(const FrameSettings& f);
    /// --environment: the environment lights the scene instead of its ambient term, and instead
    /// of the default key light of a model without lights of its own (docs/conventions.md).
    void environmentFor(const FrameSettings& f);
    /// The --ground floor added to or taken from `posed` as the frame asks, after frameFor (the
    /// framing is the model's); the shadow and cull hierarchies are rebuilt when it comes or goes.
    void groundFor(const FrameSettings& f);
    /// The shadow stage and frustum cull for this frame, built or brought to the pose held.
    SceneShadows* shadowsFor(const FrameSettings& f);
    SceneFrustumCull* cullingFor(const FrameSettings& f);
};

struct SceneAccess {
    static LoadedScene::State& state(const LoadedScene& s) { return *s.state_; }
};

}  // namespace cuberille::render
