#include "scene/camera.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "raster/framebuffer.h"

namespace cuberille::scene {

glm::mat4 Camera::viewFromWorld() const { return glm::lookAtRH(position, target, up); }

glm::mat4 Camera::clipFromView(float aspect) const {
    if (orthographic) {
        const float h = orthographicHalfHeight;
        glm::mat4 m = glm::orthoRH_ZO(-h * aspect, h * aspect, -h, h, nearPlane, farPlane);
        if (reversedDepth) {  // z' = 1 - z, with the constants computed directly
            const double n = nearPlane, f = farPlane;
            m[2][2] = float(1.0 / (f - n));
            m[3][2] = float(f / (f - n));
        }
        return m;
    }
    return raster::perspectiveProjection(glm::radians(verticalFovDegrees), aspect, nearPlane, farPlane,
                                         reversedDepth ? raster::DepthConvention::Reversed : raster::DepthConvention::Standard);
}

Camera placeCamera(const CameraPlacement& p, const Camera& framing, const glm::vec3& boundsMin,
                   const glm::vec3& boundsMax) {
    Camera c = framing;
    c.position = p.eye;
    c.target = p.target.value_or(framing.target);
    c.up = p.up.value_or(glm::vec3(0.0f, 1.0f, 0.0f));
    if (p.verticalFovDegrees > 0.0f) c.verticalFovDegrees = p.verticalFovDegrees;
    // Planes around the bounding sphere as seen from the eye, as frameBounds places them; from
    // inside the sphere, the near plane at a thousandth of the far one.
    const glm::vec3 centre = 0.5f * (boundsMin + boundsMax);
    const float radius = std::max(0.5f * glm::length(boundsMax - boundsMin), 1e-6f);
    const float distance = glm::length(centre - p.eye);
    c.farPlane = distance + 1.5f * radius;
    c.nearPlane = std::max(distance - 1.5f * radius, c.farPlane * 1e-3f);
    return c;
}

Camera orthographicView(const Camera& c) {
    if (c.orthographic) return c;
    Camera o = c;
    o.orthographic = true;
    o.orthographicHalfHeight =
        glm::length(c.target - c.position) * std::tan(glm::radians(c.verticalFovDegrees) * 0.5f);
    return o;
}

Camera frameBounds(const glm::vec3& boundsMin, const glm::vec3& boundsMax, float azimuthDegrees,
                   float elevationDegrees, float verticalFovDegrees) {
    Camera c;
    c.verticalFovDegrees = verticalFovDegrees;
    c.target = 0.5f * (boundsMin + boundsMax);
    const float radius = std::max(0.5f * glm::length(boundsMax - boundsMin), 1e-6f);
    const float distance = radius / std::sin(glm::radians(verticalFovDegrees) * 0.5f) * 1.05f;
    const float az = glm::radians(azimuthDegrees), el = glm::radians(elevationDegrees);
    const glm::vec3 direction(std::cos(el) * std::sin(az), std::sin(el), std::cos(el) * std::cos(az));
    c.position = c.target + distance * direction;
    // Looking straight down or up: pick an up vector that is not parallel to the view.
    c.up = std::abs(direction.y) > 0.999f ? glm::vec3(0.0f, 0.0f, -1.0f) : glm::vec3(0.0f, 1.0f, 0.0f);
    c.nearPlane = std::max(distance - 1.5f * radius, distance * 1e-3f);
    c.farPlane = distance + 1.5f * radius;
    return c;
}

}  // namespace cuberille::scene
