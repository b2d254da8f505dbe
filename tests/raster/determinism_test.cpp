// Bit-identical images for every thread count and across runs (DESIGN.md, determinism).

#include <gtest/gtest.h>

#include <optional>

#include "apps/render_command.h"
#include "raster/instruction_set.h"
#include "tests/thread_counts.h"

namespace cuberille::testing {
namespace {

apps::RenderResult renderWithThreads(const std::string& scene, int threads, int msaa,
                                     apps::View view = apps::View::Color) {
    apps::RenderOptions o;
    o.view = view;
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

/// Puts back the instruction set the process started with (CUBERILLE_SIMD's, in the runs
/// ctest makes per instruction set) when a test that switches sets ends.
struct RestoreInstructionSet {
    const std::string initial = raster::activeInstructionSet();
    ~RestoreInstructionSet() { raster::useInstructionSet(initial); }
};

// Every compiled path against the baseline, in one process: each procedural scene (flat,
// Lambert and metallic-roughness shading with textures, alpha modes, sub-pixel triangles,
// full-screen overdraw) at 1, 4 and 16 samples, colour and depth views. The golden and
// exactness suites also run once per instruction set (tests/CMakeLists.txt).
TEST(Determinism, SameImageOnEveryInstructionSet) {
    const RestoreInstructionSet restore;
    const std::vector<std::string> sets = raster::availableInstructionSets();
    ASSERT_EQ(sets.back(), "baseline");
    if (sets.size() == 1) GTEST_SKIP() << "this CPU runs only the baseline path";
    for (const char* scene : {"demo", "field", "subpixel", "fill"}) {
        for (int msaa : {1, 4, 16}) {
            for (const apps::View view : {apps::View::Color, apps::View::Depth}) {
                raster::useInstructionSet("baseline");
                const apps::RenderResult baseline = renderWithThreads(scene, 0, msaa, view);
                ASSERT_GT(baseline.stats.counters.samplesPassed, 0u) << scene;
                for (const std::string& set : sets) {
                    raster::useInstructionSet(set);
                    ASSERT_EQ(raster::activeInstructionSet(), set);
                    const apps::RenderResult r = renderWithThreads(scene, 0, msaa, view);
                    EXPECT_EQ(baseline.image.rgba, r.image.rgba) << scene << " " << msaa << " samples on " << set;
                    EXPECT_EQ(baseline.stats.counters.samplesPassed, r.stats.counters.samplesPassed) << set;
                    EXPECT_EQ(baseline.stats.counters.pixelsShaded, r.stats.counters.pixelsShaded) << set;
                    EXPECT_EQ(baseline.stats.counters.blocksDepthCulled, r.stats.counters.blocksDepthCulled) << set;
                }
            }
        }
    }
}

TEST(InstructionSets, UnknownOrUnsupportedNamesAreRefusedWithTheChoices) {
    const RestoreInstructionSet restore;
    try {
        raster::useInstructionSet("avx1024");
        FAIL() << "accepted an unknown name";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("baseline"), std::string::npos) << e.what();
    }
    raster::useInstructionSet("baseline");
    EXPECT_EQ(raster::activeInstructionSet(), "baseline");
    // Restricting does not shrink what is offered: the widest set can be chosen again.
    const std::vector<std::string> sets = raster::availableInstructionSets();
    raster::useInstructionSet("best");
    EXPECT_EQ(raster::activeInstructionSet(), sets.front());
}

}  // namespace
}  // namespace cuberille::testing
