// Bit-identical images for every thread count and across runs (DESIGN.md, determinism).

#include <gtest/gtest.h>

#include "apps/render_command.h"

namespace cuberille::testing {
namespace {

apps::RenderResult renderWithThreads(const std::string& scene, int threads, int msaa) {
    apps::RenderOptions o;
    o.scene = scene;
    o.width = 320;
    o.height = 200;
    o.msaa = msaa;
    o.threads = threads;
    o.detail = 0.15f;  // keeps the test quick; still tens of thousands of triangles
    return apps::renderScene(o);
}

TEST(Determinism, SameImageForOneTwoAndSevenThreads) {
    for (const char* scene : {"field", "fill"}) {
        for (int msaa : {1, 4}) {
            const apps::RenderResult one = renderWithThreads(scene, 1, msaa);
            for (int threads : {2, 7}) {
                const apps::RenderResult many = renderWithThreads(scene, threads, msaa);
                EXPECT_EQ(one.image.rgba, many.image.rgba) << scene << " " << threads << " threads";
                EXPECT_EQ(one.stats.counters.samplesPassed, many.stats.counters.samplesPassed);
                EXPECT_EQ(one.stats.counters.binEntries, many.stats.counters.binEntries);
            }
        }
    }
}

TEST(Determinism, SameImageAcrossRuns) {
    const apps::RenderResult a = renderWithThreads("field", 0, 4);
    const apps::RenderResult b = renderWithThreads("field", 0, 4);
    EXPECT_EQ(a.image.rgba, b.image.rgba);
}

}  // namespace
}  // namespace cuberille::testing
