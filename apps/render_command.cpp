#include "apps/render_command.h"


#include <glm/gtc/matrix_transform.hpp>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <unordered_map>

#include "raster/clock.h"
#include "apps/atomic_file.h"
#include "apps/image_io.h"
#include "raster/parallel.h"
#include "raster/pipeline.h"
#include "raster/sample_pattern.h"
#include "raster/instruction_set.h"
#include "raster/srgb.h"
#include "raster/texture.h"
#include "scene/input_error.h"
#include "scene/model_scene.h"
#include "scene/procedural.h"
#include "scene/tri_scene.h"
#include "voxel/cvox_file.h"
#include "scene/file_names.h"

namespace cuberille::apps {
namespace {

void validate(const RenderOptions& o) {
    using scene::InputError;
    validateFrameOptions(o.width, o.height, o.msaa, o.threads);
    if (!(o.detail > 0.0f && o.detail <= 16.0f)) throw InputError("--detail: must be in (0, 16]");
    if (!std::isfinite(o.timeSeconds)) throw InputError("--time: must be a finite number of seconds");
    const rt::ShadowOptions& sh = o.shadows;
    if (sh.mapSizeTexels < 16 || sh.mapSizeTexels > 16384)
        throw InputError("--shadow-map-size: " + std::to_string(sh.mapSizeTexels) + " is outside 16..16384");
    if (sh.softSamplesPerSide < 1 || sh.softSamplesPerSide > 16)
        throw InputError("--soft-samples: " + std::to_string(sh.softSamplesPerSide) + " is outside 1..16 (rays per side)");
    if (!(sh.lightRadius >= 0.0f) || !std::isfinite(sh.lightRadius))
        throw InputError("--light-radius: must be a finite number, 0 or more");
    const scene::FileKind kind = scene::fileKindOf(o.scene);
    const bool threeD = kind != scene::FileKind::TriangleList && kind != scene::FileKind::VoxelModel;
    if ((sh.mode != rt::ShadowMode::None || o.view == View::ShadowPixels) && !threeD)
        throw InputError("--shadows and --view shadow-pixels: only for 3D scenes (glTF, PLY, OBJ, built-in), not " + o.scene);
    if (o.view == View::ShadowPixels && sh.mode == rt::ShadowMode::None)
        throw InputError("--view shadow-pixels: needs --shadows map, hybrid or raytraced");
    if (o.frustumCull && !threeD) throw InputError("--frustum-cull: only for 3D scenes (glTF, PLY, OBJ, built-in), not " + o.scene);
    if (o.animate < 0 || o.animate > 3600) throw InputError("--animate: 0 to 3600 frames");
    if (o.animate > 0 && !scene::isGltfKind(kind))
        throw InputError("--animate: only for glTF files (.gltf, .glb), not " + o.scene);
    if (o.animate > 0 && o.turntable > 0) throw InputError("--animate and --turntable: one or the other");
    if (o.placement && !threeD) throw InputError("--eye: only for 3D scenes (glTF, PLY, OBJ, built-in), not " + o.scene);
    if (o.placement && o.cameraIndex >= 0) throw InputError("--eye and --camera-index: one camera or the other");
    if (o.placement && !(o.placement->verticalFovDegrees >= 0.0f && o.placement->verticalFovDegrees < 180.0f))
        throw InputError("--fov: degrees in (0, 180)");
    if (o.placement) {
        const glm::vec3 forward = o.placement->target.value_or(glm::vec3(0.0f)) - o.placement->eye;
        const glm::vec3 up = o.placement->up.value_or(glm::vec3(0.0f, 1.0f, 0.0f));
        if (o.placement->target && !(glm::length(forward) > 0.0f)) throw InputError("--target: must differ from --eye");
        if (!(glm::length(up) > 0.0f)) throw InputError("--up: must not be zero");
    }
    if (o.zUp && !scene::isModelFile(o.scene)) throw InputError("--up-axis: only for mesh files (PLY, OBJ, glTF), not " + o.scene);
    // An option a scene cannot use is refused, not silently ignored: only glTF animates.
    if (o.timeSeconds != 0.0f && !scene::isGltfKind(kind))
        throw InputError("--time: only glTF files (.gltf, .glb) have animations, not " + o.scene);
    if (!(o.fps > 0.0f && o.fps <= 1000.0f)) throw InputError("--fps: must be in (0, 1000]");
    if (!(o.zoom > 0.0f && o.zoom <= 1000.0f)) throw InputError("--zoom: must be in (0, 1000]");
    if (o.zoom != 1.0f && kind == scene::FileKind::TriangleList) throw InputError("--zoom: not for 2D .tri scenes");
    if (!o.animation.empty() && !scene::isGltfKind(kind))
        throw InputError("--animation: only glTF files (.gltf, .glb) have animations, not " + o.scene);
}

raster::FramebufferDesc frameDesc(const RenderOptions& o, glm::vec4 background) {
    raster::FramebufferDesc d;
    d.widthPixels = o.width;
    d.heightPixels = o.height;
    d.samples = o.msaa;
    d.depthConvention = o.depth;
    d.clearColor = background;
    d.recordOverdraw = o.view == View::Overdraw;
    d.recordBlockClasses = o.view == View::Tiles;
    return d;
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
        case View::ShadowPixels: raster::resolveColor(p.framebuffer(), image); break;
        case View::Depth:
            if (camera) raster::resolveViewDistance(p.framebuffer(), camera->nearPlane, camera->farPlane, image);
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

const char* viewName(View v) {
    switch (v) {
        case View::Color: return "color";
        case View::Depth: return "depth";
        case View::Tiles: return "tiles";
        case View::Overdraw: return "overdraw";
        case View::Lod: return "lod";
        case View::Visibility: return "visibility";
        case View::ShadowPixels: return "shadow-pixels";
    }
    return "?";
}

}  // namespace

void validateFrameOptions(int width, int height, int msaa, int threads) {
    using scene::InputError;
    if (width < 1 || height < 1 || width > raster::kMaxFramebufferPixels || height > raster::kMaxFramebufferPixels)
        throw InputError("--width/--height: " + std::to_string(width) + "x" + std::to_string(height) +
                         " is outside 1.." + std::to_string(raster::kMaxFramebufferPixels));
    if (!raster::isSupportedSampleCount(msaa))
        throw InputError("--msaa: " + std::to_string(msaa) + " is not 1, 2, 4, 8 or 16");
    if (threads < 0) throw InputError("--threads: must be 0 (all cores) or more");
}

glm::vec4 clearColorFor(const glm::vec4& display) {
    const float a = display.a;
    return {float(raster::decodeSrgb(display.r)) * a, float(raster::decodeSrgb(display.g)) * a,
            float(raster::decodeSrgb(display.b)) * a, a};
}

raster::Image legibleDepth(const raster::Image& distances) {
    float nearest = std::numeric_limits<float>::infinity(), farthest = 0.0f;
    for (size_t i = 0; i < distances.rgba.size() / 4; ++i)
        if (distances.rgba[i * 4 + 3] > 0.0f) {
            nearest = std::min(nearest, distances.rgba[i * 4]);
            farthest = std::max(farthest, distances.rgba[i * 4]);
        }
    raster::Image out = distances;
    const float span = farthest > nearest ? farthest - nearest : 1.0f;
    for (size_t i = 0; i < out.rgba.size() / 4; ++i) {
        const bool covered = distances.rgba[i * 4 + 3] > 0.0f;
        // Evenly spaced in the file's codes: the grey is chosen as a display value, then decoded
        // to the linear value the sRGB encoding turns back into it.
        const double grey = covered ? kNearestGrey - (kNearestGrey - kFarthestGrey) * (distances.rgba[i * 4] - nearest) / span : 0.0;
        const float linear = float(raster::decodeSrgb(grey));
        for (int c = 0; c < 3; ++c) out.rgba[i * 4 + c] = linear;
        out.rgba[i * 4 + 3] = 1.0f;
    }
    return out;
}

ImageWriteOptions imageWriteOptions(const RenderOptions& o) {
    ImageWriteOptions w;
    w.alpha = o.background && o.background->a < 1.0f;
    w.pngBits = o.pngBits;
    return w;
}

glm::vec4 parseBackground(const std::string& text) {
    const std::string problem = "--background " + text + ": expected R,G,B or R,G,B,A, each in [0, 1]";
    std::vector<std::string> parts;
    for (size_t start = 0;;) {
        const size_t end = std::min(text.find(',', start), text.size());
        parts.push_back(text.substr(start, end - start));
        if (end == text.size()) break;
        start = end + 1;
    }
    if (parts.size() != 3 && parts.size() != 4) throw scene::InputError(problem);
    glm::vec4 v(0.0f, 0.0f, 0.0f, 1.0f);
    for (size_t k = 0; k < parts.size(); ++k) {
        const char* first = parts[k].data();
        const auto [last, ec] = std::from_chars(first, first + parts[k].size(), v[int(k)]);
        if (ec != std::errc() || last != first + parts[k].size() || !(v[int(k)] >= 0.0f && v[int(k)] <= 1.0f))
            throw scene::InputError(problem);
    }
    return v;
}

glm::vec3 parseVector3(const std::string& text, const std::string& option) {
    glm::vec3 v(0.0f);
    size_t start = 0;
    for (int k = 0; k < 3; ++k) {
        const size_t end = k < 2 ? text.find(',', start) : text.size();
        if (end == std::string::npos) break;
        const std::string part = text.substr(start, end - start);
        const char* first = part.data();
        const auto [last, ec] = std::from_chars(first, first + part.size(), v[k]);
        if (ec != std::errc() || last != first + part.size() || !std::isfinite(v[k]))
            throw scene::InputError(option + " " + text + ": expected three numbers X,Y,Z");
        if (k == 2) return v;
        start = end + 1;
    }
    throw scene::InputError(option + " " + text + ": expected three numbers X,Y,Z");
}

View parseView(const std::string& name) {
    if (name == "color") return View::Color;
    if (name == "depth") return View::Depth;
    if (name == "tiles") return View::Tiles;
    if (name == "overdraw") return View::Overdraw;
    if (name == "lod") return View::Lod;
    if (name == "visibility") return View::Visibility;
    if (name == "shadow-pixels") return View::ShadowPixels;
    throw scene::InputError("--view: '" + name + "' is not color, depth, tiles, overdraw, lod, visibility or shadow-pixels");
}

TextureFilterOverride parseTextureFilter(const std::string& name) {
    if (name == "file") return TextureFilterOverride::File;
    if (name == "nearest") return TextureFilterOverride::Nearest;
    if (name == "bilinear") return TextureFilterOverride::Bilinear;
    if (name == "trilinear") return TextureFilterOverride::Trilinear;
    throw scene::InputError("--texture-filter: '" + name + "' is not file, nearest, bilinear or trilinear");
}

raster::DepthConvention parseDepthConvention(const std::string& name) {
    if (name == "standard") return raster::DepthConvention::Standard;
    if (name == "reversed") return raster::DepthConvention::Reversed;
    throw scene::InputError("--depth: '" + name + "' is not standard or reversed");
}

rt::BvhUpdateMethod parseBvhUpdate(const std::string& name) {
    if (name == "refit") return rt::BvhUpdateMethod::Refit;
    if (name == "lazy") return rt::BvhUpdateMethod::Lazy;
    if (name == "rebuild") return rt::BvhUpdateMethod::Rebuild;
    throw scene::InputError("--bvh-update: '" + name + "' is not refit, lazy or rebuild");
}

const char* textureFilterName(TextureFilterOverride f) {
    switch (f) {
        case TextureFilterOverride::File: return "file";
        case TextureFilterOverride::Nearest: return "nearest";
        case TextureFilterOverride::Bilinear: return "bilinear";
        case TextureFilterOverride::Trilinear: return "trilinear";
    }
    return "?";
}

namespace {

bool isTriFile(const RenderOptions& o) { return scene::fileKindOf(o.scene) == scene::FileKind::TriangleList; }
bool isVoxelFile(const RenderOptions& o) { return scene::fileKindOf(o.scene) == scene::FileKind::VoxelModel; }


void overrideTextureFilters(scene::Scene& s, TextureFilterOverride which);

// --zoom F: a lens zoom. The eye stays and the field of view narrows until what it saw is F
// times larger (tan of the half-angle divided by F), whichever camera framed the scene.
void applyZoom(scene::Camera& camera, float zoom) {
    if (zoom == 1.0f) return;
    const double halfAngle = std::atan(std::tan(glm::radians(double(camera.verticalFovDegrees)) / 2.0) / zoom);
    camera.verticalFovDegrees = float(glm::degrees(2.0 * halfAngle));
}

scene::Scene loadScene(const RenderOptions& o) {
    if (scene::isProceduralScene(o.scene)) {
        scene::Scene s = scene::makeProceduralScene(o.scene, o.detail);
        if (o.placement) {
            const scene::Bounds b = scene::boundsOf(s.meshes);
            s.camera = scene::placeCamera(*o.placement, s.camera, b.min, b.max);
        }
        return s;
    }
    if (scene::isModelFile(o.scene))
        return scene::loadModelScene(o.scene, {o.azimuth, o.elevation, o.cameraIndex, o.timeSeconds, o.zUp, o.placement, o.animation},
                                     [&](const std::string& w) {
                                         if (!o.quiet) std::fprintf(stderr, "cuberille: warning: %s\n", w.c_str());
                                     });
    std::string builtIn;
    for (const std::string& name : scene::proceduralSceneNames()) builtIn += (builtIn.empty() ? "" : ", ") + name;
    throw scene::InputError("'" + o.scene + "' is not a scene: expected a .tri, .ply, .ply.gz, .obj, .gltf, .glb or .cvox "
                            "file, or a built-in scene (" + builtIn + ")");
}

// Built-in or mesh-file scenes: everything but .tri, with the accuracy knobs that change the
// scene rather than the frame (--texture-filter, --depth).
scene::Scene load3dScene(const RenderOptions& o) {
    scene::Scene s = loadScene(o);
    overrideTextureFilters(s, o.textureFilter);
    s.camera.reversedDepth = o.depth == raster::DepthConvention::Reversed;
    applyZoom(s.camera, o.zoom);
    return s;
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
        for (scene::MeshTexture* slot : {&t.baseColor, &t.metallicRoughness, &t.normal, &t.occlusion, &t.emissive})
            retarget(*slot);
    }
}

// One frame: submit(pipeline) records the draws, whose arrays stay alive until endFrame
// (Pipeline::draw's contract), then the view is resolved.
template <class Submit>
void renderFrame(const RenderOptions& o, glm::vec4 sceneBackground, const scene::Camera* camera, Submit&& submit,
                 RenderResult& result) {
    raster::Pipeline pipeline;
    pipeline.beginFrame(frameDesc(o, o.background ? clearColorFor(*o.background) : sceneBackground));
    submit(pipeline);
    pipeline.endFrame();
    result.stats = pipeline.stats();
    finishView(pipeline, o.view, camera, result.image, result.stats.times.resolveMs);
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

// A 3D scene's frame: the shadow stage first when asked for (its masks go to the shade stage
// with the lights), then the draws.
void renderFrame(scene::Scene& s, const RenderOptions& o, SceneFrustumCull* culling, SceneShadows* shadows,
                 RenderResult& result) {
    result.sceneTriangles = s.triangleCount();
    // Shadows first: casters outside the view still cast into it (the shadow stage keeps its own
    // copy of every caster), then the frustum cull trims what the frame draws.
    std::optional<raster::Lighting> shadowed;
    if (shadows) {
        result.shadows.emplace();
        const double t0 = raster::nowMs();
        if (shadows->active()) shadowed = shadows->run(s, o.width, o.height, *result.shadows);
        result.shadows->totalMs = raster::nowMs() - t0;
    }
    if (culling) result.culling = culling->cull(s, float(o.width) / float(o.height));
    renderFrame(o, s.background, &s.camera, [&](raster::Pipeline& p) {
        s.draw(p, float(o.width) / float(o.height), shadowed ? &*shadowed : nullptr);
    }, result);
    if (o.view == View::ShadowPixels) showShadowPixels(shadows->markedPixels(), result.image);
}

// The camera turned about the world's up axis through its target.
scene::Camera orbit(const scene::Camera& c, float degrees) {
    const glm::mat3 turn(glm::rotate(glm::mat4(1.0f), glm::radians(degrees), glm::vec3(0, 1, 0)));
    scene::Camera r = c;
    r.position = c.target + turn * (c.position - c.target);
    r.up = turn * c.up;
    return r;
}

std::filesystem::path frameFileName(const std::filesystem::path& out, int frame) {
    char suffix[16];
    std::snprintf(suffix, sizeof suffix, "_%03d", frame);
    return out.parent_path() / (out.stem().string() + suffix + out.extension().string());
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

/// A voxel model: blocks selected, expanded and drawn through the same pipeline.
void renderVoxelModel(const RenderOptions& o, RenderResult& result) {
    const double t0 = raster::nowMs();
    voxel::VoxelModel model = voxel::readCvox(o.scene);
    if (model.blocks.empty()) throw scene::InputError(o.scene + ": no voxels to draw (a model of no blocks)");
    lod::VoxelScene s(std::move(model), o.azimuth, o.elevation);
    s.camera.reversedDepth = o.depth == raster::DepthConvention::Reversed;
    applyZoom(s.camera, o.zoom);
    result.loadMs = raster::nowMs() - t0;
    result.sceneTriangles = s.model().triangleCount();
    result.voxelResolution = s.model().grid.resolution;
    lod::VoxelRenderOptions vo;
    vo.selection.pixelError = o.pixelError;
    vo.selection.finestLevel = finestLevelFor(s.model(), o.voxelResolution);
    vo.selection.hybrid = !o.noHybrid;
    vo.coloring = o.view == View::Lod          ? lod::BlockColoring::Level
                  : o.view == View::Visibility ? lod::BlockColoring::Visibility
                                               : lod::BlockColoring::Model;
    vo.occlusion = !o.noOcclusion;
    // Occlusion culling learns from the frame before: the warm-up frames give it that history
    // (the image is the same with or without it; only the work differs).
    const int frames = vo.occlusion ? 1 + o.warmup : 1;
    for (int f = 0; f < frames; ++f) {
        renderFrame(o, s.background, &s.camera, [&](raster::Pipeline& p) { result.voxel = s.draw(p, o.width, o.height, vo); },
                    result);
        s.readOcclusion(result.stats);
    }
    if (o.debugCamera) {  // what the main camera's frame selected, seen from its side
        const scene::Camera debug = lod::debugCameraFor(s.camera);
        vo.viewFrom = &debug;
        renderFrame(o, s.background, &s.camera, [&](raster::Pipeline& p) { result.voxel = s.draw(p, o.width, o.height, vo); },
                    result);
    }
}

// The frame; `windowScale` scales a .tri scene's window-space coordinates (pixels) with the
// frame when supersampling, as 3D scenes scale through their projection.
RenderResult renderAtScale(const RenderOptions& o, float windowScale) {
    validate(o);
    raster::ThreadLimit threadLimit(o.threads);
    RenderResult result;
    if ((o.view == View::Lod || o.view == View::Visibility || o.debugCamera) && !isVoxelFile(o))
        throw scene::InputError("--view lod, --view visibility and --debug-camera: only for voxel models (.cvox)");
    if (!(o.pixelError >= 0.0f)) throw scene::InputError("--pixel-error: must be 0 or more");
    if (o.warmup < 0 || o.warmup > 100) throw scene::InputError("--warmup: must be 0 to 100 frames");
    if (isVoxelFile(o)) {
        renderVoxelModel(o, result);
        return result;
    }
    const double t0 = raster::nowMs();
    if (!isTriFile(o)) {
        scene::Scene s = load3dScene(o);
        result.loadMs = raster::nowMs() - t0;
        result.load = s.loadStats;
        std::optional<SceneShadows> shadows;
        if (o.shadows.mode != rt::ShadowMode::None) shadows.emplace(s, o.shadows);
        std::optional<SceneFrustumCull> culling;
        if (o.frustumCull) culling.emplace(s);
        renderFrame(s, o, culling ? &*culling : nullptr, shadows ? &*shadows : nullptr, result);
        return result;
    }
    scene::TriScene s = scene::loadTriScene(o.scene);
    if (s.positions.empty()) throw scene::InputError(o.scene + ": no triangles to draw (no triangle lines)");
    for (glm::vec3& p : s.positions) p *= windowScale;
    result.loadMs = raster::nowMs() - t0;
    result.sceneTriangles = s.triangleCount();
    renderFrame(o, glm::vec4(0.0f), nullptr, [&](raster::Pipeline& p) { p.draw(s.drawCall()); }, result);
    return result;
}

// --supersample N: the frame at N x N times the pixels, each N x N block box-filtered into one
// pixel (summed in double): N² samples per pixel on a regular grid through the same pipeline, the
// ground truth of `cuberille accuracy` (256 samples at N = 16).
RenderResult renderSupersampled(const RenderOptions& o) {
    validate(o);
    if (o.view != View::Color) throw scene::InputError("--supersample: only with --view color");
    const int n = o.supersample;
    if (int64_t(o.width) * n > raster::kMaxFramebufferPixels || int64_t(o.height) * n > raster::kMaxFramebufferPixels)
        throw scene::InputError("--supersample: " + std::to_string(o.width) + "x" + std::to_string(o.height) + " times " +
                                std::to_string(n) + " exceeds " + std::to_string(raster::kMaxFramebufferPixels) + " pixels a side");
    RenderOptions big = o;
    big.width *= n;
    big.height *= n;
    big.supersample = 1;
    RenderResult r = renderAtScale(big, float(n));
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

RenderResult renderScene(const RenderOptions& o) {
    if (o.supersample < 1 || o.supersample > 16) throw scene::InputError("--supersample: must be 1 to 16");
    raster::resetThreadsThatRan();
    RenderResult r = o.supersample > 1 ? renderSupersampled(o) : renderAtScale(o, 1.0f);
    r.threadsRan = raster::threadsThatRan();
    return r;
}

nlohmann::json statsToJson(const RenderOptions& o, const RenderResult& r) {
    const raster::StageCounters& c = r.stats.counters;
    const raster::StageTimes& t = r.stats.times;
    nlohmann::json j;
    j["scene"] = o.scene;
    j["width"] = o.width;
    j["height"] = o.height;
    j["msaa"] = o.msaa;
    j["supersample"] = o.supersample;
    j["depth"] = o.depth == raster::DepthConvention::Reversed ? "reversed" : "standard";
    j["threads"] = r.threadsRan;  // that ran: TBB never runs more than the cores, whatever was asked
    j["threadsRequested"] = o.threads > 0 ? o.threads : raster::hardwareThreads();
    j["instructionSet"] = raster::activeInstructionSet();  // of the back end; the image is the same on each
    j["view"] = viewName(o.view);
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
                      {"selectMs", v.selectMs},
                      {"expandMs", v.expandMs}};
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
                        {"lightsShadowed", st.lightsShadowed},
                        {"casterTriangles", sh.casterTriangles},
                        {"receiverPixels", st.receiverPixels},
                        {"markedPixels", st.markedPixels},
                        {"markedShare", st.receiverPixels ? double(st.markedPixels) / double(st.receiverPixels) : 0.0},
                        {"raysTraced", st.raysTraced},
                        {"thinTriangles", st.thinTriangles},
                        {"bvhBuildMs", sh.bvhBuildMs},
                        {"adjacencyMs", sh.adjacencyMs},
                        {"bvhUpdated", sh.bvhUpdated},
                        {"bvhRebuilt", sh.bvhRebuilt},
                        {"degradation", sh.degradation},
                        {"bvhUpdateMs", sh.bvhUpdateMs},
                        {"castersMs", sh.castersMs},
                        {"surfacesMs", sh.surfacesMs},
                        {"mapMs", st.mapMs},
                        {"maskMs", st.maskMs},
                        {"totalMs", sh.totalMs}};
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
          {"lightEvaluations", c.lightEvaluations}}},
        {"outputMerge", {{"pixelsAlphaTested", c.pixelsAlphaTested}, {"pixelsBlended", c.pixelsBlended}}},
    };
    j["load"] = {{"verticesSkinned", r.load.verticesSkinned},
                 {"verticesMorphed", r.load.verticesMorphed},
                 {"texturesDecoded", r.load.texturesDecoded}};
    j["timesMs"] = {{"load", r.loadMs},         {"vertex", t.vertexMs},
                    {"frontEnd", t.frontEndMs}, {"backEnd", t.backEndMs},
                    {"resolve", t.resolveMs},   {"frame", t.frameMs}};
    j["occlusionSamplesPassed"] = r.stats.occlusionSamplesPassed;
    return j;
}

