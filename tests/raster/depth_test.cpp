// Depth-tested rendering: hierarchical Z is only an acceleration. Random depth-tested scenes
// (interpenetrating, nearly coplanar, clipped by near and far) render bit for bit the same with
// it and without it, for every sample count, in every depth-write mode, in both depth
// conventions; and reversed depth keeps apart what standard float depth merges.

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <span>

#include <glm/gtc/matrix_transform.hpp>

#include "raster/pipeline.h"
#include "raster/resolve.h"
#include "scene/camera.h"
#include "tests/raster/test_support.h"

namespace cuberille::testing {
namespace {

struct RandomDepthScene {
    std::vector<glm::vec3> positions;
    std::vector<glm::vec4> colors;

    explicit RandomDepthScene(uint32_t seed) {
        std::mt19937 rng(seed);
        std::uniform_real_distribution<float> u(-1.0f, 1.0f);
        const int count = std::uniform_int_distribution<int>(5, 60)(rng);
        for (int i = 0; i < count; ++i) {
            const glm::vec3 c(u(rng) * 3.0f, u(rng) * 2.0f, -5.0f + u(rng) * 4.5f);
            const float size = 0.3f + 2.5f * (u(rng) + 1.0f);
            for (int k = 0; k < 3; ++k)
                positions.push_back(c + size * glm::vec3(u(rng), u(rng), 0.3f * u(rng)));
            colors.emplace_back(float(i + 1) / 64.0f, 0.5f, 1.0f - float(i + 1) / 64.0f, 1.0f);
        }
        // A pair of nearly coplanar large triangles: depth ties and near-ties.
        for (int k = 0; k < 2; ++k) {
            const float z = -4.0f + k * 1e-5f;
            positions.insert(positions.end(), {{-6, -4, z}, {6, -4, z - 0.5f}, {0, 5, z + 0.3f}});
            colors.emplace_back(0.9f, 0.1f * k, 0.1f, 1.0f);
        }
    }
};

// The camera's projection at the origin looking down -z, in either convention (the real
// scene::Camera code, which builds the reversed matrix directly).
glm::mat4 clipFromView(float fovYRadians, float aspect, float nearPlane, float farPlane,
                       raster::DepthConvention convention) {
    scene::Camera c;
    c.position = glm::vec3(0.0f);
    c.target = glm::vec3(0, 0, -1);
    c.verticalFovDegrees = glm::degrees(fovYRadians);
    c.nearPlane = nearPlane;
    c.farPlane = farPlane;
    c.reversedDepth = convention == raster::DepthConvention::Reversed;
    return c.clipFromWorld(aspect);
}

raster::Image render(const RandomDepthScene& s, int samples, bool hiz, bool depthWrite, bool depthTest,
                     raster::PipelineStats* stats = nullptr,
                     raster::DepthConvention convention = raster::DepthConvention::Standard,
                     bool tightenBetweenDraws = false) {
    raster::DrawCall d;
    d.clipFromObject = clipFromView(1.0f, 1.5f, 0.5f, 8.0f, convention);
    d.positions = s.positions;
    d.triangleColors = s.colors;
    d.state.depthTest = depthTest;
    d.state.depthWrite = depthWrite;
    raster::FramebufferDesc desc = frame(150, 100, samples);
    desc.hierarchicalDepth = hiz;
    desc.depthConvention = convention;
    raster::Pipeline p;
    p.beginFrame(desc);
    // Two draws: the second sees the first's depths (and its hierarchical Z bounds).
    p.draw(d);
    if (tightenBetweenDraws) p.flushAndTightenHierarchicalDepth();
    d.state.depthTest = true;
    d.state.depthWrite = true;
    p.draw(d);
    p.endFrame();
    if (stats) *stats = p.stats();
    raster::Image img;
    raster::resolveColor(p.framebuffer(), img);
    return img;
}

// `scenes` random scenes in every depth-test/write mode render bit for bit the same with hierarchical
// Z and without it, and hierarchical Z rejects some blocks along the way.
void expectHierarchicalDepthChangesNothing(int samples, raster::DepthConvention convention, uint32_t scenes,
                                           uint32_t seedStride) {
    uint64_t culled = 0;
    for (uint32_t seed = 1; seed <= scenes; ++seed) {
        const RandomDepthScene s(seed * seedStride + samples);
        for (auto [test, write] : {std::pair{true, true}, std::pair{true, false}, std::pair{false, true}}) {
            raster::PipelineStats withStats, withoutStats, tightenedStats;
            const raster::Image with = render(s, samples, true, write, test, &withStats, convention);
            const raster::Image without = render(s, samples, false, write, test, &withoutStats, convention);
            // The bounds made exact between the draws (flushAndTightenHierarchicalDepth).
            const raster::Image tightened = render(s, samples, true, write, test, &tightenedStats, convention, true);
            ASSERT_EQ(with.rgba, without.rgba) << "seed " << seed << " test " << test << " write " << write;
            ASSERT_EQ(tightened.rgba, without.rgba) << "seed " << seed << " test " << test << " write " << write;
            ASSERT_EQ(withStats.counters.samplesPassed, withoutStats.counters.samplesPassed);
            ASSERT_EQ(tightenedStats.counters.samplesPassed, withoutStats.counters.samplesPassed);
            ASSERT_GE(tightenedStats.counters.blocksDepthCulled, withStats.counters.blocksDepthCulled)
                << "exact bounds reject at least what the back end's own bounds reject";
            culled += withStats.counters.blocksDepthCulled;
        }
    }
    EXPECT_GT(culled, 0u) << "the scenes must exercise hierarchical Z";
}

class HierarchicalDepth : public ::testing::TestWithParam<int> {};

TEST_P(HierarchicalDepth, NeverChangesTheImage) {
    expectHierarchicalDepthChangesNothing(GetParam(), raster::DepthConvention::Standard, 60, 7919u);
}

TEST_P(HierarchicalDepth, NeverChangesTheImageWithReversedDepth) {
    expectHierarchicalDepthChangesNothing(GetParam(), raster::DepthConvention::Reversed, 30, 104729u);
}

// After flushAndTightenHierarchicalDepth, each 8x8 block's bound is the largest key any of its
// samples inside the image holds (a 150x100 frame: tiles and blocks cut by both edges), and a block
// of a tile nothing drew into reads as the clear key.
TEST_P(HierarchicalDepth, TighteningSetsEachBlockToTheFarthestKeyItsSamplesHold) {
    const int samples = GetParam();
    for (raster::DepthConvention convention : {raster::DepthConvention::Standard, raster::DepthConvention::Reversed})
        for (uint32_t seed = 1; seed <= 8; ++seed) {
            const RandomDepthScene s(seed * 31u + uint32_t(samples));
            raster::DrawCall d;
            d.clipFromObject = clipFromView(1.0f, 1.5f, 0.5f, 8.0f, convention);
            d.positions = s.positions;
            d.triangleColors = s.colors;
            raster::FramebufferDesc desc = frame(150, 100, samples);
            desc.depthConvention = convention;
            raster::Pipeline p;
            p.beginFrame(desc);
            // Every other scene only its first five triangles: some tiles stay untouched. The
            // triangles come in two flushes, each followed by a tightening, so the second
            // tightens the tiles the second part reached and keeps the others' bounds.
            const size_t triangles = seed % 2 ? s.positions.size() / 3 : 5;
            d.positions = std::span(s.positions).first(3 * (triangles / 2));
            d.triangleColors = std::span(s.colors).first(triangles / 2);
            p.draw(d);
            p.flushAndTightenHierarchicalDepth();
            d.positions = std::span(s.positions).subspan(3 * (triangles / 2), 3 * (triangles - triangles / 2));
            d.triangleColors = std::span(s.colors).subspan(triangles / 2, triangles - triangles / 2);
            p.draw(d);
            p.flushAndTightenHierarchicalDepth();
            const raster::Framebuffer& fb = p.framebuffer();
            int touched = 0;
            for (int by = 0; by < fb.blocksY(); ++by)
                for (int bx = 0; bx < fb.blocksX(); ++bx) {
                    const int tile = (by * raster::kBlockSizePixels / raster::kTileSizePixels) * fb.tilesX() +
                                     bx * raster::kBlockSizePixels / raster::kTileSizePixels;
                    float farthest = raster::clearDepthKey(desc);
                    if (fb.tileTouched(tile)) {
                        ++touched;
                        farthest = -std::numeric_limits<float>::infinity();
                        for (int y = by * 8; y < std::min(by * 8 + 8, fb.height()); ++y)
                            for (int x = bx * 8; x < std::min(bx * 8 + 8, fb.width()); ++x)
                                for (int k = 0; k < samples; ++k)
                                    farthest = std::max(farthest, fb.tileDepth(tile)[((y % 64) * 64 + x % 64) * samples + k]);
                    }
                    ASSERT_EQ(fb.farthestDepthKeyOfBlock(bx, by), farthest) << "block " << bx << "," << by << " seed " << seed;
                }
            EXPECT_GT(touched, 0);
            p.endFrame();
        }
}

INSTANTIATE_TEST_SUITE_P(SampleCounts, HierarchicalDepth, ::testing::Values(1, 2, 4, 8, 16),
                         [](const auto& info) { return std::to_string(info.param) + "x"; });

// Ordinary ranges: both conventions draw the same surfaces. They could differ only where two
// surfaces meet within a rounding of each other; these scenes have no such place.
TEST(ReversedDepth, DrawsWhatStandardDepthDrawsOnOrdinaryScenes) {
    size_t differing = 0, pixels = 0;
    for (uint32_t seed = 1; seed <= 20; ++seed) {
        const RandomDepthScene s(seed * 31u);
        const raster::Image a = render(s, 4, true, true, true);
        const raster::Image b = render(s, 4, true, true, true, nullptr, raster::DepthConvention::Reversed);
        for (size_t i = 0; i < a.rgba.size(); i += 4) {
            ++pixels;
            differing += !std::equal(a.rgba.begin() + i, a.rgba.begin() + i + 4, b.rgba.begin() + i);
        }
    }
    // Measured: none of the 300,000 pixels (0.2% were allowed): where these scenes' triangles
    // meet, their depths are far enough apart for both conventions to order them alike.
    EXPECT_EQ(differing, 0u) << differing << " of " << pixels;
}

// Near 1e-4 and far 1e7: at 100 units standard depth sits within a few ULPs of 1 and two
// surfaces half a unit apart round to the same value, so the draw order decides (the documented
// limit of Depth.ExtremeRangeKeepsOrder). Reversed depth puts them near 1e-6, where float still has
// 24 bits to tell them apart, so the nearer one wins in either order.
TEST(ReversedDepth, KeepsApartSurfacesStandardDepthMerges) {
    auto centre = [](raster::DepthConvention convention, bool nearFirst) {
        raster::DrawCall d;
        d.clipFromObject = clipFromView(0.8f, 1.0f, 1e-4f, 1e7f, convention);
        std::vector<glm::vec3> positions;
        std::vector<glm::vec4> colors;
        auto quad = [&](float z, glm::vec4 color) {
            const float h = 0.3f * z;
            positions.insert(positions.end(), {{-h, -h, -z}, {h, -h, -z}, {h, h, -z}, {-h, -h, -z}, {h, h, -z}, {-h, h, -z}});
            colors.insert(colors.end(), 2, color);
        };
        if (nearFirst) quad(100.0f, {1, 0, 0, 1});
        quad(100.5f, {0, 1, 0, 1});
        if (!nearFirst) quad(100.0f, {1, 0, 0, 1});
        d.positions = positions;
        d.triangleColors = colors;
        raster::FramebufferDesc desc = frame(32, 32, 1);
        desc.depthConvention = convention;
        raster::Pipeline p;
        drawFrame(p, desc, d);
        raster::Image img;
        raster::resolveColor(p.framebuffer(), img);
        return glm::vec4(img.pixel(16, 16)[0], img.pixel(16, 16)[1], img.pixel(16, 16)[2], 1.0f);
    };
    const glm::vec4 red(1, 0, 0, 1);
    EXPECT_EQ(centre(raster::DepthConvention::Reversed, true), red);
    EXPECT_EQ(centre(raster::DepthConvention::Reversed, false), red);
    // The limit reversed depth lifts: standard depth lets the later draw lose a tie it should win.
    EXPECT_NE(centre(raster::DepthConvention::Standard, false), red);
}

// ---- depth-only targets (shadow maps) ----------------------------------------------------------

/// The random scene's depths, per pixel, drawn into a target with or without colour storage,
/// with colour writes off (a depth pass, with its own full-block loop at one sample) or on (the
/// general path).
std::vector<float> depthsOf(const RandomDepthScene& s, int samples, bool colorAttachment, raster::Pipeline& p,
                            bool colorWrites = false) {
    raster::DrawCall d;
    d.clipFromObject = clipFromView(1.0f, 1.5f, 0.5f, 8.0f, raster::DepthConvention::Standard);
    d.positions = s.positions;
    d.triangleColors = s.colors;
    d.state.colorWriteMask = colorWrites ? raster::kWriteAll : 0;
    raster::FramebufferDesc desc = frame(150, 100, samples);
    desc.colorAttachment = colorAttachment;
    drawFrame(p, desc, d);
    std::vector<float> depth;
    raster::resolveDepthPlane(p.framebuffer(), depth);
    return depth;
}

TEST(DepthOnlyTarget, StoresTheDepthsAColourTargetStores) {
    for (uint32_t seed = 1; seed <= 20; ++seed)
        for (const int samples : {1, 4}) {
            const RandomDepthScene s(seed);
            raster::Pipeline withColor, depthOnly;
            const std::vector<float> want = depthsOf(s, samples, true, withColor, true);
            ASSERT_EQ(depthsOf(s, samples, false, depthOnly), want) << "seed " << seed << ", " << samples << " samples";
            EXPECT_EQ(depthOnly.stats().counters.samplesTested, withColor.stats().counters.samplesTested);
            EXPECT_EQ(depthOnly.stats().counters.samplesPassed, withColor.stats().counters.samplesPassed);
            EXPECT_EQ(depthOnly.framebuffer().tileColor(0), nullptr) << "no colour storage";
            size_t drawn = 0;
            for (const float d : want) drawn += d < 1.0f;
            EXPECT_GT(drawn, 0u);
        }
}

TEST(DepthOnlyTarget, RefusesColourWritesAndResolvesToTheClearColour) {
    const RandomDepthScene s(3);
    raster::Pipeline p;
    (void)depthsOf(s, 1, false, p);
    raster::Image image;
    raster::resolveColor(p.framebuffer(), image);
    EXPECT_EQ(image.pixel(75, 50)[0], p.framebuffer().desc().clearColor.r);
    raster::DrawCall d;
    d.positions = s.positions;
    d.triangleColors = s.colors;  // colour writes on (the default)
    p.beginFrame(p.framebuffer().desc());
    EXPECT_THROW(p.draw(d), std::invalid_argument);
}

/// Two window-space rectangles, depth only, at 4 samples on 16x16 pixels: `left` spans x < 8.5
/// on every row, `right` x > 8.5 on rows 0-7 (the DepthView tests' geometry).
void drawMeetingRectangles(raster::Pipeline& p, raster::DepthConvention convention, float left, float right) {
    const std::vector<glm::vec3> positions = {{0, 0, left},  {8.5f, 0, left},  {8.5f, 16, left},
                                              {0, 0, left},  {8.5f, 16, left}, {0, 16, left},
                                              {8.5f, 0, right}, {16, 0, right}, {16, 8, right},
                                              {8.5f, 0, right}, {16, 8, right}, {8.5f, 8, right}};
    raster::DrawCall d;
    d.space = raster::PositionSpace::Window;
    d.positions = positions;
    d.state.colorWriteMask = 0;
    raster::FramebufferDesc desc = frame(16, 16, 4);
    desc.depthConvention = convention;
    drawFrame(p, desc, d);
}

TEST(DepthView, EachPixelIsTheMeanOfItsSampleDepthsReadAsStandardDepth) {
    // Two window-space rectangles meet on the line x = 8.5 through column 8's centres: of the 4x
    // samples, (-2,-6)/16 and (-6,2)/16 lie left of it, (6,-2)/16 and (2,6)/16 right. The left
    // one (depth 0.25) spans every row, the right one (0.75) rows 0-7 only, so pixel (8, y)
    // holds two samples of each for y < 8 and two of the left and two cleared below. Reversed
    // depth stores the negated depth as its key; the view reads it back as standard depth,
    // 1 - the reversed depth, and a cleared sample as 1 (far) in both.
    for (const auto convention : {raster::DepthConvention::Standard, raster::DepthConvention::Reversed}) {
        const bool reversed = convention == raster::DepthConvention::Reversed;
        const float left = 0.25f, right = 0.75f;
        raster::Pipeline p;
        drawMeetingRectangles(p, convention, left, right);
        raster::Image view;
        raster::resolveDepth(p.framebuffer(), view);
        auto seen = [&](float z) { return reversed ? 1.0f - z : z; };  // a stored depth as the view reads it
        const float far = 1.0f;
        for (int y = 0; y < 16; ++y)
            for (int x = 0; x < 16; ++x) {
                const float rightSide = y < 8 ? seen(right) : far;
                const float expected = x < 8    ? seen(left)
                                       : x == 8 ? float((2.0 * double(seen(left)) + 2.0 * double(rightSide)) / 4.0)
                                                : rightSide;
                ASSERT_EQ(view.pixel(x, y)[0], expected) << x << "," << y << (reversed ? " reversed" : " standard");
                ASSERT_EQ(view.pixel(x, y)[1], expected);
            }
    }
}

// The depth view for people: the distance along the view axis each stored depth stands for,
// inverted from the perspective depth d = f (D - n) / ((f - n) D), averaged over covered samples
// only, with the covered fraction as alpha. The geometry of the test above: column 8 holds two
// samples of the left rectangle, and below row 8 two cleared ones.
TEST(DepthView, ViewDistanceInvertsThePerspectiveDepthOverCoveredSamples) {
    const double n = 0.5, f = 10.0;
    auto distance = [&](double d) { return float(f * n / (f - d * (f - n))); };
    for (const auto convention : {raster::DepthConvention::Standard, raster::DepthConvention::Reversed}) {
        const bool reversed = convention == raster::DepthConvention::Reversed;
        const float left = 0.25f, right = 0.75f;
        raster::Pipeline p;
        drawMeetingRectangles(p, convention, left, right);
        raster::Image view;
        raster::resolveViewDistance(p.framebuffer(), float(n), float(f), view);
        // A window depth as the resolve reads its key back: reversed stores -z, read as 1 - z.
        auto seen = [&](float z) { return reversed ? 1.0 - double(z) : double(z); };
        auto D = [&](float z) { return f * n / (f - seen(z) * (f - n)); };  // in double, as the resolve sums
        for (int y = 0; y < 16; ++y)
            for (int x = 0; x < 16; ++x) {
                const float* px = view.pixel(x, y);
                if (x < 8) {
                    EXPECT_EQ(px[0], distance(seen(left))) << x << "," << y;
                    EXPECT_EQ(px[3], 1.0f);
                } else if (x == 8) {
                    const float both = float((2 * D(left) + (y < 8 ? 2 * D(right) : 0.0)) / (y < 8 ? 4 : 2));
                    EXPECT_EQ(px[0], both) << x << "," << y;
                    EXPECT_EQ(px[3], y < 8 ? 1.0f : 0.5f) << x << "," << y;
                } else {
                    EXPECT_EQ(px[0], y < 8 ? distance(seen(right)) : 0.0f) << x << "," << y;
                    EXPECT_EQ(px[3], y < 8 ? 1.0f : 0.0f) << x << "," << y;
                }
            }
    }
}

// ---- plain passes: depth and a flat colour at one sample (visibility buffers, shadow maps) -------

/// A dense patch of small triangles over a few larger ones, as a scan looks from afar: most
/// triangles fall between pixel centres or cover one or two, some cover whole blocks.
RandomDepthScene denseScene(uint32_t seed) {
    RandomDepthScene s(seed);
    std::mt19937 rng(seed * 7919u);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (int i = 0; i < 4000; ++i) {
        const glm::vec3 c(u(rng) * 2.5f, u(rng) * 1.6f, -4.5f + u(rng));
        const float size = 0.004f + 0.03f * (u(rng) + 1.0f);
        for (int k = 0; k < 3; ++k) s.positions.push_back(c + size * glm::vec3(u(rng), u(rng), u(rng)));
        s.colors.emplace_back(float(i % 251) / 251.0f, float(i / 251) / 16.0f, 0.25f, 1.0f);
    }
    return s;
}

struct PassResult {
    std::vector<float> depth;
    std::vector<glm::vec4> colour;  // per pixel, row-major (empty for depth-only targets)
    raster::StageCounters counters;
};

/// The scene drawn at one sample with depth test and write; `general` records overdraw, which
/// keeps the back end on its general path (queue, shader, output merge) for the same result.
PassResult drawPlain(const RandomDepthScene& s, bool colour, bool general) {
    raster::DrawCall d;
    d.clipFromObject = clipFromView(1.0f, 1.5f, 0.5f, 8.0f, raster::DepthConvention::Standard);
    d.positions = s.positions;
    d.triangleColors = s.colors;
    d.state.shading = raster::ShadingModel::ConstantColor;
    d.state.colorWriteMask = colour ? raster::kWriteAll : 0;
    raster::FramebufferDesc desc = frame(150, 100, 1);
    desc.colorAttachment = colour;
    desc.recordOverdraw = general;
    raster::Pipeline p;
    drawFrame(p, desc, d);
    PassResult r;
    raster::resolveDepthPlane(p.framebuffer(), r.depth);
    r.counters = p.stats().counters;
    if (!colour) return r;
    const raster::Framebuffer& fb = p.framebuffer();
    for (int y = 0; y < fb.height(); ++y)
        for (int x = 0; x < fb.width(); ++x) r.colour.push_back(sampleColor(fb, x, y, 0));
    return r;
}

TEST(PlainPass, StoresWhatTheGeneralPathStoresBitForBit) {
    raster::StageCounters paths;
    for (uint32_t seed = 1; seed <= 12; ++seed) {
        const RandomDepthScene s = denseScene(seed);
        for (const bool colour : {true, false}) {
            const PassResult plain = drawPlain(s, colour, false), general = drawPlain(s, colour, true);
            ASSERT_EQ(plain.depth, general.depth) << "seed " << seed << (colour ? ", flat colour" : ", depth only");
            ASSERT_EQ(plain.colour, general.colour) << "seed " << seed;
            EXPECT_EQ(plain.counters.samplesTested, general.counters.samplesTested);
            EXPECT_EQ(plain.counters.samplesPassed, general.counters.samplesPassed);
            EXPECT_EQ(plain.counters.pixelsShaded, general.counters.pixelsShaded);
            paths += plain.counters;
        }
    }
    // Both fine-stage entries (small triangles, partial blocks) and full blocks were drawn.
    EXPECT_GT(paths.smallTriangleEntries, 0u);
    EXPECT_GT(paths.blocksPartial, 0u);
    EXPECT_GT(paths.blocksFull, 0u);
}

TEST(Setup, TrianglesBetweenSampleCentresAreDroppedBeforeBinning) {
    // Window-space triangles inside pixel (3, 3) whose bounds hold its centre (3.5, 3.5): one
    // passes below it (hypotenuse x + y = 6.9), one covers it (x + y = 7.05).
    auto drawOne = [](std::vector<glm::vec3> positions) {
        raster::DrawCall d;
        d.space = raster::PositionSpace::Window;
        d.positions = positions;
        d.state.depthTest = false;
        raster::Pipeline p;
        drawFrame(p, frame(8, 8, 1), d);
        return p.stats().counters;
    };
    const raster::StageCounters missing = drawOne({{3.1f, 3.1f, 0.5f}, {3.8f, 3.1f, 0.5f}, {3.1f, 3.8f, 0.5f}});
    EXPECT_EQ(missing.trianglesNoSamples, 1u);
    EXPECT_EQ(missing.trianglesSetUp, 0u);
    EXPECT_EQ(missing.binEntries, 0u);
    const raster::StageCounters covering = drawOne({{3.1f, 3.1f, 0.5f}, {3.95f, 3.1f, 0.5f}, {3.1f, 3.95f, 0.5f}});
    EXPECT_EQ(covering.trianglesSetUp, 1u);
    EXPECT_EQ(covering.samplesPassed, 1u);
}

TEST(Snapping, TiesGoToTheEvenSubpixel) {
    // Direct3D's float-to-fixed rule: exact halves of a subpixel round to the even neighbour,
    // everything else to the nearest; negative coordinates (the guard band) alike.
    const float subpixel = 1.0f / raster::kSubpixelsPerPixel;
    EXPECT_EQ(raster::snapToSubpixels(0.5f * subpixel), 0);
    EXPECT_EQ(raster::snapToSubpixels(1.5f * subpixel), 2);
    EXPECT_EQ(raster::snapToSubpixels(2.5f * subpixel), 2);
    EXPECT_EQ(raster::snapToSubpixels(-0.5f * subpixel), 0);
    EXPECT_EQ(raster::snapToSubpixels(-1.5f * subpixel), -2);
    EXPECT_EQ(raster::snapToSubpixels(-2.5f * subpixel), -2);
    EXPECT_EQ(raster::snapToSubpixels(70.158203125f), 17960);  // 17960.5 subpixels
    EXPECT_EQ(raster::snapToSubpixels(62.6552734375f), 16040);  // 16039.75
    EXPECT_EQ(raster::snapToSubpixels(2.49f * subpixel), 2);
    EXPECT_EQ(raster::snapToSubpixels(2.51f * subpixel), 3);
    // Every tie in a range of coordinates, against the rule written out in integers.
    for (int twice = -4096; twice <= 4096; ++twice) {
        const float v = float(twice) / (2.0f * raster::kSubpixelsPerPixel);
        const int below = (twice - 1) / 2, above = (twice + 1) / 2;  // neighbours of an odd half
        const int expected = twice % 2 == 0 ? twice / 2 : (below % 2 == 0 ? below : above);
        ASSERT_EQ(raster::snapToSubpixels(v), expected) << twice << " half-subpixels";
    }
}

TEST(Setup, AThinSliverSnappedAsAGpuSnapsKeepsItsSamples) {
    // A sliver whose snapped vertices (16262, 14119), (20642, 16040), (25022, 17960) have twice
    // the area -4380: at pixel (85, 64), 4x sample 2 (-6, 2)/16, its edge functions are 1630,
    // 480 and 2270 (written out below), strictly inside, so set-up must keep it and that sample
    // must be covered. Rounding the tie 17960.5 up instead collapses it to zero area.
    const int64_t x[3] = {16262, 20642, 25022}, y[3] = {14119, 16040, 17960};
    const int64_t sx = 85 * 256 + 128 - 6 * 16, sy = 64 * 256 + 128 + 2 * 16;
    auto edge = [&](int i, int j) { return (x[j] - x[i]) * (sy - y[i]) - (y[j] - y[i]) * (sx - x[i]); };
    const int64_t doubleArea = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
    ASSERT_EQ(doubleArea, -4380);
    const int64_t e[3] = {-edge(1, 2), -edge(2, 0), -edge(0, 1)};  // inside is > 0 for this winding
    ASSERT_GT(std::min({e[0], e[1], e[2]}), 0);

    const std::vector<glm::vec3> positions = {{63.5234375f, 55.15234375f, 0.5f},
                                              {80.6328125f, 62.6552734375f, 0.5f},
                                              {97.7421875f, 70.158203125f, 0.5f}};
    raster::DrawCall d;
    d.space = raster::PositionSpace::Window;
    d.positions = positions;
    d.state.depthTest = false;
    d.state.constantColor = glm::vec4(1.0f);
    d.state.shading = raster::ShadingModel::ConstantColor;
    raster::Pipeline p;
    drawFrame(p, frame(256, 192, 4), d);
    EXPECT_EQ(p.stats().counters.trianglesDegenerate, 0u);
    EXPECT_EQ(p.stats().counters.trianglesSetUp, 1u);
    EXPECT_EQ(sampleColor(p.framebuffer(), 85, 64, 2), glm::vec4(1.0f));
}

}  // namespace
}  // namespace cuberille::testing
