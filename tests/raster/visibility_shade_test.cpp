// The deferred shade (raster/visibility_shade.h): handed the visibility the depth test found, it
// gives the forward frame's samples bit for bit.

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <string>

#include <glm/gtc/matrix_transform.hpp>

#include "raster/pipeline.h"
#include "raster/texture.h"
#include "tests/raster/random_draws.h"
#include "tests/raster/test_support.h"
#include "tests/thread_counts.h"

namespace cuberille::testing {
namespace {

using raster::DrawCall;

float sampleDepthKey(const raster::Framebuffer& fb, int x, int y, int s) {
    const int tile = (y / raster::kTileSizePixels) * fb.tilesX() + x / raster::kTileSizePixels;
    if (!fb.tileTouched(tile)) return raster::clearDepthKey(fb.desc());  // a tile nothing reached reads as cleared
    const size_t i = (size_t(y % raster::kTileSizePixels) * raster::kTileSizePixels + size_t(x % raster::kTileSizePixels)) *
                         fb.samples() + s;
    return fb.tileDepth(tile)[i];
}

// Random scenes through both paths at 1 and 4 samples: each sample's colour and depth key must be
// the same bits, so the set-ups, clipped pieces, barycentrics, texture derivatives and shading
// models are the forward path's own. The deferred frame must shade from a fraction of the
// triangles (only those seen) and at any thread count give the same bits.
TEST(VisibilityShade, GivesTheForwardFramesBitsWhereItSeesWhatTheDepthTestKept) {
    constexpr int kWidth = 150, kHeight = 100;
    for (const uint32_t seed : {1u, 2u, 3u}) {
        const RandomPerspectiveDraws scene(seed);
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

// One pipeline's frames one after another, as the renderer keeps it: each frame reuses the shade
// stage's tables, set-ups and vertex outputs of the one before (raster::VisibilityShadeStorage),
// over other draws, sizes and sample counts, and must give each frame's bits as a pipeline that
// never drew anything does.
TEST(VisibilityShade, AFramesBitsDoNotDependOnTheFramesThePipelineShadedBefore) {
    raster::Pipeline kept;
    struct Frame {
        uint32_t seed;
        int width, height, samples;
    };
    for (const Frame f : {Frame{5, 150, 100, 1}, Frame{6, 90, 140, 1}, Frame{5, 150, 100, 4}, Frame{7, 150, 100, 1},
                          Frame{5, 150, 100, 1}}) {
        const std::string where = "seed " + std::to_string(f.seed) + ", " + std::to_string(f.width) + "x" +
                                  std::to_string(f.height) + ", " + std::to_string(f.samples) + " samples";
        const RandomPerspectiveDraws scene(f.seed);
        const std::vector<DrawCall> draws = scene.draws();
        const raster::VisibilityBuffer seen = visibilityOfForwardFrame(draws, f.width, f.height, f.samples);
        raster::Pipeline fresh;
        for (raster::Pipeline* p : {&kept, &fresh}) {
            p->beginDeferredFrame(frame(f.width, f.height, f.samples));
            for (const DrawCall& d : draws) p->draw(d);
            p->shadeVisible(seen);
            p->endFrame();
        }
        int mismatches = 0;
        for (int y = 0; y < f.height; ++y)
            for (int x = 0; x < f.width; ++x)
                for (int s = 0; s < f.samples; ++s) {
                    const glm::vec4 a = sampleColor(kept.framebuffer(), x, y, s), b = sampleColor(fresh.framebuffer(), x, y, s);
                    mismatches += std::memcmp(&a, &b, sizeof a) != 0 ||
                                  sampleDepthKey(kept.framebuffer(), x, y, s) != sampleDepthKey(fresh.framebuffer(), x, y, s);
                }
        EXPECT_EQ(mismatches, 0) << where;
    }
}

// Samples the buffer leaves empty keep the clear colour and depth; a sample naming a triangle the
// frame does not have is refused, not read out of bounds.
TEST(VisibilityShade, EmptySamplesKeepTheClearAndUnknownTrianglesAreRefused) {
    const RandomPerspectiveDraws scene(4);
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
