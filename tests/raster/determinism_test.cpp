// Bit-identical images for every thread count and across runs (DESIGN.md, determinism).

#include <gtest/gtest.h>

#include <optional>

#include "apps/render_command.h"
#include "tests/thread_counts.h"

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
            EXPECT_EQ(one.threadsRan, 1);
            for (const ThreadCount count : {kThreadCounts[1], kThreadCounts[2]}) {
                std::optional<raster::ExactThreadScheduling> exact;
                if (count.exact) exact.emplace();
                const int threads = count.threads;
                const apps::RenderResult many = renderWithThreads(scene, threads, msaa);
                // Seven really ran (more than this machine's cores); TBB's two at most two.
                if (count.exact) EXPECT_EQ(many.threadsRan, threads) << scene;
                else EXPECT_LE(many.threadsRan, threads) << scene;
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
