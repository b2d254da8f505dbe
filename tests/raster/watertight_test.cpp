// A jittered triangulated grid that covers the viewport covers every sample exactly once, for
// every sample count: no cracks, no double hits, along shared edges and at shared vertices.

#include <gtest/gtest.h>

#include <random>

#include "raster/pipeline.h"
#include "tests/raster/test_support.h"

namespace cuberille::testing {
namespace {

scene::TriScene jitteredGrid(int width, int height, float cell, uint32_t seed) {
    std::mt19937 rng(seed);
    // Up to 0.12 cell per axis keeps every triangle positively oriented (no fold-overs), so
    // the grid stays a true partition of the plane.
    std::uniform_real_distribution<float> jitter(-0.12f * cell, 0.12f * cell);
    const int nx = int(width / cell) + 3, ny = int(height / cell) + 3;
    std::vector<glm::vec2> v(size_t(nx) * ny);
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            const bool border = i == 0 || j == 0 || i == nx - 1 || j == ny - 1;
            v[size_t(j) * nx + i] = glm::vec2((i - 1) * cell, (j - 1) * cell) +
                                    (border ? glm::vec2(0) : glm::vec2(jitter(rng), jitter(rng)));
        }
    scene::TriScene s;
    for (int j = 0; j + 1 < ny; ++j)
        for (int i = 0; i + 1 < nx; ++i) {
            const glm::vec2 a = v[size_t(j) * nx + i], b = v[size_t(j) * nx + i + 1];
            const glm::vec2 c = v[size_t(j + 1) * nx + i], d = v[size_t(j + 1) * nx + i + 1];
            // Alternate the diagonal, and the winding, so both orientations meet.
            if ((i + j) % 2) {
                s.positions.insert(s.positions.end(), {{a, 0}, {b, 0}, {d, 0}, {a, 0}, {c, 0}, {d, 0}});
            } else {
                s.positions.insert(s.positions.end(), {{a, 0}, {c, 0}, {b, 0}, {b, 0}, {c, 0}, {d, 0}});
            }
            s.colors.insert(s.colors.end(), {glm::vec4(1.0f), glm::vec4(1.0f)});
        }
    return s;
}

class Watertight : public ::testing::TestWithParam<int> {};

TEST_P(Watertight, JitteredGridCoversEverySampleExactlyOnce) {
    const int samples = GetParam();
    constexpr int kWidth = 150, kHeight = 90;
    raster::Pipeline p;
    for (float cell : {0.7f, 3.0f, 17.0f}) {
        for (uint32_t seed = 1; seed <= 3; ++seed) {
            renderTri(p, jitteredGrid(kWidth, kHeight, cell, seed), kWidth, kHeight, samples);
            // Covered at least once: no sample keeps the clear colour...
            for (int y = 0; y < kHeight; ++y)
                for (int x = 0; x < kWidth; ++x)
                    for (int s = 0; s < samples; ++s)
                        ASSERT_EQ(sampleColor(p.framebuffer(), x, y, s).r, 1.0f)
                            << "crack at (" << x << "," << y << ")#" << s << " cell " << cell;
            // ...and the additive count of covered samples is exactly one per sample.
            EXPECT_EQ(p.stats().counters.samplesPassed, uint64_t(kWidth) * kHeight * samples)
                << "cell " << cell << " seed " << seed;
        }
    }
}

INSTANTIATE_TEST_SUITE_P(SampleCounts, Watertight, ::testing::Values(1, 2, 4, 8, 16),
                         [](const auto& info) { return std::to_string(info.param) + "x"; });

}  // namespace
}  // namespace cuberille::testing