void printSummary(const RenderOptions& o, const std::filesystem::path& file, const RenderResult& r) {
    const raster::StageCounters& c = r.stats.counters;
    const int samplesPerPixel = o.msaa * o.supersample * o.supersample;
    std::printf("wrote %s (%dx%d, %d sample%s%s, view %s)\n", file.c_str(), o.width, o.height, samplesPerPixel,
                samplesPerPixel > 1 ? "s" : "", o.supersample > 1 ? " by supersampling" : "", viewName(o.view));
    // Times that add up: the drawn frame's stages plus what ran between them (flush
    // orchestration, clears), then the resolve into the image, which runs after the frame.
    const raster::StageTimes& t = r.stats.times;
    const double other = std::max(0.0, t.frameMs - t.vertexMs - t.frontEndMs - t.backEndMs);
    // A voxel model's frame draws the faces and source triangles its blocks chose, not the
    // model's source triangle count.
    std::printf(" ");
    if (r.voxel)
        std::printf(" %llu voxel faces and %llu source triangles drawn,", (unsigned long long)r.voxel->facesEmitted,
                    (unsigned long long)r.voxel->hybridTriangles);
    std::printf(" %llu triangles in, %llu set up, %llu culled, %llu clipped; %.1f ms = frame %.1f "
                "(vertex %.1f, front end %.1f, back end %.1f, other %.1f) + resolve %.1f\n",
                (unsigned long long)(r.voxel ? c.trianglesIn : r.sceneTriangles),
                (unsigned long long)c.trianglesSetUp,
                (unsigned long long)(c.trianglesCulled + c.trianglesClipRejected),
                (unsigned long long)c.trianglesClipped, t.frameMs + t.resolveMs, t.frameMs, t.vertexMs,
                t.frontEndMs, t.backEndMs, other, t.resolveMs);
    std::printf("  blocks: %llu full, %llu partial, %llu hidden by hierarchical Z; %llu samples passed "
                "depth, %llu pixels shaded\n",
                (unsigned long long)c.blocksFull, (unsigned long long)c.blocksPartial,
                (unsigned long long)c.blocksDepthCulled, (unsigned long long)c.samplesPassed,
                (unsigned long long)c.pixelsShaded);
    std::printf("  effects: %llu texture samples, %llu light evaluations, %llu pixels alpha-tested, %llu blended\n",
                (unsigned long long)c.textureSamples, (unsigned long long)c.lightEvaluations,
                (unsigned long long)c.pixelsAlphaTested, (unsigned long long)c.pixelsBlended);
    if (r.culling) {
        const FrustumCullStats& c = *r.culling;
        std::printf("  frustum cull: %llu of %llu triangles kept, %llu nodes visited; %.1f ms (bvh %s %.1f, "
                    "degradation %.3f)\n",
                    (unsigned long long)c.trianglesKept, (unsigned long long)c.trianglesIn,
                    (unsigned long long)c.counters.nodesVisited, c.cullMs, c.rebuilt ? "build" : "refit", c.buildMs,
                    c.degradation);
    }
    if (r.shadows) {
        const rt::ShadowStats& st = r.shadows->shadows;
        std::printf("  shadows (%s%s): %d light%s, %llu receiver pixels, %llu marked (%.2f%%), %llu rays; %.1f ms "
                    "(bvh %.1f, surfaces %.1f, maps %.1f, masks %.1f)\n",
                    shadowModeName(r.shadows->mode), r.shadows->soft ? ", soft" : "", st.lightsShadowed,
                    st.lightsShadowed == 1 ? "" : "s", (unsigned long long)st.receiverPixels,
                    (unsigned long long)st.markedPixels,
                    st.receiverPixels ? 100.0 * double(st.markedPixels) / double(st.receiverPixels) : 0.0,
                    (unsigned long long)st.raysTraced, r.shadows->totalMs, r.shadows->bvhBuildMs, r.shadows->surfacesMs,
                    st.mapMs, st.maskMs);
        if (r.shadows->bvhUpdated)
            std::printf("  shadow casters moved: bvh %s in %.1f ms, degradation %.3f\n", r.shadows->bvhRebuilt ? "rebuilt" : "refitted",
                        r.shadows->bvhUpdateMs, r.shadows->degradation);
    }
}

