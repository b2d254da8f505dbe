#include "scene/model_scene.h"

#include <algorithm>
#include <cmath>

#include "scene/file_names.h"
#include "scene/gltf_loader.h"
#include "scene/input_error.h"
#include "scene/obj_loader.h"
#include "scene/ply_loader.h"

namespace cuberille::scene {
namespace {

// A quarter turn about x taking +z to +y: (x, y, z) -> (x, z, -y), for positions, normals and
// tangents alike (a rotation keeps the tangents' handedness).
void turnZUpToYUp(Mesh& m) {
    auto turn = [](glm::vec3& v) { v = glm::vec3(v.x, v.z, -v.y); };
    for (glm::vec3& p : m.positions) turn(p);
    for (glm::vec3& n : m.normals) turn(n);
    for (glm::vec4& t : m.tangents) {
        glm::vec3 v(t);
        turn(v);
        t = glm::vec4(v, t.w);
    }
}

}  // namespace

bool isModelFile(const std::filesystem::path& path) { return isMeshKind(fileKindOf(path)); }

ModelContent readModelContent(const std::filesystem::path& path, const ModelSceneOptions& view, const WarningSink& warn) {
    ModelContent c;
    const FileKind kind = fileKindOf(path);
    if (kind == FileKind::Obj) {
        c.meshes = loadObj(path, warn);
    } else if (isGltfKind(kind)) {
        c = fromGltfScene(loadGltf(path, warn, view.timeSeconds, view.animation), path, warn);
    } else {
        c.meshes.push_back(loadPly(path));
    }
    finishModelContent(c, path, view.zUp);
    return c;
}

ModelContent fromGltfScene(GltfScene&& g, const std::filesystem::path& path, const WarningSink& warn) {
    ModelContent c;
    c.meshes = std::move(g.meshes);
    c.cameras = std::move(g.cameras);
    c.lights = std::move(g.lights);
    c.stats = g.stats;
    if (c.lights.size() > size_t(raster::kMaxLights)) {
        warn(path.string() + ": " + std::to_string(c.lights.size()) + " lights; the first " +
             std::to_string(raster::kMaxLights) + " are used");
        c.lights.resize(raster::kMaxLights);
    }
    return c;
}

void finishModelContent(ModelContent& c, const std::filesystem::path& path, bool zUp) {
    // A file that yields no triangle is bad input, not an empty picture (exit code 2).
    size_t triangles = 0;
    for (const Mesh& m : c.meshes) triangles += m.triangleCount();
    if (triangles == 0)
        throw InputError(path.string() + ": no triangles to draw" +
                         (isGltfKind(fileKindOf(path)) ? " (no mesh of its scene has a primitive of triangles)" : " (no faces)"));
    if (zUp)
        for (Mesh& m : c.meshes) turnZUpToYUp(m);
}

Scene loadModelScene(const std::filesystem::path& path, const ModelSceneOptions& view, const WarningSink& warn) {
    ModelContent c = readModelContent(path, view, warn);
    Scene s;
    s.name = path.filename().string();
    s.meshes = std::move(c.meshes);
    s.loadStats = c.stats;
    frameModelScene(s, boundsOf(s.meshes), c.cameras, c.lights, view, path);
    return s;
}

namespace {

/// Towards the default key light: above the camera.
glm::vec3 keyLightAbove(const Camera& camera) {
    const glm::vec3 toCamera = glm::normalize(camera.position - camera.target);
    return glm::normalize(toCamera + glm::vec3(0.0f, 0.8f, 0.0f));
}

/// Towards the key light of a staged model (ModelSceneOptions::keyLightBesideCamera): a light
/// above the camera throws the shadow behind the model, where a floor would catch nothing the
/// frame shows; this one stands kKeyLightTurn to the camera's left and kKeyLightElevation up
/// from the horizon, as a product shot's key light stands.
glm::vec3 keyLightBeside(const Camera& camera) {
    constexpr float kKeyLightTurn = glm::radians(50.0f);
    constexpr float kKeyLightElevation = glm::radians(55.0f);
    glm::vec3 toCamera = camera.position - camera.target;
    toCamera.y = 0.0f;
    toCamera = glm::dot(toCamera, toCamera) > 0.0f ? glm::normalize(toCamera) : glm::vec3(0.0f, 0.0f, 1.0f);
    const float c = std::cos(kKeyLightTurn), s = std::sin(kKeyLightTurn);
    const glm::vec3 turned(c * toCamera.x - s * toCamera.z, 0.0f, s * toCamera.x + c * toCamera.z);
    return glm::normalize(turned * std::cos(kKeyLightElevation) + glm::vec3(0.0f, std::sin(kKeyLightElevation), 0.0f));
}

}  // namespace

void frameModelScene(Scene& s, const Bounds& b, const std::vector<Camera>& cameras, const std::vector<raster::Light>& lights,
                     const ModelSceneOptions& view, const std::filesystem::path& path) {
    if (view.cameraIndex >= 0) {
        if (view.cameraIndex >= int(cameras.size()))
            throw InputError("--camera-index " + std::to_string(view.cameraIndex) + ": " + path.string() + " has " +
                             std::to_string(cameras.size()) + " camera(s)");
        s.camera = cameras[view.cameraIndex];
    } else {
        s.camera = frameBounds(b.min, b.max, view.azimuthDegrees, view.elevationDegrees);
    }
    if (view.placement) s.camera = placeCamera(*view.placement, s.camera, b.min, b.max);
    // Without lights of its own a model is lit by a key light that follows the view, so every
    // side of a turntable is readable: from above the camera, or from beside it when asked.
    const glm::vec3 toLight = view.keyLightBesideCamera ? keyLightBeside(s.camera) : keyLightAbove(s.camera);
    s.lighting = raster::Lighting::directional(toLight, glm::vec3(0.85f), glm::vec3(0.12f));
    if (!lights.empty()) {
        s.lighting.lightCount = int(std::min(lights.size(), size_t(raster::kMaxLights)));
        std::copy_n(lights.begin(), s.lighting.lightCount, s.lighting.lights);
    }
    s.background = {0.05f, 0.06f, 0.08f, 1.0f};
    // glTF says which materials are double-sided; PLY and OBJ scans promise no winding.
    s.cull = isGltfKind(fileKindOf(path)) ? raster::CullMode::Back : raster::CullMode::None;
}

}  // namespace cuberille::scene
