#include "render/renderer.h"

#include <cmath>
#include <mutex>
#include <unordered_map>

#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>

#include "raster/clock.h"
#include "raster/instruction_set.h"
#include "raster/limits.h"
#include "raster/parallel.h"
#include "raster/pipeline.h"
#include "raster/srgb.h"
#include "raster/texture.h"
#include "render/display_image.h"
#include "render/frame_memory.h"
#include "render/view_legend.h"
#include "render/scene_state.h"
#include "scene/input_error.h"

namespace cuberille::render {
namespace {

using State = LoadedScene::State;

void validate(const State& s, const FrameSettings& f);
RenderResult renderAtScale(State& s, const FrameSettings& f, float windowScale);
RenderResult renderSupersampled(State& s, const FrameSettings& f);

// Frames are drawn one at a time in a process: each already runs on every core it is allowed
// (raster/parallel.h), and the thread limit and the threads-that-ran count are the process's.
std::mutex gFrameMutex;

}  // namespace

RenderResult render(const LoadedScene& scene, const FrameSettings& f) {
    State& s = SceneAccess::state(scene);
    std::lock_guard lock(gFrameMutex);
    if (f.supersample < 1 || f.supersample > 16) throw scene::InputError("--supersample: must be 1 to 16");
    validate(s, f);  // before the memory check: a frame too large for the rasterizer is refused as such
    requireFrameMemory(f);
    raster::ThreadLimit threadLimit(f.threads);
    raster::resetThreadsThatRan();
    RenderResult r = f.supersample > 1 ? renderSupersampled(s, f) : renderAtScale(s, f, 1.0f);
    r.threadsRan = raster::threadsThatRan();
    if (f.legend) {
        drawLegend(r.image, legendFor(f.view, r.voxel ? r.voxel->selection.drawnPerLevel : std::vector<uint64_t>{},
                                      f.debugCamera));
    }
    return r;
}

size_t cameraCount(const LoadedScene& scene) {
    State& s = SceneAccess::state(scene);
    std::lock_guard lock(gFrameMutex);
    if (!s.gltf) return 0;
    if (!s.hasPose) s.poseFor(FrameSettings{});
    return s.fileCameras.size();
}

raster::Image displayImage(const LoadedScene& scene, const FrameSettings& f, const RenderResult& r) {
    raster::Image legible;
    return displayImage(r.image, f.view, !scene.isTriangleList(), legible);
}

std::vector<uint8_t> displayPixels(const LoadedScene& scene, const FrameSettings& f, const RenderResult& r) {
    raster::Image legible;
    return displayRgba8(displayImage(r.image, f.view, !scene.isTriangleList(), legible), hasAlpha(f));
}

namespace {

/// --ao's bound: past 1024 rays a pixel the estimate's noise (stratified, below 1/N) is far under
/// one 8-bit level, and a 1080p frame would trace two billion rays.
constexpr int kMaxOcclusionRaysPerPixel = 1024;

// An option a scene cannot use is refused, not silently ignored.
void validate(const State& s, const FrameSettings& o) {
    using scene::InputError;
    validateFrameOptions(o.width, o.height, o.msaa, o.threads);
    if (!std::isfinite(o.timeSeconds)) throw InputError("--time: must be a finite number of seconds");
    const rt::ShadowOptions& sh = o.shadows;
    if (sh.mapSizeTexels < 16 || sh.mapSizeTexels > 16384)
        throw InputError("--shadow-map-size: " + std::to_string(sh.mapSizeTexels) + " is outside 16..16384");
    if (sh.softSamplesPerSide < 1 || sh.softSamplesPerSide > 16)
        throw InputError("--soft-samples: " + std::to_string(sh.softSamplesPerSide) + " is outside 1..16 (rays per side)");
    if (!(sh.lightRadius >= 0.0f) || !std::isfinite(sh.lightRadius))
        throw InputError("--light-radius: must be a finite number, 0 or more");
    const bool tri = s.kind == scene::FileKind::TriangleList, voxel = s.kind == scene::FileKind::VoxelModel;
    const bool threeD = !tri && !voxel, gltf = scene::isGltfKind(s.kind);
    const rt::AmbientOcclusionOptions& ao = o.ambientOcclusion;
    if (ao.raysPerPixel < 0 || ao.raysPerPixel > kMaxOcclusionRaysPerPixel)
        throw InputError("--ao: " + std::to_string(ao.raysPerPixel) + " is outside 0.." +
                         std::to_string(kMaxOcclusionRaysPerPixel) + " (rays per pixel)");
    if (!(ao.maxDistance >= 0.0f) || !std::isfinite(ao.maxDistance))
        throw InputError("--ao-distance: must be a finite number, 0 or more (0: a tenth of the model's size)");
    // A voxel model's rays come from the ray-tracing renderer: its camera rays' faces cast them.
    const bool tracedVoxels = voxel && o.renderer == Renderer::Raytrace;
    if (ao.raysPerPixel > 0 && !threeD && !tracedVoxels)
        throw InputError("--ao: only for 3D scenes (glTF, PLY, OBJ, built-in) and, with --renderer raytrace, voxel models; not " + s.name);
    if (tracedVoxels && sh.mode != rt::ShadowMode::None && sh.mode != rt::ShadowMode::RayTraced)
        throw InputError(std::string("--shadows ") + shadowModeName(sh.mode) +
                         ": a voxel model's ray-traced frame takes --shadows raytraced (its rays go through the voxel tree)");
    if ((sh.mode != rt::ShadowMode::None && !threeD && !tracedVoxels) || (o.view == View::ShadowPixels && !threeD))
        throw InputError("--shadows and --view shadow-pixels: only for 3D scenes (glTF, PLY, OBJ, built-in) and, with "
                         "--renderer raytrace, voxel models (--shadows raytraced); not " + s.name);
    if (o.view == View::Normals && !threeD)
        throw InputError("--view normals: only for 3D scenes (glTF, PLY, OBJ, built-in), not " + s.name);
    if (o.view == View::ShadowPixels && sh.mode == rt::ShadowMode::None)
        throw InputError("--view shadow-pixels: needs --shadows map, hybrid or raytraced");
    if (o.renderer == Renderer::Raytrace && tri)
        throw InputError("--renderer raytrace: only for 3D scenes (glTF, PLY, OBJ, built-in) and voxel models, not " + s.name);
    if (o.renderer == Renderer::Raytrace && voxel && o.accel == rt::CasterAccel::Grid)
        throw InputError("--accel grid: a grid over triangles; a voxel model's rays take bvh, kdtree, octree or bvh8");
    if (o.voxelAccel != rt::VoxelStructure::Bvh && !(voxel && o.renderer == Renderer::Raytrace))
        throw InputError(std::string("--accel ") + rt::voxelStructureName(o.voxelAccel) +
                         ": a tree over voxels, for voxel models (.cvox) with --renderer raytrace");
    if (o.renderer == Renderer::Raytrace && voxel &&
        (o.debugCamera || o.noHybrid || o.noOcclusion || o.pixelError != FrameSettings{}.pixelError))
        throw InputError("--pixel-error, --no-hybrid, --no-occlusion and --debug-camera: the rasterizer's level of detail and "
                         "culling; --renderer raytrace traces one level (--voxel-resolution) of solid voxels");
    if (o.renderer == Renderer::Raytrace && o.view != View::Color && o.view != View::Depth && o.view != View::Normals &&
        o.view != View::ShadowPixels)
        throw InputError(std::string("--view ") + viewName(o.view) + ": shows the rasterizer's stages; with --renderer "
                         "raytrace only color, depth, normals and shadow-pixels");
    if (o.frustumCull && !threeD) throw InputError("--frustum-cull: only for 3D scenes (glTF, PLY, OBJ, built-in), not " + s.name);
    if (o.ground && (!threeD || s.procedural)) throw InputError("--ground: only for model files (glTF, PLY, OBJ), not " + s.name);
    // A .tri scene's triangles are flat colours; a voxel model's frame takes the voxel scene's own
    // lighting, which the environment does not reach yet. Refused rather than ignored.
    if (!o.environment.empty() && !threeD)
        throw InputError("--environment: only for 3D scenes (glTF, PLY, OBJ, built-in), not " + s.name);
    if (o.shadowCatcher && !o.ground) throw InputError("--shadow-catcher: needs --ground (the floor that catches the shadow)");
    if (o.shadowCatcher && sh.mode == rt::ShadowMode::None)
        throw InputError("--shadow-catcher: needs --shadows map, hybrid or raytraced (without them there is no shadow to catch)");
    if (o.shadowCatcher && hasAlpha(o))
        throw InputError("--shadow-catcher: needs an opaque --background (the floor is drawn in it)");
    if (o.placement && !threeD) throw InputError("--eye: only for 3D scenes (glTF, PLY, OBJ, built-in), not " + s.name);
    if (o.placement && o.cameraIndex >= 0) throw InputError("--eye and --camera-index: one camera or the other");
    if (o.placement && !(o.placement->verticalFovDegrees >= 0.0f && o.placement->verticalFovDegrees < 180.0f))
        throw InputError("--fov: degrees in (0, 180)");
    if (o.placement) {
        const glm::vec3 forward = o.placement->target.value_or(glm::vec3(0.0f)) - o.placement->eye;
        const glm::vec3 up = o.placement->up.value_or(glm::vec3(0.0f, 1.0f, 0.0f));
        if (o.placement->target && !(glm::length(forward) > 0.0f)) throw InputError("--target: must differ from --eye");
        if (!(glm::length(up) > 0.0f)) throw InputError("--up: must not be zero");
    }
    if (o.timeSeconds != 0.0f && !gltf)
        throw InputError("--time: only glTF files (.gltf, .glb) have animations, not " + s.name);
    if (!(o.zoom > 0.0f && o.zoom <= 1000.0f)) throw InputError("--zoom: must be in (0, 1000]");
    if (o.zoom != 1.0f && tri) throw InputError("--zoom: not for 2D .tri scenes");
    if (o.orthographic && tri) throw InputError("--orthographic: not for 2D .tri scenes");
    if (!o.animation.empty() && !gltf)
        throw InputError("--animation: only glTF files (.gltf, .glb) have animations, not " + s.name);
    if (o.orbitDegrees != 0.0f && tri) throw InputError("--turntable: " + s.name + " is a 2D .tri scene");
    if (o.orbitDegrees != 0.0f && voxel) throw InputError("--turntable: not for voxel models yet");
    if (!std::isfinite(o.orbitDegrees)) throw InputError("orbit: must be a finite number of degrees");
    if ((o.view == View::Lod || o.view == View::Visibility || o.debugCamera) && !voxel)
        throw InputError("--view lod, --view visibility and --debug-camera: only for voxel models (.cvox)");
    if (!(o.pixelError >= 0.0f)) throw InputError("--pixel-error: must be 0 or more");
    if (o.warmup < 0 || o.warmup > 100) throw InputError("--warmup: must be 0 to 100 frames");
    if (o.supersample > 1 && o.view != View::Color) throw InputError("--supersample: only with --view color");
    const int n = o.supersample;
    if (int64_t(o.width) * n > raster::kMaxFramebufferPixels || int64_t(o.height) * n > raster::kMaxFramebufferPixels)
        throw InputError("--supersample: " + std::to_string(o.width) + "x" + std::to_string(o.height) + " times " +
                         std::to_string(n) + " exceeds " + std::to_string(raster::kMaxFramebufferPixels) + " pixels a side");
}

// Resolves only what the view shows: the colour resolve runs for color and tiles alone.
// camera: the frame's, for the depth view's distances; null for 2D .tri scenes, whose depth view
// is the stored depth itself.
void finishView(const raster::Pipeline& p, View view, const scene::Camera* camera, raster::Image& image, double& resolveMs) {
    const double t0 = raster::nowMs();
    switch (view) {
        case View::Color:
        case View::Lod:
        case View::Visibility:
        case View::ShadowPixels:
        case View::Normals: raster::resolveColor(p.framebuffer(), image); break;
        case View::Depth:
            if (camera) raster::resolveViewDistance(p.framebuffer(), camera->nearPlane, camera->farPlane, image, camera->orthographic);
            else raster::resolveDepth(p.framebuffer(), image);
            break;
        case View::Overdraw: raster::visualizeOverdraw(p.framebuffer(), image); break;
        case View::Tiles: {
            raster::Image color;
            raster::resolveColor(p.framebuffer(), color);
            raster::visualizeBlockClasses(p.framebuffer(), color, image);
            break;
        }
    }
    resolveMs = raster::nowMs() - t0;
}

// The frame's framebuffer, cleared to --background where given, else to the scene's own.
raster::FramebufferDesc clearedFramebufferDesc(const FrameSettings& o, glm::vec4 sceneBackground) {
    raster::FramebufferDesc desc = framebufferDesc(o);
    desc.clearColor = o.background ? clearColorFor(*o.background) : sceneBackground;
    return desc;
}

// One frame: submit(pipeline) records the draws, whose arrays stay alive until endFrame
// (Pipeline::draw's contract), then the view is resolved.
template <class Submit>
void drawFrame(const FrameSettings& o, glm::vec4 sceneBackground, const scene::Camera* camera, Submit&& submit,
               RenderResult& result) {
    raster::Pipeline pipeline;
    const raster::FramebufferDesc desc = clearedFramebufferDesc(o, sceneBackground);
    pipeline.beginFrame(desc);
    submit(pipeline);
    pipeline.endFrame();
    result.stats = pipeline.stats();
    if (result.voxel) result.voxel->coveredPixels = raster::coveredPixels(pipeline.framebuffer());
    finishView(pipeline, o.view, camera, result.image, result.stats.times.resolveMs);
}

// The end of a deferred frame: the recorded opaque draws shaded where `seen` names them, then the
// see-through draws (blended, transmissive) drawn forward over them, in their order, against the
// depths the shade stage wrote, as a deferred GPU renderer draws its transparent pass.
raster::VisibilityShadeStats shadeThenDrawSeeThrough(raster::Pipeline& pipeline, const raster::VisibilityBuffer& seen,
                                                     const raster::Lighting* lighting) {
    // Copied first: shadeVisible gives the recorded draws `lighting`, which see-through ones do not take.
    const std::vector<raster::DrawCall> draws(pipeline.recordedDraws().begin(), pipeline.recordedDraws().end());
    const raster::VisibilityShadeStats shade = pipeline.shadeVisible(seen, lighting);
    for (const raster::DrawCall& d : draws)
        if (!d.state.depthWrite) pipeline.draw(d);
    return shade;
}

// Shading the shadow stage's visibility buffer saves the forward pass's work per triangle (its
// front end, binning and coverage, for triangles never seen too, and the shading of overdrawn
// pixels) and costs some per covered pixel that the forward path's 8x8 lanes do not pay (grouping
// each pixel by triangle, its own edge and depth values). Measured on turntables at 1280x720 on
// their floors, hybrid shadows, the two ways alternating (docs/performance.md, "Shadowed frames
// shade the shadow stage's visibility buffer"): the dragon's frame (871k triangles, 0.95 a pixel)
// 40-43% shorter; BrainStem (61.7k, 0.067) and DamagedHelmet (15.5k, 0.017) within this VM's noise
// either way; Virtual City (8.4k, 0.009) 27-60% longer. A quarter of a triangle a pixel lies
// between the dense scan and the rest (518k triangles at 1920x1080).
constexpr double kTrianglesPerPixelToShadeShadowVisibility = 0.25;

bool shadowStageVisibilityPays(const FrameSettings& o, const scene::Scene& s) {
    if (o.frameVisibility != FrameVisibility::Auto) return o.frameVisibility == FrameVisibility::ShadowStage;
    size_t opaqueTriangles = 0;
    for (const scene::Mesh& m : s.meshes)
        if (!m.seeThrough()) opaqueTriangles += m.triangleCount();
    return double(opaqueTriangles) >= kTrianglesPerPixelToShadeShadowVisibility * double(o.width) * double(o.height);
}

// A raster frame whose shadow stage has just drawn its own visibility buffer at the frame's one
// sample (SceneShadows::seenDraws): the depth test would keep, at every pixel, the triangle that
// buffer names, so the frame shades those (the opaque draws carrying the masked lighting) instead
// of rasterizing them a second time — the forward frame's bits, one pass over the geometry fewer.
void drawFrameOverShadowStageVisibility(State& state, const FrameSettings& o, const scene::Scene& drawn,
                                        const raster::VisibilityBuffer& seen, const raster::Lighting& shadowed,
                                        RenderResult& result) {
    raster::Pipeline& pipeline = state.deferredFrames;
    const raster::FramebufferDesc desc = clearedFramebufferDesc(o, drawn.background);
    pipeline.beginDeferredFrame(desc);
    drawn.draw(pipeline, float(o.width) / float(o.height), &shadowed);
    result.shadedShadowStageVisibility = shadeThenDrawSeeThrough(pipeline, seen, nullptr);
    pipeline.endFrame();
    result.stats = pipeline.stats();
    finishView(pipeline, o.view, &drawn.camera, result.image, result.stats.times.resolveMs);
}

// --renderer raytrace: the frame's draws recorded, camera rays through the opaque ones decide what
// each sample sees (alpha-tested ones through their alpha test), and the deferred shade stage
// shades it with the draws' own shading. See-through draws (blended, transmissive) are then drawn
// over it by the rasterizer, in their order, against the depths the shade stage wrote, as a
// deferred GPU renderer draws its transparent pass forward (docs/ray_tracing.md).
void drawRayTracedFrame(State& state, const FrameSettings& o, const scene::Scene& drawn, const scene::Camera& camera,
                        SceneShadows* shadows, RenderResult& result) {
    raster::Pipeline& pipeline = state.deferredFrames;
    const raster::FramebufferDesc desc = clearedFramebufferDesc(o, drawn.background);
    pipeline.beginDeferredFrame(desc);
    const float aspect = float(o.width) / float(o.height);
    drawn.draw(pipeline, aspect, nullptr);  // the shadow stage's lighting comes after the rays, at shadeVisible
    const std::vector<raster::DrawCall> draws(pipeline.recordedDraws().begin(), pipeline.recordedDraws().end());
    std::vector<uint8_t> traced(draws.size());
    RayTracedFrameStats st;
    for (size_t d = 0; d < draws.size(); ++d) {
        traced[d] = draws[d].state.depthWrite;
        (traced[d] ? st.drawsTraced : st.drawsRasterized) += 1;
    }
    rt::PrimaryRayCamera rays;
    rays.worldFromClip = glm::inverse(glm::dmat4(camera.clipFromWorld(aspect)));
    rays.reversedDepth = camera.reversedDepth;
    rays.orthographic = camera.orthographic;
    rays.eye = camera.position;
    rays.viewDirection = glm::normalize(camera.target - camera.position);
    raster::VisibilityBuffer seen;
    seen.reset(desc.widthPixels, desc.heightPixels, desc.samples);
    if (o.accel == rt::CasterAccel::Grid) {
        st.rays = rt::tracePrimaryVisibility(draws, traced, rays, o.accel, seen);
    } else {
        // The tree is kept for the next frame unless the frustum cull rewrites index lists in place.
        std::optional<rt::PrimaryRayHierarchy>& kept = state.primaryRays;
        if (kept && (o.frustumCull || state.primaryRaysMethod != o.bvhUpdate || !kept->sameDraws(draws, traced))) kept.reset();
        if (!kept) {
            kept.emplace(draws, traced, o.bvhUpdate);
            state.primaryRaysMethod = o.bvhUpdate;
        } else if (state.primaryRaysPoseStale || !kept->sameVertexArrays(draws)) {
            st.update = kept->update(draws);
            st.updated = true;
        }
        state.primaryRaysPoseStale = false;
        st.rays = kept->trace(draws, rays, seen);
    }
    std::optional<raster::Lighting> shadowed;
    if (shadows) {
        // The shadow stage and occlusion start from the surfaces the camera rays met at pixel
        // centres: the frame's own rays at one sample (the pattern's sample is the centre); at
        // more, the triangle a pixel's samples all see, and a ray through the centre where they
        // part (through the same structure; the grid traces every centre).
        result.shadows.emplace();
        const double t0 = raster::nowMs();
        if (shadows->active()) {
            raster::VisibilityBuffer centres;
            uint64_t centreRays = 0;
            if (desc.samples > 1) {
                std::vector<uint32_t> open;
                rt::centresWhereSamplesAgree(seen, centres, open);
                centreRays = open.size();
                if (o.accel == rt::CasterAccel::Bvh) {
                    state.primaryRays->traceCentres(draws, rays, open, centres);
                } else {  // the grid is built for a whole frame's rays: every centre, the open ones kept
                    raster::VisibilityBuffer all;
                    all.reset(desc.widthPixels, desc.heightPixels, 1);
                    rt::tracePrimaryVisibility(draws, traced, rays, o.accel, all);
                    for (const uint32_t p : open) centres.draw[p] = all.draw[p], centres.triangle[p] = all.triangle[p];
                }
            }
            scene::Camera standard = camera;
            standard.reversedDepth = false;
            rt::surfacesFromVisibility(desc.samples > 1 ? centres : seen, draws, standard.clipFromWorld(aspect), state.tracedSurfaces);
            const double surfacesMs = raster::nowMs() - t0;
            shadowed = shadows->run(drawn, state.tracedSurfaces, *result.shadows,
                                    o.accel == rt::CasterAccel::Bvh ? &*state.primaryRays : nullptr);
            // run() starts the frame's stats afresh: what came before it is filled in after.
            result.shadows->surfacesMs = surfacesMs;
            result.shadows->centreRays = centreRays;
        }
        result.shadows->totalMs = raster::nowMs() - t0;
    }
    if (o.frustumCull) state.primaryRays.reset();
    st.shade = shadeThenDrawSeeThrough(pipeline, seen, shadowed ? &*shadowed : nullptr);
    pipeline.endFrame();
    result.stats = pipeline.stats();
    result.rayTraced = st;
    finishView(pipeline, o.view, &camera, result.image, result.stats.times.resolveMs);
}

// --zoom F: a lens zoom. The eye stays and the field of view narrows until what it saw is F
// times larger (tan of the half-angle divided by F), whichever camera framed the scene; an
// orthographic camera's half height is divided by F.
void applyZoom(scene::Camera& camera, float zoom) {
    if (zoom == 1.0f) return;
    if (camera.orthographic) {
        camera.orthographicHalfHeight /= zoom;
        return;
    }
    const double halfAngle = std::atan(std::tan(glm::radians(double(camera.verticalFovDegrees)) / 2.0) / zoom);
    camera.verticalFovDegrees = float(glm::degrees(2.0 * halfAngle));
}

// The camera turned about the world's up axis through its target.
scene::Camera orbit(const scene::Camera& c, float degrees) {
    if (degrees == 0.0f) return c;
    const glm::mat3 turn(glm::rotate(glm::mat4(1.0f), glm::radians(degrees), glm::vec3(0, 1, 0)));
    scene::Camera r = c;
    r.position = c.target + turn * (c.position - c.target);
    r.up = turn * c.up;
    return r;
}

// --texture-filter other than file: every texture of the scene gets the one filter. Textures are
// shared between meshes, so each distinct one is copied once (the map is only a lookup; nothing
// is ordered by address).
void overrideTextureFilters(scene::Scene& s, TextureFilterOverride which) {
    if (which == TextureFilterOverride::File) return;
    raster::TextureFilter filter;
    filter.magnifyNearest = which == TextureFilterOverride::Nearest;
    filter.minify = which == TextureFilterOverride::Nearest  ? raster::MinFilter::Nearest
                    : which == TextureFilterOverride::Bilinear ? raster::MinFilter::Linear
                                                               : raster::MinFilter::LinearMipmapLinear;
    std::unordered_map<const raster::Texture*, std::shared_ptr<const raster::Texture>> replaced;
    auto retarget = [&](scene::MeshTexture& slot) {
        if (!slot.texture) return;
        auto& copy = replaced[slot.texture.get()];
        if (!copy) {
            auto t = std::make_shared<raster::Texture>(*slot.texture);
            t->setFilter(filter);
            copy = std::move(t);
        }
        slot.texture = copy;
    };
    for (scene::Mesh& m : s.meshes) {
        scene::MeshTextures& t = m.textures;
        for (scene::MeshTexture* slot :
             {&t.baseColor, &t.metallicRoughness, &t.normal, &t.occlusion, &t.emissive, &t.specular, &t.specularColor, &t.clearcoat,
              &t.clearcoatRoughness, &t.clearcoatNormal, &t.sheenColor, &t.sheenRoughness, &t.transmission,
              &t.thickness})
            retarget(*slot);
    }
}

// What a frame changes in the pose it borrows (the texture filters, the culled index lists),
// put back when the frame ends, so the next frame starts from the scene as loaded.
class BorrowedPose {
public:
    BorrowedPose(scene::Scene& s, bool textures, bool indices) : scene_(s) {
        for (const scene::Mesh& m : s.meshes) {
            if (textures) textures_.push_back(m.textures);
            if (indices) indices_.push_back(m.indices);
        }
    }
    ~BorrowedPose() {
        for (size_t m = 0; m < textures_.size(); ++m) scene_.meshes[m].textures = std::move(textures_[m]);
        for (size_t m = 0; m < indices_.size(); ++m) scene_.meshes[m].indices = std::move(indices_[m]);
    }
    BorrowedPose(const BorrowedPose&) = delete;
    BorrowedPose& operator=(const BorrowedPose&) = delete;

private:
    scene::Scene& scene_;
    std::vector<scene::MeshTextures> textures_;
    std::vector<std::vector<uint32_t>> indices_;
};

// --view normals: each mesh drawn unlit in its interpolated world-space vertex normals as display
// colours, (x, y, z) / 2 + 1/2 — the usual normal-map colouring, so +x is red, +y green, +z blue.
// Normal maps are not applied and textures are dropped (an alpha mask's cut-outs with them).
scene::Scene normalsScene(const scene::Scene& s) {
    scene::Scene view = s;
    for (scene::Mesh& m : view.meshes) {
        m.colors.resize(m.normals.size());
        for (size_t i = 0; i < m.normals.size(); ++i)
            for (int k = 0; k < 3; ++k) m.colors[i][k] = float(raster::decodeSrgb(0.5 * double(m.normals[i][k]) + 0.5));
        m.color = glm::vec3(1.0f);
        m.unlit = true;
        m.metallicRoughness = false;
        m.emissive = glm::vec3(0.0f);
        m.textures = {};
        m.texCoords.clear();
        m.tangents.clear();
        m.alphas.clear();
        m.alpha = 1.0f;
        m.alphaMode = raster::AlphaMode::Opaque;
    }
    return view;
}

// --view shadow-pixels: the frame dimmed, and the pixels the shadow stage traced rays for in red.
void showShadowPixels(const std::vector<uint8_t>& marked, raster::Image& image) {
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            float* p = image.pixel(x, y);
            const bool traced = !marked.empty() && marked[size_t(y) * image.width + x];
            for (int k = 0; k < 3; ++k) p[k] = traced ? (k == 0 ? 1.0f : 0.1f) : 0.3f * p[k];
        }
}

// A 3D scene's frame: posed and framed, the shadow stage first when asked for (its masks go to
// the shade stage with the lights; casters outside the view still cast into it, so it runs on
// the whole scene), then the frustum cull trims what the frame draws, then the draws.
void render3d(State& st, const FrameSettings& o, RenderResult& result) {
    result.loadMs = st.poseFor(o);
    scene::Scene& s = st.posed;
    result.load = s.loadStats;
    st.frameFor(o);
    st.groundFor(o);
    s.camera.reversedDepth = o.depth == raster::DepthConvention::Reversed;
    if (o.orthographic) s.camera = scene::orthographicView(s.camera);
    applyZoom(s.camera, o.zoom);
    s.camera = orbit(s.camera, o.orbitDegrees);
    BorrowedPose borrowed(s, o.textureFilter != TextureFilterOverride::File, o.frustumCull);
    overrideTextureFilters(s, o.textureFilter);
    result.sceneTriangles = s.triangleCount();
    SceneShadows* shadows = st.shadowsFor(o);
    SceneFrustumCull* culling = st.cullingFor(o);
    std::optional<raster::Lighting> shadowed;
    // A raster frame runs the shadow stage first, on its own visibility buffer; a ray-traced one
    // after its camera rays, on the surfaces they met (drawRayTracedFrame).
    const bool traced = o.renderer == Renderer::Raytrace;
    if (shadows && !traced) {
        result.shadows.emplace();
        const double t0 = raster::nowMs();
        if (shadows->active()) shadowed = shadows->run(s, o.width, o.height, *result.shadows);
        result.shadows->totalMs = raster::nowMs() - t0;
    }
    if (culling) result.culling = culling->cull(s, float(o.width) / float(o.height));
    const std::optional<scene::Scene> normals = o.view == View::Normals ? std::optional(normalsScene(s)) : std::nullopt;
    const scene::Scene& drawn = normals ? *normals : s;
    // A frame the shadow stage has already looked at through its own visibility buffer, as the
    // depth test would at one sample, shades what it saw (drawFrameOverShadowStageVisibility).
    raster::VisibilityBuffer seen;
    const bool overShadowStageVisibility = shadowed && !traced && o.msaa == 1 && !culling && !normals &&
                                           (o.view == View::Color || o.view == View::ShadowPixels) &&
                                           o.depth == raster::DepthConvention::Standard && shadowStageVisibilityPays(o, s) &&
                                           shadows->seenDraws(s, seen);
    if (traced) {
        drawRayTracedFrame(st, o, drawn, s.camera, shadows, result);
    } else if (overShadowStageVisibility) {
        drawFrameOverShadowStageVisibility(st, o, drawn, seen, *shadowed, result);
    } else {
        drawFrame(o, s.background, &s.camera, [&](raster::Pipeline& p) {
            drawn.draw(p, float(o.width) / float(o.height), shadowed ? &*shadowed : nullptr);
        }, result);
    }
    if (o.view == View::ShadowPixels) showShadowPixels(shadows->markedPixels(), result.image);
}

// --voxel-resolution N: the level whose resolution is N (the finest level's halved per level).
uint32_t finestLevelFor(const voxel::VoxelModel& model, uint32_t resolution) {
    if (resolution == 0) return 0;
    const uint32_t finest = model.grid.resolution;
    const uint32_t levels = model.blocks.empty() ? 1 : model.blocks.front().level + 1;
    std::string offered;
    for (uint32_t level = 0; level < levels; ++level) {
        if ((finest >> level) == resolution) return level;
        offered += (level ? ", " : "") + std::to_string(finest >> level);
    }
    throw scene::InputError("--voxel-resolution: " + std::to_string(resolution) + " is not a level of the model (" +
                            offered + ")");
}

/// --renderer raytrace for a voxel model: one level's voxels through the --accel tree, kept for
/// the next frame while the level and tree hold (render/voxel_ray_frame.h).
void drawVoxelRayTracedFrame(State& st, const FrameSettings& o, RenderResult& result) {
    lod::VoxelScene& s = *st.voxel;
    const uint32_t level = finestLevelFor(s.model(), o.voxelResolution);
    if (!st.voxelRays || st.voxelRays->level() != level || st.voxelRays->structure() != o.voxelAccel)
        st.voxelRays = std::make_unique<VoxelRayScene>(s.model(), level, o.voxelAccel);
    raster::Pipeline pipeline;
    const raster::FramebufferDesc desc = clearedFramebufferDesc(o, s.background);
    pipeline.beginDeferredFrame(desc);
    VoxelRayEffects effects;
    effects.shadows = o.shadows.mode == rt::ShadowMode::RayTraced;
    effects.soft = o.shadows.soft;
    effects.lightRadius = o.shadows.lightRadius;
    effects.softSamplesPerSide = o.shadows.softSamplesPerSide;
    effects.occlusionRays = o.ambientOcclusion.raysPerPixel;
    effects.occlusionDistance = o.ambientOcclusion.maxDistance;
    result.voxelRays = st.voxelRays->drawFrame(pipeline, s.camera, s.lighting, desc.widthPixels, desc.heightPixels, desc.samples,
                                               effects);
    pipeline.endFrame();
    result.stats = pipeline.stats();
    finishView(pipeline, o.view, &s.camera, result.image, result.stats.times.resolveMs);
}

/// A voxel model: blocks selected, expanded and drawn through the same pipeline.
void renderVoxelModel(State& st, const FrameSettings& o, RenderResult& result) {
    lod::VoxelScene& s = *st.voxel;
    s.frameFrom(o.azimuth, o.elevation);
    s.resetOcclusion();  // each render starts from nothing (render/loaded_scene.h)
    s.camera.reversedDepth = o.depth == raster::DepthConvention::Reversed;
    if (o.orthographic) s.camera = scene::orthographicView(s.camera);
    applyZoom(s.camera, o.zoom);
    result.sceneTriangles = s.model().triangleCount();
    result.voxelResolution = s.model().grid.resolution;
    if (o.renderer == Renderer::Raytrace) {
        drawVoxelRayTracedFrame(st, o, result);
        return;
    }
    lod::VoxelRenderOptions vo;
    vo.selection.pixelError = o.pixelError;
    vo.selection.finestLevel = finestLevelFor(s.model(), o.voxelResolution);
    vo.selection.hybrid = !o.noHybrid;
    vo.coloring = o.view == View::Lod          ? lod::BlockColoring::Level
                  : o.view == View::Visibility ? lod::BlockColoring::Visibility
                                               : lod::BlockColoring::Model;
    vo.occlusion = vo.leaveOutVoxelsBehindDepth = !o.noOcclusion;
    // Occlusion culling learns from the frame before: the warm-up frames give it that history
    // (the image is the same with or without it; only the work differs).
    const auto submit = [&](raster::Pipeline& p) { result.voxel = s.draw(p, o.width, o.height, vo); };
    const int frames = vo.occlusion ? 1 + o.warmup : 1;
    for (int f = 0; f < frames; ++f) {
        drawFrame(o, s.background, &s.camera, submit, result);
        s.readOcclusion(result.stats);
    }
    if (o.debugCamera) {  // what the main camera's frame selected, seen from its side
        const scene::Camera debug = lod::debugCameraFor(s.camera);
        vo.viewFrom = &debug;
        drawFrame(o, s.background, &s.camera, submit, result);
    }
}

// The frame; `windowScale` scales a .tri scene's window-space coordinates (pixels) with the
// frame when supersampling, as 3D scenes scale through their projection.
RenderResult renderAtScale(State& st, const FrameSettings& o, float windowScale) {
    RenderResult result;
    if (st.voxel) {
        renderVoxelModel(st, o, result);
        return result;
    }
    if (st.kind != scene::FileKind::TriangleList) {
        render3d(st, o, result);
        return result;
    }
    scene::TriScene scaled;
    const scene::TriScene* s = &st.tri;
    if (windowScale != 1.0f) {
        scaled = st.tri;
        for (glm::vec3& p : scaled.positions) p *= windowScale;
        s = &scaled;
    }
    result.sceneTriangles = s->triangleCount();
    drawFrame(o, glm::vec4(0.0f), nullptr, [&](raster::Pipeline& p) { p.draw(s->drawCall()); }, result);
    return result;
}

// --supersample N: the frame at N x N times the pixels, each N x N block box-filtered into one
// pixel (summed in double): N² samples per pixel on a regular grid through the same pipeline, the
// ground truth of `cuberille accuracy` (256 samples at N = 16).
RenderResult renderSupersampled(State& st, const FrameSettings& o) {
    const int n = o.supersample;  // validate() bounded n times the size
    FrameSettings big = o;
    big.width *= n;
    big.height *= n;
    big.supersample = 1;
    RenderResult r = renderAtScale(st, big, float(n));
    raster::Image small;
    small.width = o.width;
    small.height = o.height;
    small.rgba.resize(size_t(o.width) * o.height * 4);
    raster::parallelFor(size_t(o.height), [&](size_t y) {
        for (int x = 0; x < o.width; ++x)
            for (int c = 0; c < 4; ++c) {
                double sum = 0.0;
                for (int j = 0; j < n; ++j)
                    for (int i = 0; i < n; ++i) sum += r.image.pixel(x * n + i, int(y) * n + j)[c];
                small.pixel(x, int(y))[c] = float(sum / double(n * n));
            }
    });
    r.image = std::move(small);
    return r;
}

}  // namespace

