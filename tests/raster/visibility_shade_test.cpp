// The deferred shade (raster/visibility_shade.h): handed the visibility the depth test found, it
// gives the forward frame's samples bit for bit.

#include <gtest/gtest.h>

#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "raster/pipeline.h"
#include "raster/texture.h"
#include "tests/raster/test_support.h"
#include "tests/thread_counts.h"

namespace cuberille::testing {
namespace {

using raster::DrawCall;
using raster::ShadingModel;

float sampleDepthKey(const raster::Framebuffer& fb, int x, int y, int s) {
    const int tile = (y / raster::kTileSizePixels) * fb.tilesX() + x / raster::kTileSizePixels;
    const size_t i = (size_t(y % raster::kTileSizePixels) * raster::kTileSizePixels + size_t(x % raster::kTileSizePixels)) *
                         fb.samples() + s;
    return fb.tileDepth(tile)[i];
}

/// Three draws of random triangles seen in perspective, many crossing the near plane or the
/// frame's edges: Lambert with vertex colours (back faces culled), the metallic-roughness BRDF
/// with a mipmapped base-colour texture and a point light (both facings), and flat colours.
struct RandomScene {
    static constexpr int kTriangles = 1500;
    std::vector<glm::vec3> positions[3], normals[3], colors[3];
    std::vector<glm::vec2> uvs;
    std::vector<glm::vec4> flat;
    std::vector<uint32_t> indices;  // the second draw is indexed, sharing vertices
    raster::Texture texture;
    glm::mat4 clipFromWorld;

    explicit RandomScene(uint32_t seed) : texture(makeTexture(seed)) {
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
                        glm::lookAt(glm::vec3(0.3f, 0.2f, 0.6f), glm::vec3(0.0f, 0.0f, -3.0f), glm::vec3(0, 1, 0));
    }

    static raster::Texture makeTexture(uint32_t seed) {
        std::mt19937 rng(seed + 1);
        std::uniform_real_distribution<float> unit(0.0f, 1.0f);
        std::vector<glm::vec4> texels(32 * 32);
        for (glm::vec4& t : texels) t = {unit(rng), unit(rng), unit(rng), 1.0f};
        return raster::Texture(32, 32, std::move(texels));
    }

