// Resolve: k of N samples at value v give float(k·v/N) exactly (DESIGN.md, .tri scenes).

#include <gtest/gtest.h>

#include <bit>

#include <cmath>
#include <limits>
#include <vector>

#include "raster/resolve.h"
#include "raster/srgb.h"
#include "tests/raster/test_support.h"

namespace cuberille::testing {
namespace {

TEST(Resolve, PartialCoverageGivesExactFraction) {
    const float v = 0.1f;  // not a dyadic fraction: repeated float addition would round
    for (int samples : {1, 2, 4, 8, 16}) {
        scene::TriScene s;
        s.positions = {{0.3f, 0.2f, 0}, {7.7f, 1.9f, 0}, {2.1f, 7.6f, 0}};
        s.colors = {glm::vec4(v, v, v, 1.0f)};
        raster::Pipeline p;
        renderTri(p, s, 8, 8, samples);
        raster::Image img;
        raster::resolveColor(p.framebuffer(), img);
        for (int y = 0; y < 8; ++y)
            for (int x = 0; x < 8; ++x) {
                int k = 0;
                for (int i = 0; i < samples; ++i) k += sampleColor(p.framebuffer(), x, y, i).r == v;
                EXPECT_EQ(img.pixel(x, y)[0], float(double(k) * double(v) / samples))
                    << x << "," << y << " with " << samples << " samples";
            }
    }
}

// coveredPixels counts each pixel where some sample took a surface: checked against the samples'
// colours (a red triangle over a clear of transparent black) at every sample count, on a frame
// of several tiles with a ragged last row and column.
TEST(Resolve, CoveredPixelsCountsEveryPixelWithASurfaceSample) {
    for (int samples : {1, 4, 16}) {
        scene::TriScene s;
        s.positions = {{3.3f, 2.2f, 0}, {150.7f, 20.9f, 0}, {40.1f, 97.6f, 0}, {100, 90, 0}, {139.5f, 99.5f, 0}, {120, 60, 0}};
        s.colors = {glm::vec4(1, 0, 0, 1), glm::vec4(1, 0, 0, 1)};
        raster::DrawCall draw = s.drawCall();
        draw.state.depthTest = draw.state.depthWrite = true;  // coverage is read from the depth samples
        raster::Pipeline p;
        drawFrame(p, frame(150, 100, samples), draw);
        uint64_t expected = 0;
        for (int y = 0; y < 100; ++y)
            for (int x = 0; x < 150; ++x) {
                bool any = false;
                for (int i = 0; i < samples; ++i) any = any || sampleColor(p.framebuffer(), x, y, i).r == 1.0f;
                expected += any;
            }
        EXPECT_GT(expected, 5000u);
        EXPECT_EQ(raster::coveredPixels(p.framebuffer()), expected) << samples << " samples";
    }
}

TEST(Resolve, UntouchedTilesResolveToClearColor) {
    raster::Pipeline p;
    raster::FramebufferDesc d = frame(200, 100, 4);
    d.clearColor = {0.25f, 0.5f, 0.75f, 1.0f};
    p.beginFrame(d);
    p.endFrame();
    raster::Image img;
    raster::resolveColor(p.framebuffer(), img);
    EXPECT_EQ(img.pixel(150, 70)[2], 0.75f);
}

// Every pixel of every channel, on a frame of ragged tiles where only some tiles are drawn to:
// a touched tile's pixel is its samples' average (summed in double, as the contract says), an
// untouched tile's the clear colour. The resolve writes a tile row at a time with streamed
// stores; this is the check that no row, edge or tile is left out or misplaced.
TEST(Resolve, EveryPixelIsItsSamplesAverageOrTheClearColour) {
    for (int samples : {1, 4, 16}) {
        scene::TriScene s;
        s.positions = {{3.3f, 2.2f, 0}, {120.7f, 20.9f, 0}, {40.1f, 97.6f, 0}};
        s.colors = {glm::vec4(0.1f, 0.7f, 0.3f, 1)};
        raster::Pipeline p;
        raster::FramebufferDesc d = frame(203, 141, samples);
        d.clearColor = {0.25f, 0.5f, 0.75f, 0.125f};
        drawFrame(p, d, s.drawCall());
        raster::Image img;
        raster::resolveColor(p.framebuffer(), img);
        ASSERT_EQ(img.width, 203);
        ASSERT_EQ(img.height, 141);
        const raster::Framebuffer& fb = p.framebuffer();
        int touched = 0, untouched = 0;
        for (int y = 0; y < 141; ++y)
            for (int x = 0; x < 203; ++x) {
                const int tile = (y / raster::kTileSizePixels) * fb.tilesX() + x / raster::kTileSizePixels;
                glm::vec4 expected = d.clearColor;
                if (fb.tileTouched(tile)) {
                    double sum[4] = {0, 0, 0, 0};
                    for (int i = 0; i < samples; ++i)
                        for (int c = 0; c < 4; ++c) sum[c] += sampleColor(fb, x, y, i)[c];
                    for (int c = 0; c < 4; ++c) expected[c] = float(sum[c] / samples);
                }
                (fb.tileTouched(tile) ? touched : untouched)++;
                for (int c = 0; c < 4; ++c)
                    ASSERT_EQ(img.pixel(x, y)[c], expected[c]) << x << "," << y << " channel " << c << ", " << samples << " samples";
            }
        EXPECT_GT(touched, 0);
        EXPECT_GT(untouched, 0);
    }
}

}  // namespace
}  // namespace cuberille::testing

