#pragma once
// The shadow stage for a 3D scene (rt/shadows.h) wired to the scene: which meshes cast and
// receive, the BVH over them, and the per-frame screen-space masks handed to the shade stage.
//
// Casters are the opaque and alpha-tested meshes (alpha-tested ones as if opaque), concatenated
// in world space in draw order, each keeping its culling so the visibility buffer sees what the
// frame shades. See-through meshes (blended or transmissive: scene::Mesh::seeThrough) neither
// cast nor take masks (scene::Scene::draw). Nothing here runs unless a mode is asked for and a
// light casts shadows: the promise that a stage a scene does not need costs nothing.

#include <optional>
#include <vector>

#include "rt/ambient_occlusion.h"
#include "rt/bvh.h"
#include "rt/deforming_bvh.h"
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
    double bvhBuildMs = 0.0;   // once per scene, reported with the first frame
    double adjacencyMs = 0.0;  // hybrid: the casters' edge adjacency, likewise
    // Animated scenes: how the hierarchy followed the casters to this frame's pose (update()).
    bool bvhUpdated = false;   // the casters moved since the last frame; the fields below say how
    bool bvhRebuilt = false;   // Lauterbach's criterion passed its threshold: rebuilt, not refitted
    double degradation = 0.0;  // the criterion's value after the refit (rt/bvh_refit.h)
    double bvhUpdateMs = 0.0;  // the refit or rebuild, and for hybrid the edge adjacency found again
    /// The casters gathered from the scene and their planes found for the visibility buffer: once
    /// per pose (at construction, reported with the first frame, and in each update()).
    double castersMs = 0.0;
    double surfacesMs = 0.0;  // the visibility buffer and surface reconstruction
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
    SceneShadows(const scene::Scene& scene, const rt::ShadowOptions& options,
                 rt::BvhUpdateMethod bvhUpdate = rt::BvhUpdateMethod::Refit,
                 const rt::AmbientOcclusionOptions& occlusion = {}, rt::CasterAccel accel = rt::CasterAccel::Bvh);

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

    /// Per pixel of the last frame: rays were traced there for some light.
    const std::vector<uint8_t>& markedPixels() const { return masks_.marked; }

private:
    void gatherCasters(const scene::Scene& scene);
    void findAdjacency();

    rt::ShadowOptions options_;
    rt::AmbientOcclusionOptions occlusion_;
    bool shadowed_ = false;  // some light casts shadows in a mode other than none
    bool active_ = false;    // shadowed_ or occlusion_, with casters
    std::vector<float> occlusionMask_;  // per pixel, reused from frame to frame
    std::vector<glm::vec3> positions_;
    std::vector<uint32_t> indices_;
    std::vector<rt::CasterRange> ranges_;
    rt::Aabb bounds_;
    uint64_t castersVersion_ = 0;  // a fresh rt::nextCastersVersion() per pose: maps are kept while it stays
    rt::CasterAccel accel_;
    std::optional<rt::DeformingBvh> bvh_;  // hybrid, raytraced, auto and --ao, under --accel bvh
    std::optional<rt::UniformGrid> grid_;  // the same under --accel grid
    /// Hybrid: thin casters are looked for at silhouettes. Built per pose for hybrid; for auto on
    /// the first light given hybrid (adjacencyFound_ says whether it is this pose's).
    rt::MeshAdjacency adjacency_;
    bool adjacencyFound_ = false;
    /// What construction or update() did (builds, refits and their times), for the next run() to
    /// report: each is reported once, with the frame that follows it.
    ShadowFrameStats pending_;
    rt::VisibilityBuffer visibility_;  // per pose: the casters' planes and id colours
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
