// Set-up in lanes (raster/setup_lanes.h) must be setupTriangle() bit for bit: the same verdict
// for every triangle and, for an accepted one, the same record and vertex order. Checked here
// on every sample count and cull mode, on random triangles of every size and on the hard ones:
// vertices on sample positions (edges through samples, the fill rule decides), axis-aligned
// edges, collinear vertices, slivers, and coordinates at the guard band's limit where an
// inexact product would show. Runs once per instruction set (tests/CMakeLists.txt).

#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <string>
#include <random>

#include "raster/limits.h"
#include "raster/sample_pattern.h"
#include "raster/setup.h"
#include "raster/setup_lanes.h"

namespace cuberille::testing {
namespace {

using raster::SetupResult;
using raster::WindowVertex;
using Triangle = std::array<WindowVertex, 3>;

/// Depths and 1/w vary with the position, so the depth plane and the vertex order are checked
/// too (a swap of v1 and v2 shows in them).
WindowVertex at(int32_t xSubpixels, int32_t ySubpixels) {
    const float z = float((uint32_t(xSubpixels) * 2654435761u + uint32_t(ySubpixels)) % 1000003u) / 1000003.0f;
    return {xSubpixels, ySubpixels, z, 1.0f / (1.0f + z)};
}

void expectSameRecord(const raster::TriangleSetup& a, const int (&orderA)[3], const raster::TriangleSetup& b,
                      const int (&orderB)[3], const std::string& where) {
    for (int k = 0; k < 3; ++k) {
        ASSERT_EQ(a.edgeA[k], b.edgeA[k]) << where;
        ASSERT_EQ(a.edgeB[k], b.edgeB[k]) << where;
        ASSERT_EQ(a.edgeC[k], b.edgeC[k]) << where;
        ASSERT_EQ(a.fillBias[k], b.fillBias[k]) << where;
        ASSERT_EQ(std::bit_cast<uint32_t>(a.invW[k]), std::bit_cast<uint32_t>(b.invW[k])) << where;
        ASSERT_EQ(orderA[k], orderB[k]) << where;
    }
    ASSERT_EQ(a.backFacing, b.backFacing) << where;
    ASSERT_EQ(a.pixelMinX, b.pixelMinX) << where;
    ASSERT_EQ(a.pixelMinY, b.pixelMinY) << where;
    ASSERT_EQ(a.pixelMaxX, b.pixelMaxX) << where;
    ASSERT_EQ(a.pixelMaxY, b.pixelMaxY) << where;
    ASSERT_EQ(a.originXSubpixels, b.originXSubpixels) << where;
    ASSERT_EQ(a.originYSubpixels, b.originYSubpixels) << where;
    ASSERT_EQ(std::bit_cast<uint32_t>(a.depthAtOrigin), std::bit_cast<uint32_t>(b.depthAtOrigin)) << where;
    ASSERT_EQ(std::bit_cast<uint32_t>(a.depthPerSubpixelX), std::bit_cast<uint32_t>(b.depthPerSubpixelX)) << where;
    ASSERT_EQ(std::bit_cast<uint32_t>(a.depthPerSubpixelY), std::bit_cast<uint32_t>(b.depthPerSubpixelY)) << where;
    ASSERT_EQ(std::bit_cast<uint32_t>(a.depthKeySign), std::bit_cast<uint32_t>(b.depthKeySign)) << where;
    ASSERT_EQ(std::bit_cast<uint64_t>(a.invDoubleArea), std::bit_cast<uint64_t>(b.invDoubleArea)) << where;
}

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

TEST(SetupLanes, VerdictsAndRecordsAreSetupsOnRandomAndHardTriangles) {
    std::mt19937 rng(20261202);
    size_t seen[4] = {};
    for (int samples : {1, 2, 4, 8, 16}) {
        const raster::SamplePattern& sp = raster::standardSamplePattern(samples);
        for (raster::CullMode cull : {raster::CullMode::None, raster::CullMode::Back, raster::CullMode::Front}) {
            for (auto [width, height] : {std::pair{1, 1}, std::pair{7, 3}, std::pair{64, 48}, std::pair{1920, 1080}}) {
                raster::SetupContext context = raster::SetupContext::forDraw(raster::PositionSpace::Window, width, height,
                                                                             sp, cull, 0);
                context.depthKeySign = width == 7 ? -1.0f : 1.0f;  // reversed depth on one size
                const std::vector<Triangle> triangles = hardAndRandomTriangles(width, height, sp, rng);
                for (size_t first = 0; first < triangles.size(); first += raster::kSetupChunkTriangles) {
                    const int count = int(std::min(triangles.size() - first, size_t(raster::kSetupChunkTriangles)));
                    raster::TriangleLanes lanes{};
                    for (int j = 0; j < count; ++j)
                        for (int v = 0; v < 3; ++v) {
                            const WindowVertex& w = triangles[first + j][v];
                            lanes.x[v][j] = w.x, lanes.y[v][j] = w.y, lanes.z[v][j] = w.z, lanes.invW[v][j] = w.invW;
                        }
                    raster::SetupLanes setup;
                    raster::setUpLanes(lanes, count, context, setup);
                    for (int j = 0; j < count; ++j) {
                        const Triangle& t = triangles[first + j];
                        const std::string where = std::to_string(samples) + " samples, cull " + std::to_string(int(cull)) +
                                                  ", " + std::to_string(width) + "x" + std::to_string(height) + ": (" +
                                                  std::to_string(t[0].x) + "," + std::to_string(t[0].y) + ") (" +
                                                  std::to_string(t[1].x) + "," + std::to_string(t[1].y) + ") (" +
                                                  std::to_string(t[2].x) + "," + std::to_string(t[2].y) + ")";
                        raster::TriangleSetup expected;
                        int expectedOrder[3];
                        const SetupResult result = raster::setupTriangle(t[0], t[1], t[2], context, expected, expectedOrder);
                        ASSERT_EQ(int(setup.verdict[j]), int(result)) << where;
                        ++seen[int(result)];
                        if (result != SetupResult::Accepted) continue;
                        raster::TriangleSetup record;
                        int order[3];
                        raster::setupRecord(lanes, setup, j, context, record, order);
                        expectSameRecord(record, order, expected, expectedOrder, where);
                        if (::testing::Test::HasFatalFailure()) return;
                    }
                }
            }
        }
    }
    // Every verdict occurred, so none of the paths went unchecked.
    for (size_t n : seen) EXPECT_GT(n, 1000u);
}

}  // namespace
}  // namespace cuberille::testing