int runTurntable(const RenderOptions& o);
int runAnimation(const RenderOptions& o);

// The depth view of a 3D scene holds distances: EXR keeps them, 8-bit files get them legible.
raster::Image imageToWrite(const RenderOptions& o, const std::filesystem::path& file, const raster::Image& image) {
    if (o.view == View::Depth && !isTriFile(o) && imageFormatFor(file) != ImageFormat::Exr) return legibleDepth(image);
    return image;
}

int runRenderCommand(const RenderOptions& o) {
    if (o.out.empty()) throw scene::InputError("--out: an output file is required (.png, .exr or .jpg)");
    // Refuse what cannot be written before any work: a bad extension, alpha in a JPEG.
    const ImageFormat format = imageFormatFor(o.out);
    if (format == ImageFormat::Jpeg && imageWriteOptions(o).alpha)
        throw scene::InputError("--background: an opacity below 1 needs a .png or .exr output (JPEG has no alpha)");
    if (o.pngBits != 8 && o.pngBits != 16) throw scene::InputError("--png-bits: 8 or 16");
    if (o.pngBits != 8 && format != ImageFormat::Png)
        throw scene::InputError("--png-bits: only for .png outputs");
    requireOutputPath(o.out, "--out");
    requireOutputPath(o.statsPath, "--stats");
    if (o.supersample > 1 && (o.turntable > 0 || o.animate > 0))
        throw scene::InputError("--supersample: not with --turntable or --animate (each frame would be rendered without it)");
    if (o.turntable > 0 && isVoxelFile(o)) throw scene::InputError("--turntable: not for voxel models yet");
    if (o.turntable > 0) return runTurntable(o);
    if (o.animate > 0) return runAnimation(o);
    const RenderResult r = renderScene(o);
    writeImageAtomically(o.out, imageToWrite(o, o.out, r.image), imageWriteOptions(o));
    if (!o.statsPath.empty()) writeJsonAtomically(o.statsPath, statsToJson(o, r));
    if (!o.quiet) printSummary(o, o.out, r);
    return 0;
}

