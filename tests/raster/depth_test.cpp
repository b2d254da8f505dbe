// Depth-tested rendering: hierarchical Z is only an acceleration. Random depth-tested scenes
// (interpenetrating, nearly coplanar, clipped by near and far) render bit for bit the same with
// it and without it, for every sample count, in every depth-write mode.

#include <gtest/gtest.h>

#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "raster/pipeline.h"
#include "raster/resolve.h"
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

raster::Image render(const RandomDepthScene& s, int samples, bool hiz, bool depthWrite,
                     bool depthTest, raster::PipelineStats* stats = nullptr) {
    raster::DrawCall d;
    d.clipFromObject = glm::perspectiveRH_ZO(1.0f, 1.5f, 0.5f, 8.0f);
    d.positions = s.positions;
    d.triangleColors = s.colors;
    d.state.depthTest = depthTest;
    d.state.depthWrite = depthWrite;
    raster::FramebufferDesc desc = frame(150, 100, samples);
    desc.hierarchicalDepth = hiz;
    raster::Pipeline p;
    p.beginFrame(desc);
    // Two draws: the second sees the first's depths (and its hierarchical Z bounds).
    p.draw(d);
    d.state.depthTest = true;
    d.state.depthWrite = true;
    p.draw(d);
    p.endFrame();
    if (stats) *stats = p.stats();
    raster::Image img;
    raster::resolveColor(p.framebuffer(), img);
    return img;
}

class HierarchicalDepth : public ::testing::TestWithParam<int> {};

TEST_P(HierarchicalDepth, NeverChangesTheImage) {
    const int samples = GetParam();
    uint64_t culled = 0;
    for (uint32_t seed = 1; seed <= 60; ++seed) {
        const RandomDepthScene s(seed * 7919u + samples);
        for (auto [test, write] : {std::pair{true, true}, std::pair{true, false}, std::pair{false, true}}) {
            raster::PipelineStats withStats, withoutStats;
            const raster::Image with = render(s, samples, true, write, test, &withStats);
            const raster::Image without = render(s, samples, false, write, test, &withoutStats);
            ASSERT_EQ(with.rgba, without.rgba) << "seed " << seed << " test " << test << " write " << write;
            ASSERT_EQ(withStats.counters.samplesPassed, withoutStats.counters.samplesPassed);
            culled += withStats.counters.blocksDepthCulled;
        }
    }
    EXPECT_GT(culled, 0u) << "the scenes must exercise hierarchical Z";
}

INSTANTIATE_TEST_SUITE_P(SampleCounts, HierarchicalDepth, ::testing::Values(1, 2, 4, 8, 16),
                         [](const auto& info) { return std::to_string(info.param) + "x"; });

}  // namespace
}  // namespace cuberille::testing
