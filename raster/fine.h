#pragma once
// Fine stage: the per-sample coverage mask of one pixel, for blocks the coarse stage found
// Partial and for small triangles.
//
// The three edge values are stepped from pixel centre to pixel centre (+A·256 per pixel in x),
// and each sample adds a constant per-edge offset A·dx·16 + B·dy·16 computed once per
// triangle. A sample is covered iff its three biased edge values are all >= 0, i.e. iff their
// bitwise OR has no sign bit: one test instead of three.

#include <cstdint>

#include "raster/sample_pattern.h"
#include "raster/setup.h"

namespace cuberille::raster {

template <int S>
struct SampleEdgeOffsets {
    int64_t edge[3][S];  // subpixels², added to the edge value at the pixel centre
};

/// What sample s of the pattern adds to edge k's value at the pixel centre, in subpixels².
[[gnu::always_inline]] inline int64_t sampleEdgeOffset(const TriangleSetup& t, const SamplePattern& sp, int k, int s) {
    return int64_t{t.edgeA[k]} * (sp.dx[s] * kSampleOffsetUnitSubpixels) +
           int64_t{t.edgeB[k]} * (sp.dy[s] * kSampleOffsetUnitSubpixels);
}

template <int S>
[[gnu::always_inline]] inline void computeSampleEdgeOffsets(const TriangleSetup& t, const SamplePattern& sp,
                              SampleEdgeOffsets<S>& out) {
    for (int k = 0; k < 3; ++k)
        for (int s = 0; s < S; ++s) out.edge[k][s] = sampleEdgeOffset(t, sp, k, s);
}

/// Biased edge values at the centre of pixel (x, y).
[[gnu::always_inline]] inline void edgesAtPixelCentre(const TriangleSetup& t, int32_t x, int32_t y, int64_t out[3]) {
    const int64_t cx = int64_t{x} * kSubpixelsPerPixel + kPixelCentreSubpixels;
    const int64_t cy = int64_t{y} * kSubpixelsPerPixel + kPixelCentreSubpixels;
    for (int k = 0; k < 3; ++k) out[k] = t.edgeA[k] * cx + t.edgeB[k] * cy + t.edgeC[k];
}

template <int S>
[[gnu::always_inline]] inline uint32_t coverageMask(const int64_t centre[3], const SampleEdgeOffsets<S>& o) {
    uint32_t mask = 0;
    for (int s = 0; s < S; ++s) {
        const int64_t any = (centre[0] + o.edge[0][s]) | (centre[1] + o.edge[1][s]) |
                            (centre[2] + o.edge[2][s]);
        mask |= uint32_t(any >= 0) << s;
    }
    return mask;
}

}  // namespace cuberille::raster
