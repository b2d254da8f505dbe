#pragma once
// The shadow stage for a 3D scene (rt/shadows.h) wired to the scene: which meshes cast and
// receive, the BVH over them, and the per-frame screen-space masks handed to the shade stage.
//
// Casters are the opaque and alpha-tested meshes (alpha-tested ones block rays and fill the maps
// only where their alpha passes: rt/caster_alpha_test.h), concatenated
// in world space in draw order, each keeping its culling so the visibility buffer sees what the
// frame shades. See-through meshes (blended or transmissive: scene::Mesh::seeThrough) neither
// cast nor take masks (scene::Scene::draw). Nothing here runs unless a mode is asked for and a
// light casts shadows: the promise that a stage a scene does not need costs nothing.

#include <list>
#include <memory>
#include <optional>
#include <unordered_map>
#include <vector>

#include "rt/ambient_occlusion.h"
#include "rt/bvh.h"
#include "rt/caster_alpha_test.h"
#include "rt/deforming_bvh.h"
#include "rt/primary_rays.h"
#include "rt/screen_surfaces.h"
#include "rt/shadows.h"
#include "scene/scene.h"

namespace cuberille::render {

struct ShadowFrameStats {
    rt::ShadowMode mode = rt::ShadowMode::None;
    bool soft = false;
    rt::MapFocus focus = rt::MapFocus::View;
    rt::ShadowStats shadows;
    size_t casterTriangles = 0;
    double bvhBuildMs = 0.0;   // once per scene, reported with the first frame that needs it
    /// The rays went through the camera rays' tree (--renderer raytrace): no tree of the stage's own.
    bool bvhShared = false;
    double adjacencyMs = 0.0;  // hybrid: the casters' edge adjacency, likewise
    // Animated scenes: how the hierarchy followed the casters to this frame's pose (update()).
    bool bvhUpdated = false;   // the casters moved since the last frame; the fields below say how
    bool bvhRebuilt = false;   // Lauterbach's criterion passed its threshold: rebuilt, not refitted
    double degradation = 0.0;  // the criterion's value after the refit (rt/bvh_refit.h)
    double bvhUpdateMs = 0.0;  // the refit or rebuild, and for hybrid the edge adjacency found again
    /// The casters gathered from the scene: once per pose (at construction, reported with the
    /// first frame, and in each update()).
    double castersMs = 0.0;
    /// The surfaces the masks start from: the visibility buffer drawn and read (with its casters'
    /// planes, the first frame of a pose that draws it), or under --renderer raytrace the
    /// surfaces taken from the camera rays (render/renderer.cpp).
    double surfacesMs = 0.0;
    /// --renderer raytrace at more than one sample: the rays traced through pixel centres for the
    /// receivers, where a pixel's samples see different triangles (rt::centresWhereSamplesAgree).
    uint64_t centreRays = 0;
    rt::AmbientOcclusionStats occlusion;  // --ao: its rays and time (in totalMs too); raysPerPixel 0: not run
    /// What answered the rays; the bvh* fields above then describe the grid (built at
    /// construction, and built again, never refitted, for every pose: bvhRebuilt).
    rt::CasterAccel accel = rt::CasterAccel::Bvh;
    double totalMs = 0.0;     // the whole stage this frame; the BVH build (at construction) is not in it
};

class SceneShadows {
public:
    /// `bvhUpdate`: how update() makes the casters' hierarchy follow each new pose
    /// (rt/deforming_bvh.h); with Lazy the shadow rays refresh the lower boxes they reach.
    /// `occlusion`: ambient occlusion by rays from the same surfaces through the same BVH, with
    /// or without shadows. `accel`: Grid answers the rays with a uniform grid built for each
    /// pose instead of the BVH (rt/caster_rays.h): the same masks, another cost.
    /// `bvhFromCameraRays`: the frames will hand run() the camera rays' tree over the same
    /// triangles (render --renderer raytrace, rt::PrimaryRayHierarchy), so none is built here.
    SceneShadows(const scene::Scene& scene, const rt::ShadowOptions& options,
                 rt::BvhUpdateMethod bvhUpdate = rt::BvhUpdateMethod::Refit,
                 const rt::AmbientOcclusionOptions& occlusion = {}, rt::CasterAccel accel = rt::CasterAccel::Bvh,
                 bool bvhFromCameraRays = false);

    /// Whether the stage runs at all: casters, and a mode other than none with a shadow-casting
    /// light, or ambient occlusion.
    bool active() const { return active_; }

    /// The next pose of an animated scene (the same meshes and triangles, moved): the casters
    /// are gathered again and their hierarchy refitted to them, or rebuilt when Lauterbach's
    /// criterion fires (rt/deforming_bvh.h), instead of built anew each frame; the next run()
    /// reports which. Throws std::runtime_error when the casters' triangles changed.
    void update(const scene::Scene& scene);