// Frame `index` of a sequence: OUT_00i.ext, its stats kept for {"frames": [...]}, its summary.
void writeSequenceFrame(const RenderOptions& o, int index, const RenderResult& r, nlohmann::json& frames) {
    const std::filesystem::path file = frameFileName(o.out, index);
    writeImageAtomically(file, imageToWrite(o, file, r.image), imageWriteOptions(o));
    if (!o.statsPath.empty()) frames.push_back(statsToJson(o, r));
    if (!o.quiet) printSummary(o, file, r);
}

// --turntable N: the scene is loaded once, then N frames go around it, the camera turned about
// the world's up axis by 360/N degrees a frame; files are named OUT_000.ext, OUT_001.ext, ...
int runTurntable(const RenderOptions& o) {
    if (isTriFile(o)) throw scene::InputError("--turntable: " + o.scene + " is a 2D .tri scene");
    if (o.turntable > 3600) throw scene::InputError("--turntable: at most 3600 frames");
    validate(o);
    raster::ThreadLimit threadLimit(o.threads);
    const double t0 = raster::nowMs();
    scene::Scene s = load3dScene(o);
    const double loadMs = raster::nowMs() - t0;
    const scene::Camera start = s.camera;
    std::optional<SceneShadows> shadows;
    if (o.shadows.mode != rt::ShadowMode::None) shadows.emplace(s, o.shadows);
    std::optional<SceneFrustumCull> culling;
    const std::vector<scene::Mesh> uncut = o.frustumCull ? s.meshes : std::vector<scene::Mesh>{};
    if (o.frustumCull) culling.emplace(s);
    nlohmann::json frames = nlohmann::json::array();
    for (int i = 0; i < o.turntable; ++i) {
        s.camera = orbit(start, 360.0f * float(i) / float(o.turntable));
        RenderResult r;
        r.loadMs = i == 0 ? loadMs : 0.0;
        r.load = s.loadStats;
        if (culling)  // each frame culls from the whole scene again
            for (size_t m = 0; m < s.meshes.size(); ++m) s.meshes[m].indices = uncut[m].indices;
        raster::resetThreadsThatRan();
        renderFrame(s, o, culling ? &*culling : nullptr, shadows ? &*shadows : nullptr, r);
        r.threadsRan = raster::threadsThatRan();
        writeSequenceFrame(o, i, r, frames);
    }
    if (!o.statsPath.empty()) writeJsonAtomically(o.statsPath, {{"frames", frames}});
    return 0;
}

