// Resolve: k of N samples at value v give float(k·v/N) exactly (DESIGN.md, .tri scenes).

#include <gtest/gtest.h>

#include <bit>

#include "raster/resolve.h"
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

}  // namespace
}  // namespace cuberille::testing
