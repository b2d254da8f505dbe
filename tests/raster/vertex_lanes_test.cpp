// The vertex stage in lanes (raster/vertex_lanes.h) must be the scalar stage bit for bit: glm's
// mat4 * vec4(p, 1), clip.cpp's outcode() after the finiteness test, and projectToWindow() for
// the vertices inside the clip volume. Checked on random cameras and on the hard positions:
// behind the eye, at w near 0 and exactly on the w plane's limit, exactly on the near, far and
// guard-band planes, not finite (NaN, infinities, overflow in the transform), and window
// coordinates that fall exactly half-way between subpixels (the snap's tie goes to even).
// Runs once per instruction set (tests/CMakeLists.txt).

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "raster/clip.h"
#include "raster/sample_pattern.h"
#include "raster/setup.h"
#include "raster/vertex.h"
#include "raster/vertex_lanes.h"

namespace cuberille::testing {
namespace {

using raster::WindowVertex;

struct Case {
    std::string name;
    raster::PositionSpace space;
    glm::mat4 clipFromObject;
    int width, height;
    std::vector<glm::vec3> positions;
};

bool sameBits(float a, float b) { return std::bit_cast<uint32_t>(a) == std::bit_cast<uint32_t>(b); }

/// Positions whose clip coordinates land on the planes and limits of `m`'s clip volume: solved
/// from the inverse (not exact, so some land a rounding either side, which is the point).
void addPlaneHuggers(const glm::mat4& m, const raster::ClipVolume& volume, std::mt19937& rng, std::vector<glm::vec3>& out) {
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    const glm::mat4 inverse = glm::inverse(m);
    for (int k = 0; k < raster::ClipVolume::kPlaneCount; ++k)
        for (int i = 0; i < 40; ++i) {
            glm::vec4 clip(unit(rng), unit(rng), std::abs(unit(rng)), 1.0f + std::abs(unit(rng)));
            const glm::vec4& plane = volume.planes[k];
            // Move along the plane's normal until the distance is zero (or kMinClipW on w).
            const float target = k == 2 ? raster::kMinClipW : 0.0f;
            const float distance = glm::dot(plane, clip) - target;
            clip -= plane * (distance / glm::dot(plane, plane));
            const glm::vec4 object = inverse * clip;
            if (object.w != 0.0f) out.push_back(glm::vec3(object) / object.w);
        }
}

std::vector<Case> cases() {
    std::mt19937 rng(20261205);
    std::uniform_real_distribution<float> coordinate(-3.0f, 3.0f);
    std::vector<Case> out;
    const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
    const std::vector<glm::vec3> notFinite = {{nan, 0, 0}, {0, nan, 0}, {0, 0, nan}, {inf, 0, 0}, {0, -inf, 0},
                                              {0, 0, inf}, {3e38f, 3e38f, 3e38f}, {-3e38f, 1, 1}};
    for (auto [width, height] : {std::pair{1920, 1080}, std::pair{7, 3}, std::pair{64, 48}}) {
        // Perspective cameras looking at the origin from random places, standard and reversed depth.
        for (int camera = 0; camera < 6; ++camera) {
            const glm::vec3 eye(coordinate(rng), coordinate(rng), 4.0f + coordinate(rng));
            const float near = camera % 2 ? 0.01f : 0.5f;
            glm::mat4 projection = glm::perspective(glm::radians(20.0f + 30.0f * camera), float(width) / height, near, 50.0f);
            if (camera == 5) {  // reversed depth: z' = w - z
                glm::mat4 flip(1.0f);
                flip[2][2] = -1.0f, flip[3][2] = 1.0f;
                projection = flip * projection;
            }
            Case c{"perspective " + std::to_string(camera), raster::PositionSpace::Clip,
                   projection * glm::lookAt(eye, glm::vec3(0.0f), glm::vec3(0, 1, 0)), width, height, {}};
            for (int i = 0; i < 3000; ++i) c.positions.emplace_back(coordinate(rng), coordinate(rng), coordinate(rng));
            // Behind, at and just in front of the eye: w negative, zero, near zero.
            for (float t : {0.0f, 1e-30f, 1e-21f, 1e-20f, 1e-19f, -1e-20f, 1e-7f, -1e-7f, -1.0f}) {
                const glm::vec3 forward = glm::normalize(-eye);
                c.positions.push_back(eye + t * forward);
                c.positions.push_back(eye + t * forward + glm::vec3(0.5f, 0.0f, 0.0f));
            }
            addPlaneHuggers(c.clipFromObject, raster::ClipVolume::forViewport(width, height), rng, c.positions);
            c.positions.insert(c.positions.end(), notFinite.begin(), notFinite.end());
            out.push_back(std::move(c));
        }
        // An orthographic camera whose window coordinates are exact: x * (width / 2) + width / 2,
        // so positions on a 1/512-pixel grid hit every snapping tie.
        {
            const glm::mat4 ortho = glm::ortho(-float(width) / 2, float(width) / 2, -float(height) / 2, float(height) / 2, -1.0f, 1.0f);
            Case c{"orthographic ties", raster::PositionSpace::Clip, ortho, width, height, {}};
            std::uniform_int_distribution<int> halfSubpixel(-width * 512, width * 512);
            for (int i = 0; i < 3000; ++i)
                c.positions.emplace_back(float(halfSubpixel(rng)) / 512.0f, float(halfSubpixel(rng)) / 512.0f, coordinate(rng) / 4.0f);
            c.positions.insert(c.positions.end(), notFinite.begin(), notFinite.end());
            out.push_back(std::move(c));
        }
        // Window-space draws: no transform, w = 1; ties, the guard band's edges, the depth clamp.
        {
            Case c{"window space", raster::PositionSpace::Window, glm::mat4(1.0f), width, height, {}};
            std::uniform_int_distribution<int> halfSubpixel(-width * 1024, width * 1024);
            std::uniform_real_distribution<float> depth(-0.5f, 1.5f);
            for (int i = 0; i < 3000; ++i)
                c.positions.emplace_back(float(halfSubpixel(rng)) / 512.0f, float(halfSubpixel(rng)) / 512.0f, depth(rng));
            const float g = raster::kGuardBandPixels;
            for (float x : {-g, std::nextafter(-g, -inf), float(width) + g, std::nextafter(float(width) + g, inf)})
                c.positions.emplace_back(x, 1.0f, 0.5f), c.positions.emplace_back(1.0f, x, -0.0f);
            c.positions.insert(c.positions.end(), notFinite.begin(), notFinite.end());
            out.push_back(std::move(c));
        }
    }
    return out;
}

TEST(VertexLanes, MatchScalarVertexStageOnRandomAndHardPositions) {
    constexpr uint8_t kUntouched = 0x5a;
    size_t inside = 0, outside = 0, invalid = 0, ties = 0;
    for (const Case& c : cases()) {
        const raster::SamplePattern& sp = raster::standardSamplePattern(1);
        const raster::SetupContext viewport =
            raster::SetupContext::forDraw(c.space, c.width, c.height, sp, raster::CullMode::None, 0);
        const raster::ClipVolume volume = c.space == raster::PositionSpace::Window
                                              ? raster::ClipVolume::forWindowSpace(c.width, c.height)
                                              : raster::ClipVolume::forViewport(c.width, c.height);
        // A range that starts and ends inside a chunk, so offsets and partial chunks are exercised.
        const size_t n = c.positions.size(), begin = 5, end = n - 3;
        std::vector<glm::vec4> clip(n, glm::vec4(-7.0f));
        std::vector<uint8_t> codes(n, kUntouched);
        std::vector<WindowVertex> window(n, WindowVertex{-1, -1, -1.0f, -1.0f});
        raster::transformAndProjectVertices(c.positions, c.space, c.clipFromObject, volume, viewport, begin, end,
                                            clip.data(), codes.data(), window.data());
        for (size_t i = 0; i < n; ++i) {
            const std::string where = c.name + ", " + std::to_string(c.width) + "x" + std::to_string(c.height) +
                                      ", vertex " + std::to_string(i) + " (" + std::to_string(c.positions[i].x) + ", " +
                                      std::to_string(c.positions[i].y) + ", " + std::to_string(c.positions[i].z) + ")";
            if (i < begin || i >= end) {
                ASSERT_EQ(codes[i], kUntouched) << where << ": outside the range, written";
                ASSERT_EQ(window[i].x, -1) << where;
                continue;
            }
            const glm::vec4 expectedClip = c.space == raster::PositionSpace::Window
                                               ? glm::vec4(c.positions[i], 1.0f)
                                               : c.clipFromObject * glm::vec4(c.positions[i], 1.0f);
            for (int k = 0; k < 4; ++k) ASSERT_TRUE(sameBits(clip[i][k], expectedClip[k]) || (std::isnan(clip[i][k]) && std::isnan(expectedClip[k]))) << where;
            uint8_t expectedCode;
            WindowVertex expectedWindow{};
            if (!std::isfinite(expectedClip.x) || !std::isfinite(expectedClip.y) || !std::isfinite(expectedClip.z) ||
                !std::isfinite(expectedClip.w))
                expectedCode = raster::kInvalidVertex;
            else {
                expectedCode = uint8_t(raster::outcode(volume, expectedClip));
                if (expectedCode == 0 && !raster::projectToWindow(expectedClip, viewport, expectedWindow))
                    expectedCode = raster::kInvalidVertex;
            }
            ASSERT_EQ(int(codes[i]), int(expectedCode)) << where;
            if (expectedCode == raster::kInvalidVertex) ++invalid;
            if (expectedCode != 0) {
                outside += expectedCode != raster::kInvalidVertex;
                ASSERT_EQ(window[i].x, -1) << where << ": a vertex outside the clip volume got a window position";
                continue;
            }
            ++inside;
            ASSERT_EQ(window[i].x, expectedWindow.x) << where;
            ASSERT_EQ(window[i].y, expectedWindow.y) << where;
            ASSERT_TRUE(sameBits(window[i].z, expectedWindow.z)) << where;
            ASSERT_TRUE(sameBits(window[i].invW, expectedWindow.invW)) << where;
            // A tie: the window coordinate is exactly half-way between two subpixels.
            const glm::vec4 ndc = expectedClip / expectedClip.w;
            const float wx = ndc.x * viewport.viewportScale.x + viewport.viewportOffset.x;
            const double scaled = double(wx) * raster::kSubpixelsPerPixel;
            ties += scaled - std::floor(scaled) == 0.5;
        }
    }
    // Every outcome occurs, many times over: the comparison above is not vacuous.
    EXPECT_GT(inside, 10000u);
    EXPECT_GT(outside, 5000u);
    EXPECT_GT(invalid, 100u);
    EXPECT_GT(ties, 500u);
}

}  // namespace
}  // namespace cuberille::testing
