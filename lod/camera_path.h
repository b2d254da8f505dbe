#pragma once
// Camera paths for flights through a model (`cuberille fly`, Chajdas 2015, section 4.8): an orbit
// around it, a zoom towards its surface, or keyframes from a text file. A path is sampled at
// t in [0, 1] (the first and last frame), positions and targets interpolated linearly between
// keyframes spaced evenly in t.
//
// The file format: UTF-8 text, `#` starts a comment, one keyframe per line:
//   px py pz  tx ty tz        (camera position and the point it looks at, model units)
// At least two keyframes.

#include <filesystem>
#include <vector>

#include <glm/glm.hpp>

#include "scene/camera.h"

namespace cuberille::lod {

struct CameraKey {
    glm::vec3 position, target;
};

class CameraPath {
public:
    /// A full turn about the vertical axis through the bounds' centre, from the framing camera.
    static CameraPath orbit(const scene::Camera& framing, int keys = 64);
    /// Straight towards the target, from the framing camera to `closeness` of its distance (the
    /// surface of a model framed by its bounding sphere is at about 0.4 of it).
    static CameraPath zoom(const scene::Camera& framing, float closeness = 0.45f);
    /// Throws scene::InputError naming the file and line.
    static CameraPath fromFile(const std::filesystem::path& path);

    /// The camera at t in [0, 1], with base's lens (field of view, far plane; the near plane at
    /// most 1% of the distance to the target, so approaching a surface never clips it).
    scene::Camera at(float t, const scene::Camera& base) const;
    const std::vector<CameraKey>& keys() const { return keys_; }

private:
    std::vector<CameraKey> keys_;
};

}  // namespace cuberille::lod