    std::vector<DrawCall> draws() const {
        std::vector<DrawCall> out(3);
        for (int d = 0; d < 3; ++d) {
            DrawCall& c = out[d];
            c.clipFromObject = clipFromWorld;
            c.positions = positions[d];
            c.normals = normals[d];
            c.state.lighting.ambient = glm::vec3(0.05f);
            c.state.lighting.lightCount = 1;
            c.state.lighting.lights[0].direction = glm::normalize(glm::vec3(0.3f, -0.6f, -0.5f));
        }
        out[0].vertexColors = colors[0];
        out[0].state.shading = ShadingModel::Lambert;
        out[0].state.cull = raster::CullMode::Back;
        out[1].indices = indices;
        out[1].texCoords = uvs;
        out[1].state.shading = ShadingModel::MetallicRoughness;
        out[1].state.metallic = 0.3f, out[1].state.roughness = 0.5f;
        out[1].state.textures.baseColor.texture = &texture;
        out[1].state.cameraPosition = glm::vec3(0.3f, 0.2f, 0.6f);
        out[1].state.lighting.lights[0].type = raster::LightType::Point;
        out[1].state.lighting.lights[0].position = glm::vec3(0.0f, 2.0f, -1.0f);
        out[2].triangleColors = flat;
        out[2].state.shading = ShadingModel::ConstantColor;
        return out;
    }
};

/// What the forward frame's depth test kept at each sample, read back from an id pass: the same
/// draws, flat-coloured with (draw, triangle, 1).
raster::VisibilityBuffer visibilityOfForwardFrame(const std::vector<DrawCall>& draws, int width, int height, int samples) {
    std::vector<std::vector<glm::vec4>> ids(draws.size());
    raster::Pipeline p;
    p.beginFrame(frame(width, height, samples));
    for (size_t d = 0; d < draws.size(); ++d) {
        for (size_t t = 0; t < draws[d].triangleCount(); ++t) ids[d].push_back({float(d), float(t), 1.0f, 1.0f});
        DrawCall id = draws[d];
        id.state.shading = ShadingModel::ConstantColor;
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

// Random scenes through both paths at 1 and 4 samples: each sample's colour and depth key must be
// the same bits, so the set-ups, clipped pieces, barycentrics, texture derivatives and shading
// models are the forward path's own. The deferred frame must shade from a fraction of the
// triangles (only those seen) and at any thread count give the same bits.
TEST(VisibilityShade, GivesTheForwardFramesBitsWhereItSeesWhatTheDepthTestKept) {
    constexpr int kWidth = 150, kHeight = 100;
    for (const uint32_t seed : {1u, 2u, 3u}) {
        const RandomScene scene(seed);
        const std::vector<DrawCall> draws = scene.draws();
        for (const int samples : {1, 4}) {
            const std::string where = "seed " + std::to_string(seed) + ", " + std::to_string(samples) + " samples";
            raster::Pipeline forward;
            forward.beginFrame(frame(kWidth, kHeight, samples));
            for (const DrawCall& d : draws) forward.draw(d);
            forward.endFrame();
            const raster::VisibilityBuffer seen = visibilityOfForwardFrame(draws, kWidth, kHeight, samples);
            ASSERT_GT(forward.stats().counters.trianglesClipped, 10u) << where;
            for (const ThreadCount count : kThreadCounts) {
                ThreadCountScope threads(count);
                raster::Pipeline deferred;
                deferred.beginDeferredFrame(frame(kWidth, kHeight, samples));
                for (const DrawCall& d : draws) deferred.draw(d);
                const raster::VisibilityShadeStats stats = deferred.shadeVisible(seen);
                deferred.endFrame();
                EXPECT_EQ(stats.samplesWithoutSetUp, 0u) << where;
                EXPECT_GT(stats.trianglesSeen, 100u) << where;
                EXPECT_LT(stats.trianglesSeen, forward.stats().counters.trianglesSetUp) << where;
                int seenSamples = 0, mismatches = 0;
                for (int y = 0; y < kHeight; ++y)
                    for (int x = 0; x < kWidth; ++x)
                        for (int s = 0; s < samples; ++s) {
                            const glm::vec4 a = sampleColor(forward.framebuffer(), x, y, s);
                            const glm::vec4 b = sampleColor(deferred.framebuffer(), x, y, s);
                            seenSamples += seen.draw[(size_t(y) * kWidth + x) * samples + s] != raster::VisibilityBuffer::kNone;
                            const bool same = std::memcmp(&a, &b, sizeof a) == 0 &&
                                              sampleDepthKey(forward.framebuffer(), x, y, s) ==
                                                  sampleDepthKey(deferred.framebuffer(), x, y, s);
                            if (!same && mismatches++ < 3)
                                ADD_FAILURE() << where << ", " << count.threads << " threads: sample " << s << " of (" << x
                                              << ", " << y << ") is (" << b.r << ", " << b.g << ", " << b.b << ", " << b.a
                                              << "), the forward frame's (" << a.r << ", " << a.g << ", " << a.b << ", "
                                              << a.a << ")";
                        }
                EXPECT_EQ(mismatches, 0) << where;
                EXPECT_GT(seenSamples, kWidth * kHeight * samples / 2) << where;
            }
        }
    }
}

// Samples the buffer leaves empty keep the clear colour and depth; a sample naming a triangle the
// frame does not have is refused, not read out of bounds.
TEST(VisibilityShade, EmptySamplesKeepTheClearAndUnknownTrianglesAreRefused) {
    const RandomScene scene(4);
    const std::vector<DrawCall> draws = scene.draws();
    raster::FramebufferDesc desc = frame(40, 30, 1);
    desc.clearColor = glm::vec4(0.25f, 0.5f, 0.75f, 1.0f);
    raster::Pipeline p;
    p.beginDeferredFrame(desc);
    for (const DrawCall& d : draws) p.draw(d);
    raster::VisibilityBuffer seen;
    seen.reset(40, 30, 1);
    p.shadeVisible(seen);
    p.endFrame();
    for (int y = 0; y < 30; ++y)
        for (int x = 0; x < 40; ++x) {
            ASSERT_EQ(sampleColor(p.framebuffer(), x, y, 0), desc.clearColor);
            ASSERT_EQ(sampleDepthKey(p.framebuffer(), x, y, 0), 1.0f);
        }
    p.beginDeferredFrame(desc);
    for (const DrawCall& d : draws) p.draw(d);
    seen.draw[5] = 1, seen.triangle[5] = uint32_t(draws[1].triangleCount());
    EXPECT_THROW(p.shadeVisible(seen), std::invalid_argument);
    seen.draw[5] = 3, seen.triangle[5] = 0;
    EXPECT_THROW(p.shadeVisible(seen), std::invalid_argument);
}

}  // namespace
}  // namespace cuberille::testing
