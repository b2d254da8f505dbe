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
#include "raster/texture.h"
#include "raster/limits.h"
#include "raster/setup.h"

namespace cuberille::raster {

/// Pixels of one block waiting to be shaded, as structure-of-arrays, so a shading model's loop
/// runs across pixels and the compiler vectorises it (the software counterpart of a GPU
/// shading a warp of pixels). Filled by the depth stage, read by output merge.
struct ShadeQueue {
    static constexpr int kCapacity = kBlockSizePixels * kBlockSizePixels;
    int count = 0;
    // Biased edge values at the pixel centre (each edge opposite its vertex).
    int64_t edge0[kCapacity], edge1[kCapacity], edge2[kCapacity];
    uint32_t firstSample[kCapacity];  // index of the pixel's first sample in the tile
    uint32_t passMask[kCapacity];     // samples that passed the depth test
    float red[kCapacity], green[kCapacity], blue[kCapacity], alpha[kCapacity];
};

struct ConstantColorShader {
    void shade(const TriangleSetup& t, const float*, ShadeQueue& q) const {
        for (int i = 0; i < q.count; ++i) {
            q.red[i] = t.flatColor.r;
            q.green[i] = t.flatColor.g;
            q.blue[i] = t.flatColor.b;
            q.alpha[i] = t.flatColor.a;
        }
    }
};

/// The surface shading models, specialised at compile time so a draw pays only for what its
/// material uses: kTextured multiplies the albedo by the base colour texture (trilinear, with
/// exact per-pixel UV derivatives); kLit applies Lambert with one directional light plus
/// ambient, otherwise the colour is the albedo alone (KHR_materials_unlit).
/// Varyings per vertex: normal (3), linear colour (3), and uv (2) when textured. Per pixel:
/// perspective-correct weights (screen weights clamped to the triangle, times 1/w,
/// renormalised), interpolated attributes, then albedo * (ambient + radiance * max(0, n.l)).
template <bool kTextured, bool kLit>
struct SurfaceShader {
    DirectionalLight light;
    const Texture* texture = nullptr;
    float alpha = 1.0f;  // the material's; times the texture's when textured

    void shade(const TriangleSetup& t, const float* v, ShadeQueue& q) const {
        constexpr int n = kTextured ? 8 : 6;  // varyings per vertex
        const float invArea = float(t.invDoubleArea);
        const float bias0 = t.fillBias[0], bias1 = t.fillBias[1], bias2 = t.fillBias[2];
        const float invW0 = t.invW[0], invW1 = t.invW[1], invW2 = t.invW[2];
        const glm::vec3 l = light.directionToLight, rad = light.radiance, amb = light.ambient;
        for (int i = 0; i < q.count; ++i) {
            const float q0 = std::max(0.0f, float(q.edge0[i] - int64_t(bias0)) * invArea) * invW0;
            const float q1 = std::max(0.0f, float(q.edge1[i] - int64_t(bias1)) * invArea) * invW1;
            const float q2 = std::max(0.0f, float(q.edge2[i] - int64_t(bias2)) * invArea) * invW2;
            const float norm = 1.0f / (q0 + q1 + q2);
            const float w0 = q0 * norm, w1 = q1 * norm, w2 = q2 * norm;
            float ax = w0 * v[3] + w1 * v[n + 3] + w2 * v[2 * n + 3];
            float ay = w0 * v[4] + w1 * v[n + 4] + w2 * v[2 * n + 4];
            float az = w0 * v[5] + w1 * v[n + 5] + w2 * v[2 * n + 5];
            float a = alpha;
            if constexpr (kTextured) {
                const glm::vec4 texel = sampleTexture(t, v, q, i, glm::vec3(w0, w1, w2));
                ax *= texel.r, ay *= texel.g, az *= texel.b, a *= texel.a;
            }
            if constexpr (kLit) {
                const float nx = w0 * v[0] + w1 * v[n] + w2 * v[2 * n];
                const float ny = w0 * v[1] + w1 * v[n + 1] + w2 * v[2 * n + 1];
                const float nz = w0 * v[2] + w1 * v[n + 2] + w2 * v[2 * n + 2];
                const float len2 = nx * nx + ny * ny + nz * nz;
                const float nDotL = nx * l.x + ny * l.y + nz * l.z;
                const float cosine = len2 > 0.0f ? std::max(0.0f, nDotL) / std::sqrt(len2) : 0.0f;
                q.red[i] = ax * (amb.x + rad.x * cosine);
                q.green[i] = ay * (amb.y + rad.y * cosine);
                q.blue[i] = az * (amb.z + rad.z * cosine);
            } else {
                q.red[i] = ax, q.green[i] = ay, q.blue[i] = az;
            }
            q.alpha[i] = a;
        }
    }

private:
    // The level of detail comes from exact UV derivatives: the perspective-correct UV is also
    // evaluated one pixel right and one pixel down, from the same edge functions stepped by
    // A·256 and B·256, and differenced (per pixel, where a GPU differences across a 2x2 quad).
    // Those neighbours use unclamped weights, which like a GPU's helper pixels extrapolate the
    // attribute plane past the triangle's edges (clamping would bend it there); a degenerate
    // extrapolation gives NaN, which the level of detail treats as level 0.
    glm::vec4 sampleTexture(const TriangleSetup& t, const float* v, const ShadeQueue& q, int i,
                            const glm::vec3& w) const {
        const float invArea = float(t.invDoubleArea);
        auto extrapolatedWeights = [&](int64_t e0, int64_t e1, int64_t e2) {
            const float q0 = float(e0 - t.fillBias[0]) * invArea * t.invW[0];
            const float q1 = float(e1 - t.fillBias[1]) * invArea * t.invW[1];
            const float q2 = float(e2 - t.fillBias[2]) * invArea * t.invW[2];
            const float sum = q0 + q1 + q2;
            const float norm = sum > 0.0f ? 1.0f / sum : NAN;
            return glm::vec3(q0 * norm, q1 * norm, q2 * norm);
        };
        auto uvAt = [&](const glm::vec3& b) {
            return glm::vec2(b.x * v[6] + b.y * v[14] + b.z * v[22], b.x * v[7] + b.y * v[15] + b.z * v[23]);
        };
        auto step = [&](const int32_t* coefficient, int k) { return int64_t{coefficient[k]} * kSubpixelsPerPixel; };
        const glm::vec2 uvPlane = uvAt(extrapolatedWeights(q.edge0[i], q.edge1[i], q.edge2[i]));
        const glm::vec2 uvRight = uvAt(extrapolatedWeights(q.edge0[i] + step(t.edgeA, 0), q.edge1[i] + step(t.edgeA, 1),
                                                           q.edge2[i] + step(t.edgeA, 2)));
        const glm::vec2 uvDown = uvAt(extrapolatedWeights(q.edge0[i] + step(t.edgeB, 0), q.edge1[i] + step(t.edgeB, 1),
                                                          q.edge2[i] + step(t.edgeB, 2)));
        return texture->sampleTrilinear(uvAt(w), texture->levelOfDetail(uvRight - uvPlane, uvDown - uvPlane));
    }
};

}  // namespace cuberille::raster
