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

/// Bounds, in subpixels, of every sample position of a rectangle's pixels.
struct SampleBox {
    int64_t loX, hiX, loY, hiY;
};

[[gnu::always_inline]] inline SampleBox sampleBoxOf(const PixelRect& r, const SamplePattern& sp) {
    auto position = [&](int32_t pixel, int offset) {
        return int64_t{pixel} * kSubpixelsPerPixel + kPixelCentreSubpixels +
               offset * kSampleOffsetUnitSubpixels;
    };
    return {position(r.minX, sp.minDx), position(r.maxX, sp.maxDx), position(r.minY, sp.minDy),
            position(r.maxY, sp.maxDy)};
}

[[gnu::always_inline]] inline BlockClass classifySampleBox(const TriangleSetup& t, const SampleBox& b) {
    bool full = true;
    for (int k = 0; k < 3; ++k) {
        const int64_t a = t.edgeA[k], c = t.edgeB[k];
        const int64_t minE = a * (a >= 0 ? b.loX : b.hiX) + c * (c >= 0 ? b.loY : b.hiY) + t.edgeC[k];
        const int64_t maxE = a * (a >= 0 ? b.hiX : b.loX) + c * (c >= 0 ? b.hiY : b.loY) + t.edgeC[k];
        if (maxE < 0) return BlockClass::Empty;
        full = full && minE >= 0;
    }
    return full ? BlockClass::Full : BlockClass::Partial;
}

inline BlockClass classifyPixelRect(const TriangleSetup& t, const PixelRect& r,
                                    const SamplePattern& sp) {
    return classifySampleBox(t, sampleBoxOf(r, sp));
}

}  // namespace cuberille::raster