// --animate N: frame i poses the animation (--animation) at --time + i / --fps and is written as
// OUT_00i.ext. The glTF loader poses at load, so each frame loads the file again; the frustum
// cull's hierarchy and the shadow stage's are built on the first pose and refitted to each next
// one (rebuilt when Lauterbach's criterion fires), which --stats reports per frame.
int runAnimation(const RenderOptions& o) {
    validate(o);
    raster::ThreadLimit threadLimit(o.threads);
    std::optional<SceneFrustumCull> culling;
    std::optional<SceneShadows> shadows;
    nlohmann::json frames = nlohmann::json::array();
    for (int i = 0; i < o.animate; ++i) {
        RenderOptions frame = o;
        frame.timeSeconds = o.timeSeconds + float(i) / o.fps;
        const double t0 = raster::nowMs();
        scene::Scene s = load3dScene(frame);
        RenderResult r;
        r.loadMs = raster::nowMs() - t0;
        r.load = s.loadStats;
        if (o.frustumCull) {
            if (culling) culling->update(s);
            else culling.emplace(s, o.bvhUpdate);
        }
        if (o.shadows.mode != rt::ShadowMode::None) {  // like the cull: built on the first pose, refitted to the next
            if (shadows) shadows->update(s);
            else shadows.emplace(s, o.shadows, o.bvhUpdate);
        }
        raster::resetThreadsThatRan();
        renderFrame(s, frame, culling ? &*culling : nullptr, shadows ? &*shadows : nullptr, r);
        r.threadsRan = raster::threadsThatRan();
        writeSequenceFrame(frame, i, r, frames);
    }
    if (!o.statsPath.empty()) writeJsonAtomically(o.statsPath, {{"frames", frames}});
    return 0;
}

}  // namespace cuberille::apps
