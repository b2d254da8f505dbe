// The footprint tests in lanes (voxel/face_footprint_lanes.h) must decide as the tests written
// one voxel and one sample at a time do:
// - the corner projection gives, for every voxel not crossing the near plane, the scalar
//   projection's corners, box, depth range and least w bit for bit, and the same fate (crossing
//   the near plane, outside the viewport, projected), on random cameras that put voxels behind
//   the eye, across the near plane, at every edge of the viewport and far outside it;
// - the face search finds a sample exactly when brute force over every sample of every pixel
//   near the quad finds one in the quad's box and inside its four edges (moved outwards, or
//   inwards, by the margin), on quads of every size the expansion searches, placed on and beside
//   sample positions and across the image's edges, for every standard sample count.
// Runs once per instruction set (tests/CMakeLists.txt).

#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "raster/sample_pattern.h"
#include "voxel/face_expansion.h"
#include "voxel/face_footprint_lanes.h"

namespace cuberille::testing {
namespace {

using voxel::FaceQuadLanes;
using voxel::VoxelCornerFrame;
using voxel::VoxelCornerLanes;

bool sameBits(double a, double b) { return std::bit_cast<uint64_t>(a) == std::bit_cast<uint64_t>(b); }

/// The projection one voxel at a time, as expansion computed it before the lanes.
struct ScalarProjection {
    uint8_t projection = voxel::kProjected;
    glm::dvec2 window[8];
    glm::dvec2 lo{std::numeric_limits<double>::infinity()}, hi{-std::numeric_limits<double>::infinity()};
    double nearestZ = std::numeric_limits<double>::infinity(), farthestZ = -std::numeric_limits<double>::infinity();
    double nearestW = std::numeric_limits<double>::infinity();
};

ScalarProjection projectOne(const VoxelCornerFrame& f, const glm::ivec3& p) {
    ScalarProjection r;
    const glm::dvec4 base = f.origin + f.step[0] * double(p.x) + f.step[1] * double(p.y) + f.step[2] * double(p.z);
    for (int k = 0; k < 8; ++k) {
        glm::dvec4 clip = base;
        if (k & 1) clip += f.step[0];
        if (k & 2) clip += f.step[1];
        if (k & 4) clip += f.step[2];
        if (!(clip.w > 0.0) || clip.z < 0.0) {
            r.projection = voxel::kCrossesNearPlane;
            return r;
        }
        const double invW = 1.0 / clip.w;
        r.window[k] = {(clip.x * invW + 1.0) * f.halfWidth, (1.0 - clip.y * invW) * f.halfHeight};
        r.lo = glm::min(r.lo, r.window[k]), r.hi = glm::max(r.hi, r.window[k]);
        const double z = clip.z * invW;
        r.nearestZ = std::min(r.nearestZ, z), r.farthestZ = std::max(r.farthestZ, z), r.nearestW = std::min(r.nearestW, clip.w);
    }
    const double m = voxel::kFootprintMarginPixels;
    if (r.hi.x < -m || r.hi.y < -m || r.lo.x > f.widthPixels + m || r.lo.y > f.heightPixels + m)
        r.projection = voxel::kOutsideViewport;
    return r;
}

TEST(FaceFootprintLanes, CornerProjectionMatchesTheScalarProjectionOnRandomCameras) {
    std::mt19937 rng(20261206);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::uniform_int_distribution<int> coordinate(0, 63);
    int projected = 0, crossing = 0, outside = 0;
    for (int view = 0; view < 200; ++view) {
        // A 64^3 block of voxels of size s at the origin; the eye anywhere from inside it to far
        // away, looking at a point near it, so some runs straddle the near plane and the edges.
        const double size = 1.0 / 64.0 * std::exp2(double(view % 4));
        const glm::dvec3 eye = glm::dvec3(unit(rng), unit(rng), unit(rng)) * (view % 3 == 0 ? 0.6 : 3.0) + 0.5 * 64.0 * size;
        const glm::dvec3 target = glm::dvec3(unit(rng), unit(rng), unit(rng)) * 0.5 + 0.5 * 64.0 * size;
        const int width = 64 + int(rng() % 1900), height = 48 + int(rng() % 1000);
        const glm::dmat4 clipFromModel = glm::perspectiveRH_ZO(glm::radians(20.0 + 60.0 * std::abs(unit(rng))),
                                                               double(width) / height, 0.01 + 0.1 * std::abs(unit(rng)), 100.0) *
                                         glm::lookAtRH(eye, target, glm::dvec3(0, 1, 0));
        VoxelCornerFrame f;
        f.origin = clipFromModel * glm::dvec4(0.0, 0.0, 0.0, 1.0);
        for (int axis = 0; axis < 3; ++axis) f.step[axis] = clipFromModel[axis] * size;
        f.halfWidth = 0.5 * width, f.halfHeight = 0.5 * height, f.widthPixels = width, f.heightPixels = height;
        VoxelCornerLanes lanes;
        lanes.count = 1 + int(rng() % voxel::kFootprintLanes);
        for (int i = 0; i < lanes.count; ++i) lanes.x[i] = coordinate(rng), lanes.y[i] = coordinate(rng), lanes.z[i] = coordinate(rng);
        voxel::projectVoxelCorners(f, lanes);
        for (int i = 0; i < lanes.count; ++i) {
            const ScalarProjection r = projectOne(f, {lanes.x[i], lanes.y[i], lanes.z[i]});
            ASSERT_EQ(int(lanes.projection[i]), int(r.projection)) << "view " << view << " voxel " << i;
            if (r.projection == voxel::kCrossesNearPlane) {
                ++crossing;
                continue;
            }
            ++(r.projection == voxel::kOutsideViewport ? outside : projected);
            for (int k = 0; k < 8; ++k)
                ASSERT_TRUE(sameBits(lanes.windowX[k][i], r.window[k].x) && sameBits(lanes.windowY[k][i], r.window[k].y))
                    << "view " << view << " voxel " << i << " corner " << k;
            ASSERT_TRUE(sameBits(lanes.loX[i], r.lo.x) && sameBits(lanes.loY[i], r.lo.y) && sameBits(lanes.hiX[i], r.hi.x) &&
                        sameBits(lanes.hiY[i], r.hi.y))
                << "view " << view << " voxel " << i;
            ASSERT_TRUE(sameBits(lanes.nearestZ[i], r.nearestZ) && sameBits(lanes.farthestZ[i], r.farthestZ) &&
                        sameBits(lanes.nearestW[i], r.nearestW))
                << "view " << view << " voxel " << i;
        }
    }
    // Every fate was met, many times.
    EXPECT_GT(projected, 1000);
    EXPECT_GT(crossing, 100);
    EXPECT_GT(outside, 100);
}

/// The hidden-depth pre-test one voxel at a time, as expansion decided it before the lanes: the
/// shared margin functions, then every footprint block under the widened box, found by integer
/// division.
voxel::DepthPretest pretestOne(const voxel::HiddenDepthFrame& f, const ScalarProjection& p) {
    if (p.projection != voxel::kProjected || p.hi.x - p.lo.x > voxel::kDepthTestedVoxelPixels ||
        p.hi.y - p.lo.y > voxel::kDepthTestedVoxelPixels)
        return voxel::kNotDepthTested;
    const voxel::DepthFootprint& d = *f.depth;
    const double error = voxel::cornerError(f.clipZError, f.clipWError, p.nearestZ, p.farthestZ, p.nearestW);
    auto key = [&](double z) { return double(d.keySign) * std::clamp(z, 0.0, 1.0); };
    const double nearestKey = std::min(key(p.nearestZ), key(p.farthestZ));
    const double bound = nearestKey - voxel::hiddenDepthMargin(p.nearestZ, p.farthestZ, error, 0.0);
    const double m = voxel::kFootprintMarginPixels;
    const int x0 = std::max(0, int(p.lo.x - m) / d.blockSizePixels), y0 = std::max(0, int(p.lo.y - m) / d.blockSizePixels);
    const int x1 = std::min(d.blocksX - 1, int(p.hi.x + m) / d.blockSizePixels);
    const int y1 = std::min(d.blocksY - 1, int(p.hi.y + m) / d.blockSizePixels);
    if (x0 > x1 || y0 > y1) return voxel::kInFront;
    if (x1 - x0 > 2 || y1 - y0 > 2) return voxel::kTestDepthOnOwn;
    auto behind = [&](double key) {
        for (int by = y0; by <= y1; ++by)
            for (int bx = x0; bx <= x1; ++bx)
                if (!(double(d.farthestKey[size_t(by * d.blocksX + bx)]) <= key)) return false;
        return true;
    };
    if (!behind(bound)) return voxel::kInFront;
    const double largest = nearestKey - voxel::hiddenDepthMargin(p.nearestZ, p.farthestZ, error, voxel::kLargestPlaneTermRatio);
    return behind(largest) ? voxel::kBehindWithAnyMargin : voxel::kMayBeBehind;
}

TEST(FaceFootprintLanes, HiddenDepthPretestMatchesTheOneVoxelTest) {
    std::mt19937 rng(6122026);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::uniform_int_distribution<int> coordinate(0, 63);
    int counts[5] = {};
    for (int view = 0; view < 300; ++view) {
        // Voxels of about a pixel to a few pixels, seen from 1 to 3 block widths away; a footprint
        // whose blocks hold keys around the voxels' own depths, so that many are decided by a
        // rounding, either key sign.
        const double size = 1.0 / 64.0;
        const glm::dvec3 eye = glm::normalize(glm::dvec3(unit(rng), unit(rng), unit(rng))) * (1.0 + 2.0 * std::abs(unit(rng))) + 0.5;
        const int width = 160 + int(rng() % 400), height = 120 + int(rng() % 300);
        const glm::dmat4 clipFromModel =
            glm::perspectiveRH_ZO(glm::radians(40.0), double(width) / height, 0.1, 10.0) * glm::lookAtRH(eye, glm::dvec3(0.5), glm::dvec3(0, 1, 0));
        VoxelCornerFrame f;
        f.origin = clipFromModel * glm::dvec4(0.0, 0.0, 0.0, 1.0);
        for (int axis = 0; axis < 3; ++axis) f.step[axis] = clipFromModel[axis] * size;
        f.halfWidth = 0.5 * width, f.halfHeight = 0.5 * height, f.widthPixels = width, f.heightPixels = height;
        VoxelCornerLanes lanes;
        lanes.count = voxel::kFootprintLanes;
        for (int i = 0; i < lanes.count; ++i) lanes.x[i] = coordinate(rng), lanes.y[i] = coordinate(rng), lanes.z[i] = coordinate(rng);
        voxel::projectVoxelCorners(f, lanes);
        double zLo = 1.0, zHi = 0.0;
        for (int i = 0; i < lanes.count; ++i)
            if (lanes.projection[i] == voxel::kProjected) zLo = std::min(zLo, lanes.nearestZ[i]), zHi = std::max(zHi, lanes.farthestZ[i]);
        voxel::DepthFootprint depth;
        depth.blocksX = (width + 7) / 8, depth.blocksY = (height + 7) / 8;
        depth.keySign = view % 2 ? 1.0f : -1.0f;
        std::uniform_real_distribution<double> z(zLo, zHi);
        std::vector<double> nearestKeys;
        for (int i = 0; i < lanes.count; ++i)
            if (lanes.projection[i] == voxel::kProjected)
                nearestKeys.push_back(std::min(depth.keySign * std::clamp(lanes.nearestZ[i], 0.0, 1.0),
                                               depth.keySign * std::clamp(lanes.farthestZ[i], 0.0, 1.0)));
        for (int b = 0; b < depth.blocksX * depth.blocksY; ++b) {
            // A third of the blocks hold a voxel's own nearest key, rounded to float, give or take
            // a few float steps: there the margin (a few 2^-21) decides.
            float key = float(depth.keySign * z(rng));
            if (b % 3 == 0 && !nearestKeys.empty()) {
                key = float(nearestKeys[rng() % nearestKeys.size()]);
                for (int step = int(rng() % 9) - 4; step != 0; step += step > 0 ? -1 : 1)
                    key = std::nextafter(key, step > 0 ? 2.0f : -2.0f);
            }
            depth.farthestKey.push_back(key);
        }
        const voxel::HiddenDepthFrame frame{&depth, 1e-7 * std::abs(unit(rng)), 1e-7 * std::abs(unit(rng))};
        uint8_t pretest[voxel::kFootprintLanes];
        voxel::pretestHiddenDepth(frame, lanes, pretest);
        for (int i = 0; i < lanes.count; ++i) {
            const ScalarProjection p = projectOne(f, {lanes.x[i], lanes.y[i], lanes.z[i]});
            const voxel::DepthPretest expected = pretestOne(frame, p);
            ASSERT_EQ(int(pretest[i]), int(expected)) << "view " << view << " voxel " << i;
            ++counts[expected];
        }
    }
    EXPECT_GT(counts[voxel::kInFront], 1000);
    EXPECT_GT(counts[voxel::kMayBeBehind], 500);
    EXPECT_GT(counts[voxel::kBehindWithAnyMargin], 500);
    EXPECT_GT(counts[voxel::kNotDepthTested], 100);
}

/// Brute force: whether a sample of some pixel of the image lies in the quad's box widened by
/// max(margin, 0) and on the inner side of each of its edges moved outwards by
/// margin (|dx| + |dy|) (expansion's definition of a face that may cover a sample).
bool bruteForceHoldsSample(const glm::dvec2 (&q)[4], double margin, const voxel::SampleFootprint& f) {
    double area2 = 0.0;
    for (int i = 0; i < 4; ++i) area2 += q[i].x * q[(i + 1) % 4].y - q[(i + 1) % 4].x * q[i].y;
    const double orientation = area2 >= 0.0 ? 1.0 : -1.0;
    const double widening = std::max(margin, 0.0);
    const glm::dvec2 lo = glm::min(glm::min(q[0], q[1]), glm::min(q[2], q[3])) - widening;
    const glm::dvec2 hi = glm::max(glm::max(q[0], q[1]), glm::max(q[2], q[3])) + widening;
    const int x0 = std::max(0, int(std::floor(lo.x)) - 2), x1 = std::min(f.widthPixels - 1, int(std::ceil(hi.x)) + 2);
    const int y0 = std::max(0, int(std::floor(lo.y)) - 2), y1 = std::min(f.heightPixels - 1, int(std::ceil(hi.y)) + 2);
    for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x)
            for (const glm::dvec2& offset : f.samples) {
                // In the box: the pixel lies in [lo, hi] less the sample's offset (the box's
                // terms, not the sample's position, rounded: as expansion asks).
                if (x < lo.x - offset.x || x > hi.x - offset.x || y < lo.y - offset.y || y > hi.y - offset.y) continue;
                const double sx = x + offset.x, sy = y + offset.y;
                bool inside = true;
                for (int i = 0; i < 4; ++i) {
                    const glm::dvec2 d = q[(i + 1) % 4] - q[i];
                    const double a = -d.y * orientation, b = d.x * orientation;
                    const double c = -(a * q[i].x + b * q[i].y) + margin * (std::abs(d.x) + std::abs(d.y));
                    inside = inside && a * sx + b * sy + c >= 0.0;
                }
                if (inside) return true;
            }
    return false;
}

TEST(FaceFootprintLanes, FaceSearchFindsASampleExactlyWhenBruteForceDoes) {
    std::mt19937 rng(61202026);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    int found = 0, none = 0, big = 0;
    for (int samples : {1, 2, 4, 8, 16}) {
        voxel::SampleFootprint f;
        f.widthPixels = 40, f.heightPixels = 30;
        const raster::SamplePattern& pattern = raster::standardSamplePattern(samples);
        for (int i = 0; i < pattern.count; ++i)
            f.samples.push_back({0.5 + pattern.dx[size_t(i)] / 16.0, 0.5 + pattern.dy[size_t(i)] / 16.0});
        const double searched = 2.0 / samples;  // expansion's kSearchedFacePixels over the samples
        for (double margin : {voxel::kFootprintMarginPixels, -4.0 / 256.0, 0.0}) {
            for (int run = 0; run < 60; ++run) {
                FaceQuadLanes lanes;
                lanes.count = voxel::kFootprintLanes;
                std::vector<std::array<glm::dvec2, 4>> quads(size_t(lanes.count));
                for (int i = 0; i < lanes.count; ++i) {
                    // A parallelogram (a voxel face's projection, near enough) of up to the searched
                    // size, or now and then larger, anywhere from beyond the left and top edges to
                    // beyond the right and bottom ones; a third of them with a corner on a sample
                    // position, or a margin from one, where the edge tests decide by a rounding.
                    const double extent = (i % 17 == 0 ? 3.0 : 1.0) * searched;
                    glm::dvec2 origin(-3.0 + unit(rng) * (f.widthPixels + 6), -3.0 + unit(rng) * (f.heightPixels + 6));
                    if (i % 3 == 0) {
                        const glm::dvec2& s = f.samples[rng() % f.samples.size()];
                        origin = glm::floor(origin) + s + (i % 2 ? margin : 0.0);
                    }
                    glm::dvec2 u(unit(rng) * extent, (unit(rng) - 0.5) * extent);
                    glm::dvec2 v((unit(rng) - 0.5) * extent, unit(rng) * extent);
                    if (i % 5 == 1 || i % 5 == 2) {
                        // A sliver nearly as long as the searched size, seen edge on: its box
                        // spans three pixels' samples, and often only the last holds one.
                        u = {searched * (0.85 + 0.15 * unit(rng)), (unit(rng) - 0.5) * 0.3 * searched};
                        v = {0.0, 0.02 * unit(rng)};
                        if (i % 5 == 2) u = {u.y, u.x}, v = {v.y, v.x};
                    }
                    quads[size_t(i)] = {origin, origin + u, origin + u + v, origin + v};
                    if (i % 2) std::swap(quads[size_t(i)][1], quads[size_t(i)][3]);  // the other winding
                    for (int c = 0; c < 4; ++c) lanes.x[c][i] = quads[size_t(i)][size_t(c)].x, lanes.y[c][i] = quads[size_t(i)][size_t(c)].y;
                }
                voxel::searchFaceSamples(f, margin, searched, lanes);
                for (int i = 0; i < lanes.count; ++i) {
                    const glm::dvec2 q[4] = {quads[size_t(i)][0], quads[size_t(i)][1], quads[size_t(i)][2], quads[size_t(i)][3]};
                    const glm::dvec2 lo = glm::min(glm::min(q[0], q[1]), glm::min(q[2], q[3]));
                    const glm::dvec2 hi = glm::max(glm::max(q[0], q[1]), glm::max(q[2], q[3]));
                    if (hi.x - lo.x > searched || hi.y - lo.y > searched) {
                        ASSERT_EQ(int(lanes.found[i]), int(voxel::kMayCover)) << "a face too large to search is kept";
                        ++big;
                        continue;
                    }
                    ASSERT_NE(int(lanes.found[i]), int(voxel::kSearchOnOwn)) << "a searched face's box spans at most 3 pixels";
                    const bool expected = bruteForceHoldsSample(q, margin, f);
                    ASSERT_EQ(lanes.found[i] == voxel::kMayCover, expected)
                        << samples << " samples, margin " << margin << ", quad (" << q[0].x << ", " << q[0].y << ") ("
                        << q[1].x << ", " << q[1].y << ") (" << q[2].x << ", " << q[2].y << ") (" << q[3].x << ", "
                        << q[3].y << ")";
                    ++(expected ? found : none);
                }
            }
        }
    }
    EXPECT_GT(found, 5000);
    EXPECT_GT(none, 5000);
    EXPECT_GT(big, 500);
}

}  // namespace
}  // namespace cuberille::testing
