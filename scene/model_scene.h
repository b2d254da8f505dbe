#pragma once
// Mesh files as scenes: PLY (`.ply`, `.ply.gz`) and OBJ (`.obj`), framed by a camera from the
// given angles, lit by one directional light from above the camera. No culling: scans do not
// promise a consistent winding.

#include <filesystem>
#include <optional>

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
};

bool isModelFile(const std::filesystem::path& path);

/// Throws InputError for unreadable or malformed files.
Scene loadModelScene(const std::filesystem::path& path, const ModelSceneOptions& view, const WarningSink& warn);

}  // namespace cuberille::scene
