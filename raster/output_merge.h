#pragma once
// Output merge: write the pixel's one shaded colour to every sample that passed the depth
// test, honouring the colour write mask, and the samples' depths when depth writes are on.

#include <cstdint>

#include <glm/glm.hpp>

#include "raster/draw.h"

namespace cuberille::raster {

template <int S>
inline void mergeColor(glm::vec4* samples, uint32_t pass, const glm::vec4& color,
                       uint8_t writeMask) {
    if (writeMask == kWriteAll) {
        for (int s = 0; s < S; ++s)
            if (pass & (1u << s)) samples[s] = color;
        return;
    }
    for (int s = 0; s < S; ++s) {
        if (!(pass & (1u << s))) continue;
        for (int c = 0; c < 4; ++c)
            if (writeMask & (1u << c)) samples[s][c] = color[c];
    }
}

template <int S>
inline void mergeDepth(float* samples, uint32_t pass, const float depth[S]) {
    for (int s = 0; s < S; ++s)
        if (pass & (1u << s)) samples[s] = depth[s];
}

}  // namespace cuberille::raster
