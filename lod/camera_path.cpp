#include "lod/camera_path.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "scene/input_error.h"

namespace cuberille::lod {

CameraPath CameraPath::orbit(const scene::Camera& framing, int keys) {
    CameraPath p;
    const glm::vec3 offset = framing.position - framing.target;
    for (int k = 0; k <= keys; ++k) {
        const float a = 2.0f * float(M_PI) * float(k) / float(keys);
        const glm::vec3 turned(std::cos(a) * offset.x + std::sin(a) * offset.z, offset.y,
                               -std::sin(a) * offset.x + std::cos(a) * offset.z);
        p.keys_.push_back({framing.target + turned, framing.target});
    }
    return p;
}

CameraPath CameraPath::zoom(const scene::Camera& framing, float closeness) {
    CameraPath p;
    p.keys_.push_back({framing.position, framing.target});
    p.keys_.push_back({framing.target + (framing.position - framing.target) * closeness, framing.target});
    return p;
}

CameraPath CameraPath::fromFile(const std::filesystem::path& path) {
    std::ifstream in(path);
    if (!in) throw scene::InputError(path.string() + ": cannot open the camera path");
    CameraPath p;
    std::string line;
    for (int number = 1; std::getline(in, line); ++number) {
        if (const size_t hash = line.find('#'); hash != std::string::npos) line.erase(hash);
        std::istringstream s(line);
        std::string word;
        std::vector<float> v;
        while (s >> word) {
            char* end = nullptr;
            const float x = std::strtof(word.c_str(), &end);
            if (end != word.c_str() + word.size() || !std::isfinite(x))
                throw scene::InputError(path.string() + ":" + std::to_string(number) + ": '" + word + "' is not a number");
            v.push_back(x);
        }
        if (v.empty()) continue;
        if (v.size() != 6)
            throw scene::InputError(path.string() + ":" + std::to_string(number) +
                                    ": expected 'px py pz tx ty tz', found " + std::to_string(v.size()) + " numbers");
        const CameraKey k{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}};
        if (k.position == k.target)
            throw scene::InputError(path.string() + ":" + std::to_string(number) + ": the camera is at its target");
        p.keys_.push_back(k);
    }
    if (p.keys_.size() < 2) throw scene::InputError(path.string() + ": a camera path needs at least two keyframes");
    return p;
}

scene::Camera CameraPath::at(float t, const scene::Camera& base) const {
    scene::Camera c = base;
    const float x = std::clamp(t, 0.0f, 1.0f) * float(keys_.size() - 1);
    const size_t i = std::min(size_t(x), keys_.size() - 2);
    const float f = x - float(i);
    c.position = glm::mix(keys_[i].position, keys_[i + 1].position, f);
    c.target = glm::mix(keys_[i].target, keys_[i + 1].target, f);
    // A lens framed for the first view would clip a surface the path approaches: the near plane
    // comes along, at most 1% of the way to the target.
    c.nearPlane = std::min(base.nearPlane, 0.01f * glm::distance(c.position, c.target));
    return c;
}

}  // namespace cuberille::lod
