#pragma once
// Output merge: write the pixel's one shaded colour to every sample that passed the depth
// test, honouring the colour write mask, and the samples' depths when depth writes are on.

#include <cstdint>

#include <glm/glm.hpp>

#include "raster/draw.h"

namespace cuberille::raster {

template <int S>
[[gnu::always_inline]] inline void mergeColor(glm::vec4* samples, uint32_t pass, const glm::vec4& color,
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

/// Over-blending (AlphaMode::Blend): rgb = src.rgb * src.a + dst.rgb * (1 - src.a),
/// a = src.a + dst.a * (1 - src.a), per passing sample, under the write mask.
template <int S>
[[gnu::always_inline]] inline void blendColor(glm::vec4* samples, uint32_t pass, const glm::vec4& src, uint8_t writeMask) {
    const float keep = 1.0f - src.a;
    for (int s = 0; s < S; ++s) {
        if (!(pass & (1u << s))) continue;
        const glm::vec4 dst = samples[s];
        const glm::vec4 out(src.r * src.a + dst.r * keep, src.g * src.a + dst.g * keep,
                            src.b * src.a + dst.b * keep, src.a + dst.a * keep);
        for (int c = 0; c < 4; ++c)
            if (writeMask & (1u << c)) samples[s][c] = out[c];
    }
}

template <int S>
[[gnu::always_inline]] inline void mergeDepth(float* samples, uint32_t pass, const float depth[S]) {
    for (int s = 0; s < S; ++s)
        if (pass & (1u << s)) samples[s] = depth[s];
}

}  // namespace cuberille::raster
