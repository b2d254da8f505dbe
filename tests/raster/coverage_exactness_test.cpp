// The pipeline's coverage equals the brute-force reference bit for bit, sample for sample, on
// thousands of seeded random scenes for every sample count; the scenes hold every shape set-up
// and the back end treat specially, long near-collinear slivers among them.

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "raster/pipeline.h"
#include "raster/sample_pattern.h"
#include "tests/raster/reference_raster.h"
#include "tests/raster/test_support.h"

namespace cuberille::testing {
namespace {

constexpr int kWidth = 72, kHeight = 40;  // crosses a tile boundary in x
constexpr int kScenesPerSampleCount = 600;

class SceneGenerator {
public:
    explicit SceneGenerator(uint32_t seed) : rng_(seed) {}

    scene::TriScene make() {
        scene::TriScene s;
        const int triangles = uniformInt(1, 14);
        for (int i = 0; i < triangles; ++i) addShape(s, uniformInt(0, 9));
        for (size_t t = 0; t < s.colors.size(); ++t) {
            const float v = float(t + 1) / 64.0f;  // distinct per triangle: overwrites show
            s.colors[t] = glm::vec4(v, 1.0f - v, 0.5f, 1.0f);
        }
        return s;
    }

private:
    int uniformInt(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
    float uniform(float lo, float hi) { return std::uniform_real_distribution<float>(lo, hi)(rng_); }

    glm::vec2 anyPoint() { return {uniform(-6, kWidth + 6), uniform(-6, kHeight + 6)}; }
    // On the 1/256 grid, so exact hits of sample points and edges are frequent.
    glm::vec2 gridPoint() {
        return {uniformInt(-4 * 16, (kWidth + 4) * 16) / 16.0f,
                uniformInt(-4 * 16, (kHeight + 4) * 16) / 16.0f};
    }
    glm::vec2 pixelCentre() { return {uniformInt(-2, kWidth + 2) + 0.5f, uniformInt(-2, kHeight + 2) + 0.5f}; }
    glm::vec2 samplePoint() {
        const auto& sp = raster::standardSamplePattern(16);
        const int s = uniformInt(0, 15);
        return pixelCentre() + glm::vec2(sp.dx[s], sp.dy[s]) / 16.0f;
    }

    static glm::vec2 onHalfSubpixels(glm::vec2 p) { return glm::round(p * 512.0f) / 512.0f; }

    void add(scene::TriScene& s, glm::vec2 a, glm::vec2 b, glm::vec2 c) {
        s.positions.insert(s.positions.end(), {{a, 0}, {b, 0}, {c, 0}});
        s.colors.emplace_back(0.0f);
    }

    void addShape(scene::TriScene& s, int kind) {
        switch (kind) {
            case 0: add(s, anyPoint(), anyPoint(), anyPoint()); break;
            case 1: add(s, gridPoint(), gridPoint(), gridPoint()); break;
            case 2: add(s, pixelCentre(), pixelCentre(), samplePoint()); break;
            case 3: {  // fan around a shared vertex
                const glm::vec2 c = gridPoint();
                glm::vec2 prev = gridPoint();
                for (int i = 0, n = uniformInt(2, 6); i < n; ++i) {
                    const glm::vec2 next = gridPoint();
                    add(s, c, prev, next);
                    prev = next;
                }
                break;
            }
            case 4: {  // strip / small grid with shared edges
                const glm::vec2 o = gridPoint();
                const float cell = uniformInt(8, 80) / 16.0f;
                const int n = uniformInt(1, 3);
                for (int i = 0; i < n; ++i)
                    for (int j = 0; j < n; ++j) {
                        const glm::vec2 p00 = o + cell * glm::vec2(i, j), p10 = o + cell * glm::vec2(i + 1, j);
                        const glm::vec2 p01 = o + cell * glm::vec2(i, j + 1), p11 = o + cell * glm::vec2(i + 1, j + 1);
                        add(s, p00, p10, p11);
                        add(s, p00, p11, p01);
                    }
                break;
            }
            case 5: {  // sliver
                const glm::vec2 a = anyPoint(), b = anyPoint();
                const glm::vec2 n = glm::vec2(-(b - a).y, (b - a).x) * uniform(-0.01f, 0.01f);
                add(s, a, b, glm::mix(a, b, uniform(0, 1)) + n);
                break;
            }
            case 6: {  // zero area: collinear or repeated vertices
                const glm::vec2 a = gridPoint(), b = gridPoint();
                add(s, a, b, uniformInt(0, 1) ? a + 2.0f * (b - a) : a);
                break;
            }
            case 7: {  // far outside the viewport, inside the guard band
                const float far = 30000.0f;
                add(s, {uniform(-far, far), uniform(-far, far)}, {uniform(-far, far), uniform(-far, far)},
                    anyPoint());
                break;
            }
            case 9: {  // long near-collinear sliver: tens of pixels long, a fraction of a sample wide
                // Any orientation; vertices on the 1/512 grid, so half of their coordinates are
                // snapping ties (the tie rule decides whether the snapped area is zero).
                const float angle = uniform(0.0f, 6.2831853f), length = uniform(10.0f, 60.0f);
                const glm::vec2 dir(std::cos(angle), std::sin(angle)), normal(-dir.y, dir.x);
                const float widthPixels = uniform(0.0005f, 0.04f);  // 16x samples are 1/16 px apart
                const glm::vec2 a = onHalfSubpixels(anyPoint()), b = onHalfSubpixels(a + length * dir);
                add(s, a, b, onHalfSubpixels(glm::mix(a, b, uniform(0.05f, 0.95f)) + widthPixels * normal));
                ++longSlivers_;
                break;
            }
            case 8: {  // tiny (sub-pixel)
                const glm::vec2 a = anyPoint();
                add(s, a, a + glm::vec2(uniform(-1, 1), uniform(-1, 1)),
                    a + glm::vec2(uniform(-1, 1), uniform(-1, 1)));
                break;
            }
        }
    }

    std::mt19937 rng_;
    int longSlivers_ = 0;

public:
    int longSlivers() const { return longSlivers_; }
};

class CoverageExactness : public ::testing::TestWithParam<int> {};

TEST_P(CoverageExactness, MatchesBruteForceOnRandomScenes) {
    const int samples = GetParam();
    SceneGenerator gen(1234u + samples);
    raster::Pipeline pipeline;
    raster::StageCounters paths;
    for (int n = 0; n < kScenesPerSampleCount; ++n) {
        const scene::TriScene s = gen.make();
        renderTri(pipeline, s, kWidth, kHeight, samples);
        paths += pipeline.stats().counters;
        const ReferenceImage ref = referenceRasterize(s, kWidth, kHeight, samples);
        int mismatches = 0;
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x)
                for (int k = 0; k < samples; ++k)
                    if (sampleColor(pipeline.framebuffer(), x, y, k) != ref.at(x, y, k)) {
                        if (++mismatches <= 3)
                            ADD_FAILURE() << "scene " << n << " sample (" << x << "," << y << ")#" << k;
                    }
        ASSERT_EQ(mismatches, 0) << "scene " << n << " of seed " << 1234u + samples;
    }
    // Every path of the coarse stage was exercised, and clipping by the guard band too.
    EXPECT_GT(paths.blocksFull, 0u);
    EXPECT_GT(paths.blocksPartial, 0u);
    EXPECT_GT(paths.smallTriangleEntries, 0u);
    EXPECT_GT(paths.trianglesDegenerate, 0u);
    EXPECT_GT(gen.longSlivers(), kScenesPerSampleCount / 2);
}

INSTANTIATE_TEST_SUITE_P(SampleCounts, CoverageExactness, ::testing::Values(1, 2, 4, 8, 16),
                         [](const auto& info) { return std::to_string(info.param) + "x"; });

TEST(FillRule, SharedEdgeCoveredOnce) {
    // Two triangles sharing the diagonal y = x through sample points. Each sample must show the
    // value of the one triangle that owns it, and the samples passed must total one a sample: a
    // sample covered twice would raise the total unless another were left uncovered, which would
    // show the background. On the diagonal the first triangle (x > y) owns it: the diagonal is
    // its left edge (the top-left rule), and the second's right edge.
    const float a = 0.25f, b = 0.75f;
    scene::TriScene s;
    s.positions = {{0, 0, 0}, {8, 0, 0}, {8, 8, 0}, {0, 0, 0}, {8, 8, 0}, {0, 8, 0}};
    s.colors = {glm::vec4(a, a, a, 1.0f), glm::vec4(b, b, b, 1.0f)};
    raster::Pipeline p;
    renderTri(p, s, 8, 8, 16);
    EXPECT_EQ(p.stats().counters.samplesPassed, 8u * 8u * 16u);
    const auto& sp = raster::standardSamplePattern(16);
    int onTheDiagonal = 0;
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x)
            for (int k = 0; k < 16; ++k) {
                const int sx = x * 16 + 8 + sp.dx[k], sy = y * 16 + 8 + sp.dy[k];  // in 1/16 pixel
                onTheDiagonal += sx == sy;
                const float want = sy <= sx ? a : b;
                ASSERT_EQ(sampleColor(p.framebuffer(), x, y, k), glm::vec4(want, want, want, 1.0f))
                    << "pixel " << x << "," << y << " sample " << k;
            }
    EXPECT_GT(onTheDiagonal, 0) << "samples lie exactly on the shared edge";
}

TEST(FillRule, TopAndLeftEdgesOwnTheirSamples) {
    // A square whose four edges pass exactly through pixel centres (x, y = 1.5 and 3.5): the
    // left and top edges own the centres on them, the right and bottom edges do not.
    scene::TriScene s;
    s.positions = {{1.5f, 1.5f, 0}, {3.5f, 1.5f, 0}, {3.5f, 3.5f, 0},
                   {1.5f, 1.5f, 0}, {3.5f, 3.5f, 0}, {1.5f, 3.5f, 0}};
    s.colors = {glm::vec4(1.0f), glm::vec4(1.0f)};
    raster::Pipeline p;
    renderTri(p, s, 6, 6, 1);
    for (int y = 0; y < 6; ++y)
        for (int x = 0; x < 6; ++x) {
            const bool inside = x >= 1 && x <= 2 && y >= 1 && y <= 2;  // top-left owns centre
            EXPECT_EQ(sampleColor(p.framebuffer(), x, y, 0).r, inside ? 1.0f : 0.0f) << x << "," << y;
        }
}

TEST(FillRule, ZeroAreaCoversNothing) {
    scene::TriScene s;
    s.positions = {{0.5f, 0.5f, 0}, {4.5f, 4.5f, 0}, {2.5f, 2.5f, 0}};
    s.colors = {glm::vec4(1.0f)};
    raster::Pipeline p;
    renderTri(p, s, 6, 6, 16);
    EXPECT_EQ(p.stats().counters.samplesPassed, 0u);
    EXPECT_EQ(p.stats().counters.trianglesDegenerate, 1u);
}

}  // namespace
}  // namespace cuberille::testing