namespace cuberille::testing {
namespace {

/// The reference encoder, straight from IEC 61966-2-1 in double: the number of codes whose
/// decision threshold (the decoded midpoint between two codes, rounded to float as the encoder
/// rounds it) is at or below the value.
int referenceSrgb8(float linear) {
    static const std::vector<float> thresholds = [] {
        std::vector<float> t;
        for (int c = 0; c < 255; ++c) {
            const double encoded = (c + 0.5) / 255.0;
            t.push_back(float(encoded <= 0.04045 ? encoded / 12.92 : std::pow((encoded + 0.055) / 1.055, 2.4)));
        }
        return t;
    }();
    int count = 0;
    for (const float t : thresholds) count += t <= linear;
    return count;
}

TEST(Srgb, EncodingCountsTheThresholdsBelowEachValue) {
    // Every code's threshold and the floats around it, where a lookup shortcut would slip.
    for (int c = 0; c < 255; ++c) {
        const double encoded = (c + 0.5) / 255.0;
        const float t = float(encoded <= 0.04045 ? encoded / 12.92 : std::pow((encoded + 0.055) / 1.055, 2.4));
        uint32_t bits = std::bit_cast<uint32_t>(t);
        for (uint32_t b = bits - 4; b <= bits + 4; ++b) {
            const float v = std::bit_cast<float>(b);
            ASSERT_EQ(int(raster::encodeSrgb8(v)), referenceSrgb8(v)) << v;
        }
    }
    // A stride through every float in [0, 1] (one in 4099: ~260k values, every octave).
    for (uint32_t b = 0; b <= std::bit_cast<uint32_t>(1.0f); b += 4099) {
        const float v = std::bit_cast<float>(b);
        ASSERT_EQ(int(raster::encodeSrgb8(v)), referenceSrgb8(v)) << v;
    }
    EXPECT_EQ(raster::encodeSrgb8(-0.5f), 0);
    EXPECT_EQ(raster::encodeSrgb8(std::nanf("")), 0);
    EXPECT_EQ(raster::encodeSrgb8(1.0f), 255);
    EXPECT_EQ(raster::encodeSrgb8(3.0f), 255);
    EXPECT_EQ(raster::encodeSrgb8(std::numeric_limits<float>::infinity()), 255);
    // Decoding then encoding every code gives the code back.
    for (int c = 0; c < 256; ++c) EXPECT_EQ(int(raster::encodeSrgb8(raster::decodeSrgb8(uint8_t(c)))), c);
}

}  // namespace
}  // namespace cuberille::testing
