#pragma once
// A pinhole camera producing Direct3D/Vulkan clip space (depth 0..1, NDC y up; the viewport
// flips y). World space is right-handed with y up.

#include <optional>

#include <glm/glm.hpp>

namespace cuberille::scene {

struct Camera {
    glm::vec3 position{0.0f, 0.0f, 5.0f};
    glm::vec3 target{0.0f};
    glm::vec3 up{0.0f, 1.0f, 0.0f};
    float verticalFovDegrees = 45.0f;
    float nearPlane = 0.1f;
    float farPlane = 1000.0f;
    bool orthographic = false;
    float orthographicHalfHeight = 1.0f;  // world units, when orthographic
    /// Depth 1 at the near plane and 0 at the far plane, for a framebuffer with
    /// raster::DepthConvention::Reversed (`render --depth reversed`).
    bool reversedDepth = false;

    glm::mat4 viewFromWorld() const;
    glm::mat4 clipFromView(float aspect) const;
    glm::mat4 clipFromWorld(float aspect) const { return clipFromView(aspect) * viewFromWorld(); }
};

/// A camera placed by hand (`render --eye --target --up --fov`): the eye is required, the rest
/// default to the framing camera's target, +y and its field of view. The near and far planes
/// hug the bounds as seen from the eye.
struct CameraPlacement {
    glm::vec3 eye{0.0f};
    std::optional<glm::vec3> target, up;
    float verticalFovDegrees = 0.0f;  // 0: the framing camera's
};
Camera placeCamera(const CameraPlacement& placement, const Camera& framing, const glm::vec3& boundsMin,
                   const glm::vec3& boundsMax);

/// The orthographic camera that sees what `c` sees in the plane through its target at the same
/// size (half height = the target's distance times tan(half the field of view)); the same eye,
/// direction and planes. An orthographic camera is returned as it is.
Camera orthographicView(const Camera& c);

/// A camera that frames a bounding box (its bounding sphere fills the vertical field of view),
/// looking at its centre from the given azimuth (degrees about +y, 0 = from +z) and elevation
/// (degrees above the horizon), with near and far planes hugging the sphere.
Camera frameBounds(const glm::vec3& boundsMin, const glm::vec3& boundsMax, float azimuthDegrees,
                   float elevationDegrees, float verticalFovDegrees = 40.0f);

}  // namespace cuberille::scene
