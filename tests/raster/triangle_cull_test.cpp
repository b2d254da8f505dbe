// The triangle cull (raster/triangle_cull.h) decides set-up's rejections in lanes; the property
// that makes it safe is that its verdict is setupTriangle()'s for every triangle. Checked here
// on every sample count and cull mode, on random triangles of every size and on the hard ones:
// vertices on sample positions (edges through samples, the fill rule decides), axis-aligned
// edges, collinear vertices, slivers, and coordinates at the guard band's limit where an
// inexact product would show. Runs once per instruction set (tests/CMakeLists.txt).

#include <gtest/gtest.h>

#include <array>
#include <random>

#include "raster/limits.h"
#include "raster/sample_pattern.h"
#include "raster/setup.h"
#include "raster/triangle_cull.h"

namespace cuberille::testing {
namespace {

using raster::CullVerdict;
using raster::SetupResult;
using raster::WindowVertex;
using Triangle = std::array<WindowVertex, 3>;

CullVerdict verdictOf(SetupResult r) {
    switch (r) {
        case SetupResult::Accepted: return CullVerdict::MaySurvive;
        case SetupResult::Degenerate: return CullVerdict::Degenerate;
        case SetupResult::Culled: return CullVerdict::Culled;
        case SetupResult::NoSamples: return CullVerdict::NoSamples;
    }
    return CullVerdict::MaySurvive;
}

WindowVertex at(int32_t xSubpixels, int32_t ySubpixels) { return {xSubpixels, ySubpixels, 0.5f, 1.0f}; }

/// Triangles of every kind the cull must agree on, for a scissor of width x height pixels.
std::vector<Triangle> hardAndRandomTriangles(int width, int height, const raster::SamplePattern& sp, std::mt19937& rng) {
    std::vector<Triangle> out;
    auto uniform = [&](int32_t lo, int32_t hi) { return std::uniform_int_distribution<int32_t>(lo, hi)(rng); };
    const int32_t w = width * raster::kSubpixelsPerPixel, h = height * raster::kSubpixelsPerPixel;
    // A sample position of a pixel near the scissor (inside or just outside).
    auto samplePosition = [&] {
        const int s = uniform(0, sp.count - 1);
        return at(uniform(-2, width + 1) * raster::kSubpixelsPerPixel + raster::kPixelCentreSubpixels +
                      sp.dx[s] * raster::kSampleOffsetUnitSubpixels,
                  uniform(-2, height + 1) * raster::kSubpixelsPerPixel + raster::kPixelCentreSubpixels +
                      sp.dy[s] * raster::kSampleOffsetUnitSubpixels);
    };
    for (int i = 0; i < 3000; ++i) {
        // Tiny: within two pixels of a point, the common case of dense meshes.
        const int32_t cx = uniform(-512, w + 512), cy = uniform(-512, h + 512);
        out.push_back({at(cx + uniform(-512, 512), cy + uniform(-512, 512)), at(cx + uniform(-512, 512), cy + uniform(-512, 512)),
                       at(cx + uniform(-512, 512), cy + uniform(-512, 512))});
        // Sub-pixel: within a quarter pixel.
        out.push_back({at(cx + uniform(-64, 64), cy + uniform(-64, 64)), at(cx + uniform(-64, 64), cy + uniform(-64, 64)),
                       at(cx + uniform(-64, 64), cy + uniform(-64, 64))});
        // Corners on sample positions: edges pass through samples, the fill rule decides.
        out.push_back({samplePosition(), samplePosition(), samplePosition()});
        const WindowVertex a = samplePosition();
        const int32_t d = uniform(1, 3) * raster::kSampleOffsetUnitSubpixels;
        // Axis-aligned right triangles through a sample (top and left edges), both windings.
        out.push_back({a, at(a.x + d, a.y), at(a.x, a.y + d)});
        out.push_back({a, at(a.x, a.y + d), at(a.x + d, a.y)});
        out.push_back({at(a.x - d, a.y), a, at(a.x, a.y - d)});
        // Collinear, and slivers one subpixel off collinear.
        out.push_back({a, at(a.x + d, a.y + 2 * d), at(a.x + 2 * d, a.y + 4 * d)});
        out.push_back({a, at(a.x + d, a.y + 2 * d + 1), at(a.x + 40 * d, a.y + 80 * d)});
        // Anywhere in the frame, large ones included.
        out.push_back({at(uniform(-w, 2 * w), uniform(-h, 2 * h)), at(uniform(-w, 2 * w), uniform(-h, 2 * h)),
                       at(uniform(-w, 2 * w), uniform(-h, 2 * h))});
    }
    // At the guard band's limit (raster/limits.h): products near 2^50, edge values near 2^51.
    constexpr int32_t kFar = (1 << 24) - 1;
    for (int i = 0; i < 500; ++i) {
        out.push_back({at(-kFar + uniform(0, 255), uniform(-kFar, kFar)), at(kFar - uniform(0, 255), uniform(-kFar, kFar)),
                       at(uniform(0, w), uniform(0, h))});
        out.push_back({at(uniform(-kFar, kFar), -kFar), at(uniform(-kFar, kFar), kFar), at(uniform(-kFar, kFar), uniform(-kFar, kFar))});
        // A long sliver crossing the frame, its third vertex a subpixel off the line.
        out.push_back({at(-kFar, -kFar), at(kFar, kFar), at(uniform(0, w), uniform(0, w) + uniform(-1, 1))});
    }
    return out;
}

TEST(TriangleCull, VerdictsAreSetupsOnRandomAndHardTriangles) {
    std::mt19937 rng(20261202);
    size_t seen[4] = {};
    for (int samples : {1, 2, 4, 8, 16}) {
        const raster::SamplePattern& sp = raster::standardSamplePattern(samples);
        for (raster::CullMode cull : {raster::CullMode::None, raster::CullMode::Back, raster::CullMode::Front}) {
            for (auto [width, height] : {std::pair{1, 1}, std::pair{7, 3}, std::pair{64, 48}, std::pair{1920, 1080}}) {
                raster::SetupContext context = raster::SetupContext::forDraw(raster::PositionSpace::Window, width, height,
                                                                             sp, cull, 0);
                const std::vector<Triangle> triangles = hardAndRandomTriangles(width, height, sp, rng);
                for (size_t first = 0; first < triangles.size(); first += raster::kCullChunkTriangles) {
                    const int count = int(std::min(triangles.size() - first, size_t(raster::kCullChunkTriangles)));
                    raster::TriangleLanes lanes{};
                    for (int j = 0; j < count; ++j)
                        for (int v = 0; v < 3; ++v) {
                            lanes.x[v][j] = triangles[first + j][v].x;
                            lanes.y[v][j] = triangles[first + j][v].y;
                        }
                    CullVerdict verdicts[raster::kCullChunkTriangles];
                    raster::cullTriangles(lanes, count, context, verdicts);
                    for (int j = 0; j < count; ++j) {
                        const Triangle& t = triangles[first + j];
                        raster::TriangleSetup setup;
                        int order[3];
                        const CullVerdict expected = verdictOf(raster::setupTriangle(t[0], t[1], t[2], context, setup, order));
                        ASSERT_EQ(int(verdicts[j]), int(expected))
                            << samples << " samples, cull " << int(cull) << ", " << width << "x" << height << ": ("
                            << t[0].x << "," << t[0].y << ") (" << t[1].x << "," << t[1].y << ") (" << t[2].x << ","
                            << t[2].y << ")";
                        ++seen[int(expected)];
                    }
                }
            }
        }
    }
    // Every verdict occurred, so none of the cull's paths went unchecked.
    for (size_t n : seen) EXPECT_GT(n, 1000u);
}

}  // namespace
}  // namespace cuberille::testing
