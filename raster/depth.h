#pragma once
// Depth stage: per-sample depth from the triangle's plane equation, and the LESS test.
//
// What is stored and compared is a depth key: the depth (standard convention) or its negation
// (reversed; raster/framebuffer.h), so nearer is always less and one LESS test, one hierarchical-Z
// direction and one bound serve both conventions. The flip is exact, so reversed depth keeps its
// precision.
//
// Depth is evaluated directly at each sample, relative to the snapped vertex 0: the offset
// X - originX is an integer below 2^24 and so exact in float, and the evaluation order is
// fixed, so a sample's depth never depends on which tile or thread computed it. Values are
// clamped to [0, 1] (the viewport's depth range).

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "raster/sample_pattern.h"
#include "raster/setup.h"

namespace cuberille::raster {

template <int S>
struct SampleSubpixelOffsets {
    int32_t x[S], y[S];  // from the pixel centre
};

template <int S>
[[gnu::always_inline]] inline void computeSampleSubpixelOffsets(const SamplePattern& sp, SampleSubpixelOffsets<S>& out) {
    for (int s = 0; s < S; ++s) {
        out.x[s] = sp.dx[s] * kSampleOffsetUnitSubpixels;
        out.y[s] = sp.dy[s] * kSampleOffsetUnitSubpixels;
    }
}

template <int S>
[[gnu::always_inline]] inline void sampleDepths(const TriangleSetup& t, int32_t pixelX, int32_t pixelY,
                         const SampleSubpixelOffsets<S>& o, float out[S]) {
    const int32_t cx = pixelX * kSubpixelsPerPixel + kPixelCentreSubpixels - t.originXSubpixels;
    const int32_t cy = pixelY * kSubpixelsPerPixel + kPixelCentreSubpixels - t.originYSubpixels;
    for (int s = 0; s < S; ++s) {
        const float z = t.depthAtOrigin + t.depthPerSubpixelX * float(cx + o.x[s]) +
                        t.depthPerSubpixelY * float(cy + o.y[s]);
        out[s] = t.depthKeySign * std::clamp(z, 0.0f, 1.0f);
    }
}

/// A lower bound on the depth key sampleDepths() computes for any sample whose position lies in
/// [loX, hiX] x [loY, hiY] (subpixels). The key plane's minimum over the box sits at the corner
/// picked by its gradient's signs; the margin covers the float rounding of sampleDepths()
/// (three roundings of terms no larger than `magnitude`, far below 1e-6 of it).
[[gnu::always_inline]] inline float minSampleDepthOverBox(const TriangleSetup& t, int64_t loX, int64_t hiX, int64_t loY,
                                   int64_t hiY) {
    const double sign = t.depthKeySign;
    const double gx = sign * t.depthPerSubpixelX, gy = sign * t.depthPerSubpixelY;
    const double dx = double((gx >= 0 ? loX : hiX) - t.originXSubpixels);
    const double dy = double((gy >= 0 ? loY : hiY) - t.originYSubpixels);
    const double z = sign * t.depthAtOrigin + gx * dx + gy * dy;
    const double magnitude = std::abs(double(t.depthAtOrigin)) + std::abs(gx * dx) + std::abs(gy * dy);
    return float(std::clamp(z - magnitude * 1e-6, std::min(0.0, sign), std::max(0.0, sign)));
}

/// Samples of `covered` whose depth is less than the stored depth.
template <int S>
[[gnu::always_inline]] inline uint32_t depthTestLess(uint32_t covered, const float depth[S], const float* stored) {
    uint32_t pass = 0;
    for (int s = 0; s < S; ++s) pass |= uint32_t(depth[s] < stored[s]) << s;
    return pass & covered;
}

}  // namespace cuberille::raster
