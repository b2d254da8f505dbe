#pragma once
// Standard multisample positions (Direct3D 11 / Vulkan), as DESIGN.md lists them.
// Offsets are in 1/16 pixel from the pixel centre, x right and y down.

#include <array>
#include <cstdint>

#include "raster/limits.h"

namespace cuberille::raster {

struct SamplePattern {
    int count = 1;
    std::array<int8_t, kMaxSamples> dx{};  // 1/16 pixel
    std::array<int8_t, kMaxSamples> dy{};
    // Extremes over the samples, so the coarse stage can bound a block's sample positions.
    int minDx = 0, maxDx = 0, minDy = 0, maxDy = 0;
};

bool isSupportedSampleCount(int count);

/// The pattern for 1, 2, 4, 8 or 16 samples; throws std::invalid_argument otherwise.
const SamplePattern& standardSamplePattern(int count);

}  // namespace cuberille::raster