std::string statsJson(const std::string& sceneName, const FrameSettings& o, const RenderResult& r) {
    const raster::StageCounters& c = r.stats.counters;
    const raster::StageTimes& t = r.stats.times;
    nlohmann::json j;
    j["scene"] = sceneName;
    j["width"] = o.width;
    j["height"] = o.height;
    j["msaa"] = o.msaa;
    j["supersample"] = o.supersample;
    j["depth"] = o.depth == raster::DepthConvention::Reversed ? "reversed" : "standard";
    j["threads"] = r.threadsRan;  // that ran: TBB never runs more than the cores, whatever was asked
    j["threadsRequested"] = o.threads > 0 ? o.threads : raster::hardwareThreads();
    j["instructionSet"] = raster::activeInstructionSet();  // of the back end; the image is the same on each
    j["view"] = viewName(o.view);
    j["renderer"] = rendererName(o.renderer);
    j["projection"] = o.orthographic ? "orthographic" : "perspective";
    const FrameMemory memory = frameMemory(o);
    j["memory"] = {{"framebufferBytes", memory.framebufferBytes}, {"imageBytes", memory.imageBytes}};
    j["sceneTriangles"] = r.sceneTriangles;
    if (r.voxel) {
        const lod::VoxelFrameStats& v = *r.voxel;
        j["voxel"] = {{"modelResolution", r.voxelResolution},
                      {"blocksVisited", v.selection.blocksVisited},
                      {"frustumCulled", v.selection.frustumCulled},
                      {"occlusionCulled", v.occlusionCulled},
                      {"visibilityTests", v.visibilityTests},
                      {"voxelBlocksDrawn", v.voxelBlocksDrawn},
                      {"drawnPerLevel", v.selection.drawnPerLevel},
                      {"triangleBlocksDrawn", v.triangleBlocksDrawn},
                      {"hybridTriangles", v.hybridTriangles},
                      {"voxelsExpanded", v.voxelsExpanded},
                      {"facesEmitted", v.facesEmitted},
                      {"facesBetweenSamples", v.facesBetweenSamples},
                      {"facesBehindDepth", v.facesBehindDepth},
                      {"coveredPixels", v.coveredPixels},
                      {"facesPerCoveredPixel", v.facesPerCoveredPixel()},
                      {"selectMs", v.selectMs},
                      {"expandMs", v.expandMs}};
    }
    if (r.rayTraced) {
        const RayTracedFrameStats& rt = *r.rayTraced;
        j["primaryRays"] = {{"accel", accelName(rt.rays.accel)},
                            {"drawsTraced", rt.drawsTraced},
                            {"drawsRasterized", rt.drawsRasterized},
                            {"triangles", rt.rays.triangles},
                            {"rays", rt.rays.rays},
                            {"hits", rt.rays.hits},
                            {"trianglesSeen", rt.shade.trianglesSeen},
                            {"samplesWithoutSetUp", rt.shade.samplesWithoutSetUp},
                            {"gatherMs", rt.rays.gatherMs},
                            {"buildMs", rt.rays.buildMs},
                            {"bvhUpdated", rt.updated},
                            {"bvhRebuilt", rt.update.rebuilt},
                            {"traceMs", rt.rays.traceMs},
                            {"shadeMs", rt.shade.vertexMs + rt.shade.setupMs + rt.shade.shadeMs}};
    }
    if (r.shadows && o.renderer == Renderer::Raster && !r.shadedShadowStageVisibility)
        j["frameVisibility"] = {{"asked", frameVisibilityName(o.frameVisibility)}, {"from", "depth test"}};
    if (r.shadedShadowStageVisibility) {
        const raster::VisibilityShadeStats& v = *r.shadedShadowStageVisibility;
        j["frameVisibility"] = {{"asked", frameVisibilityName(o.frameVisibility)},
                                {"from", "shadow stage"},
                                {"trianglesSeen", v.trianglesSeen},
                                {"samplesWithoutSetUp", v.samplesWithoutSetUp},
                                {"shadeMs", v.vertexMs + v.setupMs + v.shadeMs}};
    }
    if (r.voxelRays) {
        const VoxelRayFrameStats& v = *r.voxelRays;
        const double rays = double(std::max<uint64_t>(v.rays, 1));
        j["voxelRays"] = {{"accel", rt::voxelStructureName(v.structure)},
                          {"level", v.level},
                          {"resolution", v.resolution},
                          {"voxels", v.voxels},
                          {"rays", v.rays},
                          {"hits", v.hits},
                          {"samplesInsideAVoxel", v.samplesInside},
                          {"facesSeen", v.facesSeen},
                          {"interiorNodesPerRay", double(v.counters.interiorSteps) / rays},
                          {"leavesPerRay", double(v.counters.leafSteps) / rays},
                          {"voxelTestsPerRay", double(v.counters.voxelTests) / rays},
                          {"gatherMs", v.gatherMs},
                          {"buildMs", v.buildMs},
                          {"shadowRays", v.shadowRays},
                          {"occlusionRays", v.occlusionRays},
                          {"occlusionDistance", v.occlusionDistance},
                          {"traceMs", v.traceMs},
                          {"lightMs", v.lightMs},
                          {"shadeMs", v.shadeMs}};
    }
    if (r.culling) {
        const FrustumCullStats& c = *r.culling;
        j["frustumCull"] = {{"trianglesIn", c.trianglesIn},
                            {"trianglesKept", c.trianglesKept},
                            {"nodesVisited", c.counters.nodesVisited},
                            {"subtreesAccepted", c.counters.subtreesAccepted},
                            {"subtreesRejected", c.counters.subtreesRejected},
                            {"bvhMs", c.buildMs},
                            {"degradation", c.degradation},
                            {"rebuilt", c.rebuilt},
                            {"cullMs", c.cullMs}};
    }
    if (r.shadows) {
        const ShadowFrameStats& sh = *r.shadows;
        const rt::ShadowStats& st = sh.shadows;
        j["shadows"] = {{"mode", shadowModeName(sh.mode)},
                        {"soft", sh.soft},
                        {"focus", mapFocusName(sh.focus)},
                        {"lightsShadowed", st.lightsShadowed},
                        {"casterTriangles", sh.casterTriangles},
                        {"receiverPixels", st.receiverPixels},
                        {"markedPixels", st.markedPixels},
                        {"markedShare", st.receiverPixels ? double(st.markedPixels) / double(st.receiverPixels) : 0.0},
                        {"raysTraced", st.raysTraced},
                        {"mapsDrawn", st.mapsDrawn},
                        {"mapsKept", st.mapsKept},
                        {"thinTriangles", st.thinTriangles},
                        {"accel", accelName(sh.accel)},
                        {"bvhBuildMs", sh.bvhBuildMs},
                        {"bvhShared", sh.bvhShared},
                        {"adjacencyMs", sh.adjacencyMs},
                        {"bvhUpdated", sh.bvhUpdated},
                        {"bvhRebuilt", sh.bvhRebuilt},
                        {"degradation", sh.degradation},
                        {"bvhUpdateMs", sh.bvhUpdateMs},
                        {"castersMs", sh.castersMs},
                        {"surfacesMs", sh.surfacesMs},
                        {"centreRays", sh.centreRays},
                        {"mapMs", st.mapMs},
                        {"maskMs", st.maskMs},
                        {"totalMs", sh.totalMs}};
        if (sh.occlusion.raysPerPixel > 0)
            j["ambientOcclusion"] = {{"raysPerPixel", sh.occlusion.raysPerPixel},
                                     {"distance", sh.occlusion.distance},
                                     {"pixels", sh.occlusion.pixels},
                                     {"rays", sh.occlusion.rays},
                                     {"ms", sh.occlusion.ms}};
        if (sh.mode == rt::ShadowMode::Auto)
            j["shadows"]["auto"] = {{"hybridLights", st.autoHybrid},
                                    {"raytracedLights", st.autoRayTraced},
                                    {"predictedHybridMs", st.predictedHybridMs},
                                    {"predictedRaytracedMs", st.predictedRayTracedMs},
                                    {"tookMs", st.mapMs + st.maskMs}};
    }
    j["stages"] = {
        {"vertex", {{"verticesShaded", c.verticesShaded}, {"ms", t.vertexMs}}},
        {"clip",
         {{"trianglesIn", c.trianglesIn},
          {"invalid", c.trianglesInvalid},
          {"rejected", c.trianglesClipRejected},
          {"clipped", c.trianglesClipped},
          {"clippedTrianglesOut", c.clippedTrianglesOut}}},
        {"setup",
         {{"degenerate", c.trianglesDegenerate},
          {"culled", c.trianglesCulled},
          {"noSamples", c.trianglesNoSamples},
          {"setUp", c.trianglesSetUp}}},
        {"bin", {{"binEntries", c.binEntries}, {"flushes", r.stats.flushes}}},
        {"coarse",
         {{"smallTriangleEntries", c.smallTriangleEntries},
          {"blocksEmpty", c.blocksEmpty},
          {"blocksPartial", c.blocksPartial},
          {"blocksFull", c.blocksFull},
          {"blocksDepthCulled", c.blocksDepthCulled}}},
        {"depth", {{"samplesTested", c.samplesTested}, {"samplesPassed", c.samplesPassed}}},
        {"shade",
         {{"pixelsShaded", c.pixelsShaded},
          {"varyingsInterpolated", c.varyingsInterpolated},
          {"textureSamples", c.textureSamples},
          {"lightEvaluations", c.lightEvaluations},
          {"specularGlossinessPixels", c.specularGlossinessPixels},
          {"dielectricSpecularPixels", c.dielectricSpecularPixels},
          {"clearcoatPixels", c.clearcoatPixels},
          {"sheenPixels", c.sheenPixels},
          {"transmissionPixels", c.transmissionPixels},
          {"environmentPixels", c.environmentPixels}}},
        {"outputMerge", {{"pixelsAlphaTested", c.pixelsAlphaTested}, {"pixelsBlended", c.pixelsBlended}}},
    };
    j["load"] = {{"verticesSkinned", r.load.verticesSkinned},
                 {"verticesMorphed", r.load.verticesMorphed},
                 {"texturesDecoded", r.load.texturesDecoded}};
    j["timesMs"] = {{"load", r.loadMs},         {"vertex", t.vertexMs},
                    {"frontEnd", t.frontEndMs}, {"backEnd", t.backEndMs},
                    {"resolve", t.resolveMs},   {"frame", t.frameMs}};
    j["occlusionSamplesPassed"] = r.stats.occlusionSamplesPassed;
    return j.dump();
}

}  // namespace cuberille::render
