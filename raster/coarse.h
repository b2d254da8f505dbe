#pragma once
// Coarse stage: classify a rectangle of pixels (an 8x8 block, or a whole tile when binning)
// against a triangle's three edges, exactly.
//
// The sample positions of the rectangle's pixels lie in a box of subpixel coordinates; an edge
// function is linear, so its minimum and maximum over that box sit at two corners chosen by
// the signs of A and B. If every edge's minimum is >= 0, every sample in the box is covered:
// the block is Full and needs no per-sample edge test. If some edge's maximum is < 0, no
// sample is: Empty. Otherwise Partial, for the fine stage.

#include <cstdint>

#include "raster/sample_pattern.h"
#include "raster/setup.h"

namespace cuberille::raster {

enum class BlockClass : uint8_t { Empty, Partial, Full };

/// Inclusive pixel rectangle.
struct PixelRect {
    int32_t minX, minY, maxX, maxY;
};

inline BlockClass classifyPixelRect(const TriangleSetup& t, const PixelRect& r,
                                    const SamplePattern& sp) {
    const int64_t loX = int64_t{r.minX} * kSubpixelsPerPixel + kPixelCentreSubpixels +
                        sp.minDx * kSampleOffsetUnitSubpixels;
    const int64_t hiX = int64_t{r.maxX} * kSubpixelsPerPixel + kPixelCentreSubpixels +
                        sp.maxDx * kSampleOffsetUnitSubpixels;
    const int64_t loY = int64_t{r.minY} * kSubpixelsPerPixel + kPixelCentreSubpixels +
                        sp.minDy * kSampleOffsetUnitSubpixels;
    const int64_t hiY = int64_t{r.maxY} * kSubpixelsPerPixel + kPixelCentreSubpixels +
                        sp.maxDy * kSampleOffsetUnitSubpixels;
    bool full = true;
    for (int k = 0; k < 3; ++k) {
        const int64_t a = t.edgeA[k], b = t.edgeB[k];
        const int64_t minE = a * (a >= 0 ? loX : hiX) + b * (b >= 0 ? loY : hiY) + t.edgeC[k];
        const int64_t maxE = a * (a >= 0 ? hiX : loX) + b * (b >= 0 ? hiY : loY) + t.edgeC[k];
        if (maxE < 0) return BlockClass::Empty;
        full = full && minE >= 0;
    }
    return full ? BlockClass::Full : BlockClass::Partial;
}

}  // namespace cuberille::raster
