#pragma once
// Random draws seen in perspective, and the visibility the forward frame's depth test keeps for
// them: the shared input of the deferred shade's and the camera rays' tests.

#include <random>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "raster/pipeline.h"
#include "raster/texture.h"
#include "tests/raster/test_support.h"

namespace cuberille::testing {

/// Three draws of random triangles seen in perspective, many crossing the near plane or the
/// frame's edges: Lambert with vertex colours (back faces culled), the metallic-roughness BRDF
/// with a mipmapped base-colour texture and a point light (both facings), and flat colours.
struct RandomPerspectiveDraws {
    static constexpr int kTriangles = 1500;
    std::vector<glm::vec3> positions[3], normals[3], colors[3];
    std::vector<glm::vec2> uvs;
    std::vector<glm::vec4> flat;
    std::vector<uint32_t> indices;  // the second draw is indexed, sharing vertices
    raster::Texture texture;
    glm::mat4 clipFromWorld;
    glm::vec3 eye{0.3f, 0.2f, 0.6f}, target{0.0f, 0.0f, -3.0f};

    explicit RandomPerspectiveDraws(uint32_t seed) : texture(makeTexture(seed)) {
        std::mt19937 rng(seed);
        std::uniform_real_distribution<float> unit(0.0f, 1.0f), signedUnit(-1.0f, 1.0f);
        for (int d = 0; d < 3; ++d)
            for (int i = 0; i < kTriangles; ++i) {
                // Most triangles small, some large; centres spread in depth, some behind the eye.
                const float size = unit(rng) < 0.9f ? 0.02f + 0.2f * unit(rng) : 0.3f + 1.2f * unit(rng);
                const float z = unit(rng) < 0.02f ? 0.6f - 0.6f * unit(rng) : -0.5f - 6.0f * unit(rng);
                const glm::vec3 centre(3.0f * signedUnit(rng), 2.0f * signedUnit(rng), z);
                for (int k = 0; k < 3; ++k) {
                    positions[d].push_back(centre + size * glm::vec3(signedUnit(rng), signedUnit(rng), signedUnit(rng)));
                    normals[d].push_back(glm::vec3(signedUnit(rng), signedUnit(rng), 1.0f));
                    colors[d].push_back({unit(rng), unit(rng), unit(rng)});
                    if (d == 1) uvs.push_back({2.0f * signedUnit(rng), 2.0f * signedUnit(rng)});
                }
                if (d == 2) flat.push_back({unit(rng), unit(rng), unit(rng), 1.0f});
            }
        for (int i = 0; i < kTriangles; ++i)  // each triangle takes its own corners, some a neighbour's
            for (int k = 0; k < 3; ++k) indices.push_back(uint32_t(unit(rng) < 0.2f && i > 0 ? 3 * (i - 1) + k : 3 * i + k));
        clipFromWorld = glm::perspective(glm::radians(60.0f), 1.5f, 0.1f, 20.0f) *
                        glm::lookAt(eye, target, glm::vec3(0, 1, 0));
    }

    static raster::Texture makeTexture(uint32_t seed) {
        std::mt19937 rng(seed + 1);
        std::uniform_real_distribution<float> unit(0.0f, 1.0f);
        std::vector<glm::vec4> texels(32 * 32);
        for (glm::vec4& t : texels) t = {unit(rng), unit(rng), unit(rng), 1.0f};
        return raster::Texture(32, 32, std::move(texels));
    }

    std::vector<raster::DrawCall> draws() const {
        std::vector<raster::DrawCall> out(3);
        for (int d = 0; d < 3; ++d) {
            raster::DrawCall& c = out[d];
            c.clipFromObject = clipFromWorld;
            c.positions = positions[d];
            c.normals = normals[d];
            c.state.lighting.ambient = glm::vec3(0.05f);
            c.state.lighting.lightCount = 1;
            c.state.lighting.lights[0].direction = glm::normalize(glm::vec3(0.3f, -0.6f, -0.5f));
        }
        out[0].vertexColors = colors[0];
        out[0].state.shading = raster::ShadingModel::Lambert;
        out[0].state.cull = raster::CullMode::Back;
        out[1].indices = indices;
        out[1].texCoords = uvs;
        out[1].state.shading = raster::ShadingModel::MetallicRoughness;
        out[1].state.metallic = 0.3f, out[1].state.roughness = 0.5f;
        out[1].state.textures.baseColor.texture = &texture;
        out[1].state.cameraPosition = eye;
        out[1].state.lighting.lights[0].type = raster::LightType::Point;
        out[1].state.lighting.lights[0].position = glm::vec3(0.0f, 2.0f, -1.0f);
        out[2].triangleColors = flat;
        out[2].state.shading = raster::ShadingModel::ConstantColor;
        return out;
    }
};

/// What the forward frame's depth test kept at each sample, read back from an id pass: the same
/// draws, flat-coloured with (draw, triangle, 1).
inline raster::VisibilityBuffer visibilityOfForwardFrame(const std::vector<raster::DrawCall>& draws, int width, int height, int samples) {
    std::vector<std::vector<glm::vec4>> ids(draws.size());
    raster::Pipeline p;
    p.beginFrame(frame(width, height, samples));
    for (size_t d = 0; d < draws.size(); ++d) {
        for (size_t t = 0; t < draws[d].triangleCount(); ++t) ids[d].push_back({float(d), float(t), 1.0f, 1.0f});
        raster::DrawCall id = draws[d];
        id.state.shading = raster::ShadingModel::ConstantColor;
        id.triangleColors = ids[d];
        p.draw(id);
    }
    p.endFrame();
    raster::VisibilityBuffer seen;
    seen.reset(width, height, samples);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            for (int s = 0; s < samples; ++s) {
                const glm::vec4 c = sampleColor(p.framebuffer(), x, y, s);
                if (c.b != 1.0f) continue;
                const size_t i = (size_t(y) * width + x) * samples + s;
                seen.draw[i] = uint32_t(c.r), seen.triangle[i] = uint32_t(c.g);
            }
    return seen;
}

}  // namespace cuberille::testing