    /// One frame's masks for the scene's current camera; returns the lighting to shade with
    /// (the scene's lights, each pointing at its mask). Valid until the next call.
    raster::Lighting run(const scene::Scene& scene, int width, int height, ShadowFrameStats& stats);
    /// The same frame's masks for surfaces found by the caller instead of the stage's own
    /// visibility buffer: the ray-tracing renderer's camera rays (rt::surfacesFromVisibility).
    /// Valid until the next call; `seen` must outlive the returned lighting's use.
    /// `cameraRays`: the camera rays' tree and the mesh it is over; its rays answer the stage's
    /// when that mesh holds the casters' triangles (the traced draws are the scene's opaque and
    /// alpha-tested meshes in order: the same triangles, so the same answers, rt/caster_rays.h).
    /// Otherwise, or when null, the stage builds its own tree the first time it needs one.
    raster::Lighting run(const scene::Scene& scene, const rt::ScreenSurfaces& seen, ShadowFrameStats& stats,
                         const rt::PrimaryRayHierarchy* cameraRays = nullptr);

    /// What the last run(scene, width, height, …) saw through its own visibility buffer, as the
    /// frame's draws name it: scene::Scene::draw records the opaque and alpha-tested meshes first
    /// and in the scene's order — the casters' ranges, drawn with the same culling and alpha test —
    /// so caster triangle t of range k is triangle t - first of recorded draw k. A raster frame of
    /// one sample in the standard depth convention shades this (Pipeline::shadeVisible) instead of
    /// rasterizing the same triangles again: the depth test would keep the same triangle at every
    /// pixel, so the image is the forward frame's bit for bit (render/renderer.cpp). False, `out`
    /// untouched, when the last run drew no buffer (the stage inactive, or handed its surfaces) or
    /// `scene`'s opaque and alpha-tested meshes are not the casters' ranges triangle for triangle.
    bool seenDraws(const scene::Scene& scene, raster::VisibilityBuffer& out) const;

    /// Per pixel of the last frame: rays were traced there for some light.
    const std::vector<uint8_t>& markedPixels() const { return masks_.marked; }

private:
    void gatherCasters(const scene::Scene& scene);
    std::optional<rt::CasterAlphaTest> alphaTestOf(const scene::Mesh& mesh);
    raster::Lighting maskFor(const scene::Scene& scene, const rt::ScreenSurfaces& surfaces, ShadowFrameStats& stats,
                             const rt::DeformingBvh* shared);
    void buildBvh();
    /// The rays need a BVH that is not there yet: the stage's own, built the first time a frame
    /// needs it, unless a frame hands over the camera rays' over the same triangles.
    bool bvhPending() const { return active_ && raysNeeded_ && accel_ == rt::CasterAccel::Bvh && !bvh_; }
    bool sameTriangles(const rt::TracedMesh& mesh) const;
    void findAdjacency();

    rt::ShadowOptions options_;
    rt::AmbientOcclusionOptions occlusion_;
    bool shadowed_ = false;  // some light casts shadows in a mode other than none
    bool active_ = false;    // shadowed_ or occlusion_, with casters
    std::vector<float> occlusionMask_;  // per pixel, reused from frame to frame
    std::vector<glm::vec3> positions_;
    std::vector<uint32_t> indices_;
    std::vector<rt::CasterRange> ranges_;
    // Alpha-tested casters: copies of their vertex alphas and texture coordinates (lists, so the
    // ranges' spans stay put as more are added) and their base colour textures made white, per
    // texture (a lookup only: nothing is ordered by address).
    std::list<std::vector<float>> maskAlphas_;
    std::list<std::vector<glm::vec2>> maskTexCoords_;
    std::unordered_map<const raster::Texture*, std::shared_ptr<const raster::Texture>> alphaTextures_;
    rt::CasterAlphaFilter alphaFilter_;  // the rays' alpha test over ranges_ (none: every caster opaque)
    rt::Aabb bounds_;
    uint64_t castersVersion_ = 0;  // a fresh rt::nextCastersVersion() per pose: maps are kept while it stays
    rt::CasterAccel accel_;
    rt::BvhUpdateMethod bvhUpdate_;
    bool raysNeeded_ = false;              // hybrid, raytraced, auto and --ao
    std::optional<rt::DeformingBvh> bvh_;  // the rays' tree under --accel bvh, unless the camera rays' is shared
    std::optional<rt::UniformGrid> grid_;  // the same under --accel grid
    /// Hybrid: thin casters are looked for at silhouettes. Built per pose for hybrid; for auto on
    /// the first light given hybrid (adjacencyFound_ says whether it is this pose's).
    rt::MeshAdjacency adjacency_;
    bool adjacencyFound_ = false;
    /// What construction or update() did (builds, refits and their times), for the next run() to
    /// report: each is reported once, with the frame that follows it.
    ShadowFrameStats pending_;
    rt::VisibilityBuffer visibility_;  // per pose: the casters' planes and id colours
    /// The visibility buffer's casters are set when a frame first draws it (a ray-traced frame
    /// never does: its surfaces come from its camera rays), and moved to a new pose when one
    /// draws it after update().
    enum class VisibilityPose { None, Moved, Current } visibilityPose_ = VisibilityPose::None;
    bool drewVisibility_ = false;      // the last run() drew visibility_ (seenDraws)
    rt::ShadowMasks masks_;            // reused from frame to frame
    // The software GPU the visibility buffer and the shadow maps are drawn with, one pass after
    // another: its render targets are allocated once and reused by every later frame.
    raster::Pipeline gpu_;
};

rt::ShadowMode parseShadowMode(const std::string& name);  // throws scene::InputError
const char* shadowModeName(rt::ShadowMode mode);
rt::MapFocus parseMapFocus(const std::string& name);  // view or scene; throws scene::InputError
const char* mapFocusName(rt::MapFocus focus);

}  // namespace cuberille::render
