#pragma once
// How far one image is from another, as the accuracy report measures it (docs/accuracy.md).
//
// Errors are taken on sRGB-encoded colour, clamped to [0, 1]: the values a viewer sees and an
// 8-bit file stores, so "off by more than 1/255" means a step in the output file. Alpha is left
// out (every scene's background is opaque). Encoding is the continuous sRGB curve, not 8-bit
// rounding, so differences smaller than one step still count in RMSE.

#include <string>

#include "raster/resolve.h"

namespace cuberille::apps {

struct ImageError {
    double rmse = 0.0;          // over every channel of every pixel
    double psnrDb = 0.0;        // 20 log10(1 / rmse); infinite for identical images
    double maxError = 0.0;      // the largest channel difference
    double shareOver1 = 0.0;    // pixels with some channel off by more than 1/255
    double shareOver8 = 0.0;    // ... by more than 8/255
};

/// Throws std::runtime_error when the sizes differ.
ImageError compareImages(const raster::Image& image, const raster::Image& truth);

struct PixelRect {
    int x = 0, y = 0, width = 0, height = 0;
};

/// The square of `sidePixels` (clamped to the image) with the largest summed squared error; ties
/// go to the top-most, then left-most.
PixelRect worstRegion(const raster::Image& image, const raster::Image& truth, int sidePixels);

/// Three panels side by side, each the region magnified `scale` times (nearest): the image, the
/// truth, and the difference eight times amplified in red. Linear values, ready to write.
raster::Image comparisonCrop(const raster::Image& image, const raster::Image& truth, PixelRect region, int scale);

}  // namespace cuberille::apps
