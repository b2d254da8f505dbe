#include "render/scene_shadows.h"

#include <stdexcept>
#include <utility>

#include "raster/clock.h"
#include "rt/bvh_build.h"
#include "scene/input_error.h"

namespace cuberille::render {

SceneShadows::SceneShadows(const scene::Scene& s, const rt::ShadowOptions& options, rt::BvhUpdateMethod bvhUpdate,
                           const rt::AmbientOcclusionOptions& occlusion, rt::CasterAccel accel, bool bvhFromCameraRays)
    : options_(options), occlusion_(occlusion), accel_(accel), bvhUpdate_(bvhUpdate) {
    if (options.mode != rt::ShadowMode::None)
        for (int l = 0; l < s.lighting.lightCount; ++l) shadowed_ = shadowed_ || rt::castsShadows(s.lighting.lights[l]);
    if (!shadowed_ && occlusion.raysPerPixel == 0) return;
    double t0 = raster::nowMs();
    gatherCasters(s);
    if (indices_.empty()) return;
    active_ = true;
    pending_.castersMs = raster::nowMs() - t0;
    const bool rays = options_.mode == rt::ShadowMode::Hybrid || options_.mode == rt::ShadowMode::RayTraced ||
                      options_.mode == rt::ShadowMode::Auto;
    raysNeeded_ = (shadowed_ && rays) || occlusion.raysPerPixel > 0;
    if (raysNeeded_) {
        if (accel_ == rt::CasterAccel::Grid) {
            t0 = raster::nowMs();
            grid_ = rt::buildUniformGrid({positions_, indices_});
            pending_.bvhBuildMs = raster::nowMs() - t0;
        } else if (!bvhFromCameraRays) {
            buildBvh();
        }
    }
    if (shadowed_ && options_.mode == rt::ShadowMode::Hybrid) {
        t0 = raster::nowMs();
        findAdjacency();
        pending_.adjacencyMs = raster::nowMs() - t0;
    }
}

void SceneShadows::gatherCasters(const scene::Scene& s) {
    positions_.clear();
    indices_.clear();
    ranges_.clear();
    maskAlphas_.clear();
    maskTexCoords_.clear();
    for (const scene::Mesh& m : s.meshes) {
        if (m.seeThrough()) continue;
        const uint32_t base = uint32_t(positions_.size());
        positions_.insert(positions_.end(), m.positions.begin(), m.positions.end());
        ranges_.push_back({uint32_t(indices_.size() / 3), uint32_t(m.triangleCount()), base,
                           uint32_t(m.positions.size()), m.doubleSided ? raster::CullMode::None : s.cull, alphaTestOf(m)});
        for (const uint32_t i : m.indices) indices_.push_back(base + i);
    }
    alphaFilter_.reset(ranges_, indices_);
    bounds_ = {};
    for (const glm::vec3& p : positions_) bounds_.grow(p);
    castersVersion_ = rt::nextCastersVersion();  // a new pose: every light's map is drawn again
}

// What the frame's alpha test reads of an alpha-tested mesh, as the vertex and shade stages take
// it: vertex alphas and texture coordinates only where there is one a vertex, the texture only with
// coordinates. The arrays are copied (the visibility buffer reads them when it next sets its
// casters, which a re-posed scene may outlive).
std::optional<rt::CasterAlphaTest> SceneShadows::alphaTestOf(const scene::Mesh& m) {
    if (m.alphaMode != raster::AlphaMode::Mask) return std::nullopt;
    rt::CasterAlphaTest a;
    a.cutoff = m.alphaCutoff;
    a.factor = m.alpha;
    const size_t vertices = m.positions.size();
    if (m.alphas.size() == vertices && vertices > 0) a.vertexAlphas = maskAlphas_.emplace_back(m.alphas);
    if (m.textures.baseColor && m.texCoords.size() == vertices && vertices > 0) {
        a.texCoords = maskTexCoords_.emplace_back(m.texCoords);
        std::shared_ptr<const raster::Texture>& white = alphaTextures_[m.textures.baseColor.texture.get()];
        if (!white) white = rt::alphaTestTexture(*m.textures.baseColor.texture);
        a.alphaOnly = {white.get(), m.textures.baseColor.transform};
    }
    return a;
}

// The adjacency matches edges by position, so a pose that pulls apart two vertices that shared a
// place (a skinned seam) changes it: it is found again for every pose, not carried over.
void SceneShadows::findAdjacency() {
    adjacency_ = rt::buildMeshAdjacency({positions_, indices_});
    adjacencyFound_ = true;
}

void SceneShadows::buildBvh() {
    const double t0 = raster::nowMs();
    bvh_.emplace(rt::TriangleMeshView{positions_, indices_}, bvhUpdate_);
    pending_.bvhBuildMs += raster::nowMs() - t0;
}

// The camera rays' mesh holds the casters' triangles: the same indices and the same positions.
// Compared by value each frame (about a millisecond on the dragon's 871k triangles), so a tree
// over anything else is never taken for the casters'.
bool SceneShadows::sameTriangles(const rt::TracedMesh& mesh) const {
    return mesh.indices == indices_ && mesh.positions.size() == positions_.size() &&
           std::equal(positions_.begin(), positions_.end(), mesh.positions.begin(),
                      [](const glm::vec3& a, const glm::vec3& b) { return a == b; });
}

void SceneShadows::update(const scene::Scene& s) {
    if (!active_) return;
    const double t0 = raster::nowMs();
    const std::vector<uint32_t> before = indices_;
    gatherCasters(s);
    if (indices_ != before) throw std::runtime_error("the animated scene changed its shadow casters' triangles");
    visibilityPose_ = VisibilityPose::Moved;
    pending_.castersMs = raster::nowMs() - t0;
    pending_.bvhUpdated = true;
    const double t1 = raster::nowMs();
    if (bvh_) {
        const rt::BvhUpdateReport report = bvh_->update({positions_, indices_});
        pending_.bvhRebuilt = report.rebuilt;
        pending_.degradation = report.degradation;
    }
    if (grid_) {
        *grid_ = rt::buildUniformGrid({positions_, indices_});
        pending_.bvhRebuilt = true;
    }
    adjacencyFound_ = false;  // the last pose's
    if (shadowed_ && options_.mode == rt::ShadowMode::Hybrid) findAdjacency();
    pending_.bvhUpdateMs = raster::nowMs() - t1;
}

raster::Lighting SceneShadows::run(const scene::Scene& s, int width, int height, ShadowFrameStats& stats) {
    drewVisibility_ = active_;
    if (!active_) return maskFor(s, {}, stats, nullptr);
    const double t0 = raster::nowMs();
    if (visibilityPose_ == VisibilityPose::None) visibility_.setCasters({positions_, indices_}, ranges_);
    if (visibilityPose_ == VisibilityPose::Moved) visibility_.moveCasters({positions_, indices_});
    visibilityPose_ = VisibilityPose::Current;
    // The visibility buffer is a pass of its own, always in the standard depth convention.
    scene::Camera standard = s.camera;
    standard.reversedDepth = false;
    const rt::ScreenSurfaces& surfaces = visibility_.draw(standard.clipFromWorld(float(width) / float(height)), width, height, gpu_);
    const double surfacesMs = raster::nowMs() - t0;
    raster::Lighting lighting = maskFor(s, surfaces, stats, nullptr);
    stats.surfacesMs = surfacesMs;
    return lighting;
}

raster::Lighting SceneShadows::run(const scene::Scene& s, const rt::ScreenSurfaces& seen, ShadowFrameStats& stats,
                                   const rt::PrimaryRayHierarchy* cameraRays) {
    drewVisibility_ = false;
    const bool shared = bvhPending() && cameraRays && sameTriangles(cameraRays->mesh());
    return maskFor(s, seen, stats, shared ? &cameraRays->bvh() : nullptr);
}

bool SceneShadows::seenDraws(const scene::Scene& s, raster::VisibilityBuffer& out) const {
    if (!drewVisibility_) return false;
    size_t k = 0;
    for (const scene::Mesh& m : s.meshes) {
        if (m.seeThrough()) continue;
        if (k == ranges_.size() || ranges_[k].triangleCount != m.triangleCount()) return false;
        ++k;
    }
    if (k != ranges_.size()) return false;
    visibility_.seenByRange(out);
    return true;
}

// The frame's masks from its surfaces: the stage's own visibility buffer or the caller's.
raster::Lighting SceneShadows::maskFor(const scene::Scene& s, const rt::ScreenSurfaces& surfaces, ShadowFrameStats& stats,
                                       const rt::DeformingBvh* shared) {
    if (bvhPending() && !shared) buildBvh();  // not shareable after all
    stats = std::exchange(pending_, {});
    stats.bvhShared = shared != nullptr;
    stats.mode = options_.mode;
    stats.soft = options_.soft;
    stats.focus = options_.focus;
    stats.accel = accel_;
    stats.casterTriangles = indices_.size() / 3;
    raster::Lighting lighting = s.lighting;
    if (!active_) return lighting;
    const rt::TriangleMeshView casters{positions_, indices_};
    const rt::ShadowCasters shadowCasters{.mesh = casters,
                                          .rays = {.bvh = bvh_ ? &*bvh_ : shared,
                                                   .grid = grid_ ? &*grid_ : nullptr,
                                                   .mesh = casters,
                                                   .filter = alphaFilter_.filter()},
                                          .bounds = bounds_,
                                          .adjacency = adjacencyFound_ ? &adjacency_ : nullptr,
                                          .version = castersVersion_,
                                          .adjacencyOnDemand = [this, &stats]() -> const rt::MeshAdjacency* {
                                              const double t = raster::nowMs();
                                              findAdjacency();
                                              stats.adjacencyMs += raster::nowMs() - t;
                                              return &adjacency_;
                                          },
                                          .ranges = ranges_};
    if (shadowed_) {
        rt::computeShadows(surfaces, s.lighting, shadowCasters, options_, gpu_, masks_);
        stats.shadows = masks_.stats;
        for (int l = 0; l < lighting.lightCount; ++l)
            if (!masks_.visibility[size_t(l)].empty()) lighting.lights[l].visibility = masks_.visibility[size_t(l)].data();
    }
    if (occlusion_.raysPerPixel > 0) {
        const float distance = occlusion_.maxDistance > 0.0f
                                   ? occlusion_.maxDistance
                                   : rt::kDefaultOcclusionDistanceOfBounds * glm::length(bounds_.extent());
        rt::computeAmbientOcclusion(surfaces, shadowCasters.rays, distance, rt::surfaceRayOffset(bounds_), occlusion_, occlusionMask_,
                                    stats.occlusion);
        lighting.ambientVisibility = occlusionMask_.data();
    }
    return lighting;
}

rt::ShadowMode parseShadowMode(const std::string& name) {
    if (name == "none") return rt::ShadowMode::None;
    if (name == "map") return rt::ShadowMode::Map;
    if (name == "hybrid") return rt::ShadowMode::Hybrid;
    if (name == "raytraced") return rt::ShadowMode::RayTraced;
    if (name == "auto") return rt::ShadowMode::Auto;
    throw scene::InputError("--shadows: '" + name + "' is not none, map, hybrid, raytraced or auto");
}

const char* shadowModeName(rt::ShadowMode mode) {
    switch (mode) {
        case rt::ShadowMode::None: return "none";
        case rt::ShadowMode::Map: return "map";
        case rt::ShadowMode::Hybrid: return "hybrid";
        case rt::ShadowMode::RayTraced: return "raytraced";
        case rt::ShadowMode::Auto: return "auto";
    }
    return "?";
}

rt::MapFocus parseMapFocus(const std::string& name) {
    if (name == "view") return rt::MapFocus::View;
    if (name == "scene") return rt::MapFocus::Scene;
    throw scene::InputError("--shadow-focus: '" + name + "' is not auto, view or scene");
}

const char* mapFocusName(rt::MapFocus focus) { return focus == rt::MapFocus::View ? "view" : "scene"; }

}  // namespace cuberille::render
