#pragma once
// Shade stage: once per pixel per primitive (multisample semantics), at the pixel centre.
//
// Perspective-correct barycentrics come from the exact edge values at the pixel centre. A
// pixel centre can lie outside the triangle when only some samples are covered; there the
// screen-space barycentrics are clamped onto the triangle before the perspective correction,
// so extrapolation cannot blow up with extreme w ratios and the weights always form a convex
// combination (no NaN or Inf can come out of finite vertex data).
//
// Each shading model is a small struct the back end is instantiated with, so a model's
// cost is only what it reads.

#include <algorithm>
#include <cstdint>

#include <glm/glm.hpp>

#include "raster/draw.h"
#include "raster/setup.h"

namespace cuberille::raster {

/// Perspective-correct weights of the three set-up vertices at a pixel centre, from the fine
/// stage's biased edge values there (each edge opposite its vertex, so E_k / 2A is weight k).
inline glm::vec3 perspectiveBarycentrics(const TriangleSetup& t, const int64_t centreEdges[3]) {
    // Screen-space weights sum to exactly 1 in exact arithmetic; a centre outside the triangle
    // has a negative one, clamped to 0 (the renormalisation below absorbs the change).
    const float invArea = float(t.invDoubleArea);
    const float q0 = std::max(0.0f, float(centreEdges[0] - t.fillBias[0]) * invArea) * t.invW[0];
    const float q1 = std::max(0.0f, float(centreEdges[1] - t.fillBias[1]) * invArea) * t.invW[1];
    const float q2 = std::max(0.0f, float(centreEdges[2] - t.fillBias[2]) * invArea) * t.invW[2];
    const float norm = 1.0f / (q0 + q1 + q2);
    return glm::vec3(q0 * norm, q1 * norm, q2 * norm);
}

struct ConstantColorShader {
    glm::vec4 shade(const TriangleSetup& t, const float*, const int64_t*) const {
        return t.flatColor;
    }
};

/// Lambert: varyings are world normal (3) and linear colour (3); one directional light.
struct LambertShader {
    DirectionalLight light;

    glm::vec4 shade(const TriangleSetup& t, const float* varyings, const int64_t* centreEdges) const {
        const glm::vec3 w = perspectiveBarycentrics(t, centreEdges);
        const float* v0 = varyings;
        const float* v1 = varyings + 6;
        const float* v2 = varyings + 12;
        glm::vec3 n(w.x * v0[0] + w.y * v1[0] + w.z * v2[0], w.x * v0[1] + w.y * v1[1] + w.z * v2[1],
                    w.x * v0[2] + w.y * v1[2] + w.z * v2[2]);
        const glm::vec3 albedo(w.x * v0[3] + w.y * v1[3] + w.z * v2[3],
                               w.x * v0[4] + w.y * v1[4] + w.z * v2[4],
                               w.x * v0[5] + w.y * v1[5] + w.z * v2[5]);
        const float len2 = glm::dot(n, n);
        const float cosine = len2 > 0.0f ? std::max(0.0f, glm::dot(n, light.directionToLight)) /
                                               std::sqrt(len2)
                                         : 0.0f;
        return glm::vec4(albedo * (light.ambient + light.radiance * cosine), 1.0f);
    }
};

}  // namespace cuberille::raster
