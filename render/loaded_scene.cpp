#include "render/loaded_scene.h"

#include <algorithm>
#include <cmath>

#include "raster/clock.h"
#include "render/scene_state.h"
#include "scene/model_scene.h"
#include "scene/obj_loader.h"
#include "scene/ply_loader.h"
#include "scene/procedural.h"
#include "voxel/cvox_file.h"

namespace cuberille::render {
namespace {

void loadInto(LoadedScene::State& s);
void load3d(LoadedScene::State& s);

}  // namespace

LoadedScene::LoadedScene(const std::string& sceneName, const SceneOptions& options, scene::WarningSink warn)
    : state_(std::make_unique<State>()) {
    State& s = *state_;
    s.name = sceneName;
    s.options = options;
    s.warn = warn ? std::move(warn) : [](const std::string&) {};
    s.kind = scene::fileKindOf(sceneName);
    s.procedural = scene::isProceduralScene(sceneName);
    if (!(options.detail > 0.0f && options.detail <= 16.0f)) throw scene::InputError("--detail: must be in (0, 16]");
    if (options.zUp && !scene::isModelFile(sceneName))
        throw scene::InputError("--up-axis: only for mesh files (PLY, OBJ, glTF), not " + sceneName);
    const double t0 = raster::nowMs();
    loadInto(s);
    s.loadMs = raster::nowMs() - t0;
}

LoadedScene::LoadedScene(LoadedScene&&) noexcept = default;
LoadedScene& LoadedScene::operator=(LoadedScene&&) noexcept = default;
LoadedScene::~LoadedScene() = default;

const std::string& LoadedScene::name() const { return state_->name; }
bool LoadedScene::isTriangleList() const { return state_->kind == scene::FileKind::TriangleList; }
bool LoadedScene::isVoxelModel() const { return state_->kind == scene::FileKind::VoxelModel; }
bool LoadedScene::isGltf() const { return scene::isGltfKind(state_->kind); }
const SceneOptions& LoadedScene::options() const { return state_->options; }
double LoadedScene::loadMs() const { return state_->loadMs; }
std::vector<std::string> LoadedScene::animations() const {
    return state_->gltf ? state_->gltf->animationNames() : std::vector<std::string>{};
}

namespace {

void loadInto(LoadedScene::State& s) {
    if (s.kind == scene::FileKind::TriangleList) {
        s.tri = scene::loadTriScene(s.name);
        if (s.tri.positions.empty()) throw scene::InputError(s.name + ": no triangles to draw (no triangle lines)");
        return;
    }
    if (s.kind == scene::FileKind::VoxelModel) {
        voxel::VoxelModel model = voxel::readCvox(s.name);
        if (model.blocks.empty()) throw scene::InputError(s.name + ": no voxels to draw (a model of no blocks)");
        s.voxel = std::make_unique<lod::VoxelScene>(std::move(model), 30.0f, 20.0f);
        return;
    }
    if (s.procedural || scene::isModelFile(s.name)) {
        load3d(s);
        return;
    }
    std::string builtIn;
    for (const std::string& name : scene::proceduralSceneNames()) builtIn += (builtIn.empty() ? "" : ", ") + name;
    throw scene::InputError("'" + s.name + "' is not a scene: expected a .tri, .ply, .ply.gz, .obj, .gltf, .glb or .cvox "
                            "file, or a built-in scene (" + builtIn + ")");
}

/// The floor --ground puts under a model, as model viewers stage a product shot: a square at the
/// bottom of the model's bounds (up is +y once a file is read), centred under it, reaching
/// kGroundReach times the model's larger horizontal half-extent (and at least its height) in
/// each direction, so a shadow cast by a light up to about 60 degrees from the zenith falls on
/// it; light grey, matte, one-sided (seen from above).
constexpr float kGroundAlbedo = 0.6f;  // linear: a mid-light grey, below the usual white model

scene::Mesh groundUnder(const scene::Bounds& b) {
    constexpr float kGroundReach = 3.0f;
    const glm::vec3 size = b.max - b.min;
    const float half = kGroundReach * std::max({0.5f * size.x, 0.5f * size.z, size.y});
    const float cx = 0.5f * (b.min.x + b.max.x), cz = 0.5f * (b.min.z + b.max.z), y = b.min.y;
    scene::Mesh m;
    // Counter-clockwise seen from above: (b - a) x (c - a) is +y for both triangles.
    m.positions = {{cx - half, y, cz - half}, {cx - half, y, cz + half}, {cx + half, y, cz + half}, {cx + half, y, cz - half}};
    m.normals.assign(4, glm::vec3(0.0f, 1.0f, 0.0f));
    m.indices = {0, 1, 2, 0, 2, 3};
    m.color = glm::vec3(kGroundAlbedo);
    return m;
}

/// The floor's albedo for --shadow-catcher: the background's linear colour over the irradiance a
/// lit patch of floor receives (ambient, an environment's E(up), every directional light's n.l), so the floor
/// shades to the background where nothing shadows it and to the background times the fraction
/// of light that arrives where something does. A point or spot light lights a floor unevenly,
/// which no single albedo can undo: refused.
glm::vec3 catcherAlbedo(const scene::Scene& s, const glm::vec3& backgroundLinear, const std::string& name) {
    const glm::vec3 up(0.0f, 1.0f, 0.0f);
    glm::vec3 irradiance = s.lighting.ambient;
    if (const raster::EnvironmentLight* e = s.lighting.environment)
        irradiance += glm::max(
            raster::EnvironmentLight::irradianceAt(e->irradianceHarmonics(s.lighting.environmentLessDominantLight), 0, 1, 0),
            glm::vec3(0.0f));
    for (int l = 0; l < s.lighting.lightCount; ++l) {
        const raster::Light& light = s.lighting.lights[l];
        if (light.type != raster::LightType::Directional)
            throw scene::InputError("--shadow-catcher: " + name + " has a point or spot light, which lights the floor unevenly; "
                             "the catcher needs directional lights only");
        irradiance += light.intensity * std::max(0.0f, glm::dot(up, -glm::normalize(light.direction)));
    }
    return backgroundLinear / glm::max(irradiance, glm::vec3(1e-6f));
}

// Built-in scenes and PLY and OBJ files are read whole here; a glTF is parsed here and posed by
// the first frame (which says at what time).
void load3d(LoadedScene::State& s) {
    if (s.procedural) {
        s.posed = scene::makeProceduralScene(s.name, s.options.detail);
        s.ownCamera = s.posed.camera;
        s.ownLighting = s.posed.lighting;
    } else if (scene::isGltfKind(s.kind)) {
        s.gltf.emplace(s.name, s.warn);
        return;
    } else {
        scene::ModelContent c;
        if (s.kind == scene::FileKind::Obj) c.meshes = scene::loadObj(s.name, s.warn);
        else c.meshes.push_back(scene::loadPly(s.name));
        scene::finishModelContent(c, s.name, s.options.zUp);
        s.posed.name = std::filesystem::path(s.name).filename().string();
        s.posed.meshes = std::move(c.meshes);
    }
    s.bounds = scene::boundsOf(s.posed.meshes);
    s.hasPose = true;
}

}  // namespace

double LoadedScene::State::poseFor(const FrameSettings& f) {
    if (!gltf) return 0.0;
    const bool animated = !gltf->animationNames().empty();
    // A file without animations has one pose whatever the time; the animation's name is still
    // checked (an unknown one is refused) on each frame that gives one.
    if (hasPose && poseAnimation == f.animation && (poseTimeSeconds == f.timeSeconds || !animated)) return 0.0;
    const double t0 = raster::nowMs();
    scene::ModelContent c = scene::fromGltfScene(gltf->pose(f.timeSeconds, f.animation, warn), name, warn);
    scene::finishModelContent(c, name, options.zUp);
    posed.name = std::filesystem::path(name).filename().string();
    posed.meshes = std::move(c.meshes);
    posed.loadStats = c.stats;
    fileCameras = std::move(c.cameras);
    fileLights = std::move(c.lights);
    bounds = scene::boundsOf(posed.meshes);
    groundHeld = false;  // the new pose's meshes are the model's alone
    shadowsPoseStale = cullingPoseStale = primaryRaysPoseStale = hasPose;  // the hierarchies follow the new pose
    hasPose = true;
    poseTimeSeconds = f.timeSeconds;
    poseAnimation = f.animation;
    return raster::nowMs() - t0;
}

void LoadedScene::State::frameFor(const FrameSettings& f) {
    if (procedural) {
        posed.camera = f.placement ? scene::placeCamera(*f.placement, ownCamera, bounds.min, bounds.max) : ownCamera;
        posed.lighting = ownLighting;
    } else {
        scene::ModelSceneOptions view;
        view.azimuthDegrees = f.azimuth;
        view.elevationDegrees = f.elevation;
        view.cameraIndex = f.cameraIndex;
        view.placement = f.placement;
        view.keyLightBesideCamera = f.ground;
        scene::frameModelScene(posed, bounds, fileCameras, fileLights, view, name);
    }
    environmentFor(f);
}

void LoadedScene::State::environmentFor(const FrameSettings& f) {
    if (f.environment.empty()) {
        environment.reset();
        return;
    }
    environment = scene::loadEnvironment(f.environment, f.environmentIntensity);
    raster::Lighting& l = posed.lighting;
    l.environment = environment.get();
    l.ambient = glm::vec3(0.0f);  // the environment is the light from everywhere
    // The default key light stood in for an environment; a model's own lights stay. Asked for
    // shadows, a model lit by the environment alone has them cast by its dominant light, drawn
    // apart from the rest of it (raster/environment_light.h, dominantDirection).
    if (procedural || !fileLights.empty()) return;
    l.lightCount = 0;
    if (f.shadows.mode != rt::ShadowMode::None && environment->dominantIntensity != glm::vec3(0.0f)) {
        raster::Light& dominant = l.lights[0];
        dominant = raster::Light{};
        dominant.direction = -environment->dominantDirection;
        dominant.intensity = environment->dominantIntensity;
        dominant.specular = 0.0f;
        l.lightCount = 1;
        l.environmentLessDominantLight = true;
    }
}

void LoadedScene::State::groundFor(const FrameSettings& f) {
    if (f.ground != groundAsked) {  // the scene's triangles change: hierarchies built anew
        shadows.reset();
        culling.reset();
        groundAsked = f.ground;
    }
    if (f.ground && !groundHeld && !bounds.empty()) {
        posed.meshes.push_back(groundUnder(bounds));
        groundHeld = true;
    } else if (!f.ground && groundHeld) {
        posed.meshes.pop_back();
        groundHeld = false;
    }
    if (groundHeld) {  // after frameFor: the catcher's albedo answers this frame's lights
        const glm::vec4 background = f.background ? clearColorFor(*f.background) : posed.background;
        posed.meshes.back().color =
            f.shadowCatcher ? catcherAlbedo(posed, glm::vec3(background), name) : glm::vec3(kGroundAlbedo);
    }
}

SceneShadows* LoadedScene::State::shadowsFor(const FrameSettings& f) {
    if (f.shadows.mode == rt::ShadowMode::None && f.ambientOcclusion.raysPerPixel == 0) return nullptr;
    const rt::ShadowOptions& o = f.shadows;
    const rt::AmbientOcclusionOptions& ao = f.ambientOcclusion;
    // A ray-traced frame's shadow rays share its camera rays' tree (over the same triangles) unless
    // the frustum cull builds that tree over the view's triangles alone.
    const bool shareCameraRays = f.renderer == Renderer::Raytrace && f.accel == rt::CasterAccel::Bvh && !f.frustumCull;
    const bool same = shadows && shadowsMethod == f.bvhUpdate && shadowsAccel == f.accel && shadowsShareCameraRays == shareCameraRays &&
                      occlusionOptions.raysPerPixel == ao.raysPerPixel &&
                      occlusionOptions.maxDistance == ao.maxDistance && shadowsOptions.mode == o.mode && shadowsOptions.soft == o.soft &&
                      shadowsOptions.lightRadius == o.lightRadius && shadowsOptions.mapSizeTexels == o.mapSizeTexels &&
                      shadowsOptions.softSamplesPerSide == o.softSamplesPerSide && shadowsOptions.focus == o.focus &&
                      shadowsOptions.sequenceFrames == o.sequenceFrames;
    if (!same) {
        shadows.emplace(posed, o, f.bvhUpdate, ao, f.accel, shareCameraRays);
        shadowsAccel = f.accel;
        shadowsShareCameraRays = shareCameraRays;
        shadowsOptions = o;
        occlusionOptions = ao;
        shadowsMethod = f.bvhUpdate;
    } else if (shadowsPoseStale) {
        shadows->update(posed);
    }
    shadowsPoseStale = false;
    return &*shadows;
}

SceneFrustumCull* LoadedScene::State::cullingFor(const FrameSettings& f) {
    if (!f.frustumCull) return nullptr;
    if (!culling || cullingMethod != f.bvhUpdate) {
        culling.emplace(posed, f.bvhUpdate);
        cullingMethod = f.bvhUpdate;
    } else if (cullingPoseStale) {
        culling->update(posed);
    }
    cullingPoseStale = false;
    return &*culling;
}

}  // namespace cuberille::render
