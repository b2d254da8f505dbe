#include "scene/camera.h"

#include <glm/gtc/matrix_transform.hpp>

namespace cuberille::scene {

glm::mat4 Camera::viewFromWorld() const { return glm::lookAtRH(position, target, up); }

glm::mat4 Camera::clipFromView(float aspect) const {
    return glm::perspectiveRH_ZO(glm::radians(verticalFovDegrees), aspect, nearPlane, farPlane);
}

}  // namespace cuberille::scene
