#pragma once
// A pinhole camera producing Direct3D/Vulkan clip space (depth 0..1, NDC y up; the viewport
// flips y). World space is right-handed with y up.

#include <glm/glm.hpp>

namespace cuberille::scene {

struct Camera {
    glm::vec3 position{0.0f, 0.0f, 5.0f};
    glm::vec3 target{0.0f};
    glm::vec3 up{0.0f, 1.0f, 0.0f};
    float verticalFovDegrees = 45.0f;
    float nearPlane = 0.1f;
    float farPlane = 1000.0f;

    glm::mat4 viewFromWorld() const;
    glm::mat4 clipFromView(float aspect) const;
    glm::mat4 clipFromWorld(float aspect) const { return clipFromView(aspect) * viewFromWorld(); }
};

}  // namespace cuberille::scene
