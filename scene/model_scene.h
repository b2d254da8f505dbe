#pragma once
// Mesh files as scenes: PLY (`.ply`, `.ply.gz`) and OBJ (`.obj`), framed by a camera from the
// given angles, lit by one directional light from above the camera. No culling: scans do not
// promise a consistent winding.

#include <filesystem>
#include <optional>

#include "scene/gltf_loader.h"
#include "scene/input_error.h"
#include "scene/scene.h"

namespace cuberille::scene {

struct ModelSceneOptions {
    float azimuthDegrees = 30.0f;
    float elevationDegrees = 20.0f;
    int cameraIndex = -1;      // a camera of the file (glTF) instead of framing the bounds
    float timeSeconds = 0.0f;  // glTF: the pose of the animation (below) at this time
    bool zUp = false;          // the file's up is +z (many scans and CAD files): turned to +y on load
    std::optional<CameraPlacement> placement;  // a camera placed by hand instead of the framing one
    std::string animation;     // glTF: the animation posed, by name or index; empty: the first
    /// A model without lights of its own takes its key light from beside the camera rather than
    /// from above it, so its shadow falls where the frame shows it (render --ground's staging).
    bool keyLightBesideCamera = false;
};

bool isModelFile(const std::filesystem::path& path);

/// Throws InputError for unreadable or malformed files.
Scene loadModelScene(const std::filesystem::path& path, const ModelSceneOptions& view, const WarningSink& warn);

// The steps of loadModelScene, for a renderer that reads a file once and frames it many times
// (render/loaded_scene.h): what the file holds, then a camera and lights for one frame.

/// A model file's meshes (posed, for glTF), cameras and lights (at most raster::kMaxLights;
/// more warn once).
struct ModelContent {
    std::vector<Mesh> meshes;
    std::vector<Camera> cameras;
    std::vector<raster::Light> lights;
    LoadStats stats;
};

/// The file read and posed at view.timeSeconds and view.animation; finishModelContent applied.
ModelContent readModelContent(const std::filesystem::path& path, const ModelSceneOptions& view, const WarningSink& warn);
/// A posed glTF scene as model content, before finishModelContent.
ModelContent fromGltfScene(GltfScene&& scene, const std::filesystem::path& path, const WarningSink& warn);
/// Refuses content without a triangle (InputError naming the file); turns +z up to +y if asked.
void finishModelContent(ModelContent& content, const std::filesystem::path& path, bool zUp);
/// The frame's camera (a file camera, the bounds framed from view's angles, or view's placement),
/// the lights (the file's, else a key light above the camera, or beside it for
/// view.keyLightBesideCamera), background and culling.
void frameModelScene(Scene& scene, const Bounds& bounds, const std::vector<Camera>& fileCameras,
                     const std::vector<raster::Light>& fileLights, const ModelSceneOptions& view,
                     const std::filesystem::path& path);

}  // namespace cuberille::scene
