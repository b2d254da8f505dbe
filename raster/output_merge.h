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

/// Transmission (DrawState::transmits): rgb = a src.rgb + (a T + 1 - a) dst.rgb, the pixel's own
/// light over what is behind it seen through its transmittance T, under its alpha a (1 unless
/// blended); alpha = 1 - mean(a T + 1 - a) (1 - dst.a): a transparent background stays as
/// transparent as the surface lets it be seen, so compositing over a backdrop later gives it.
template <int S>
[[gnu::always_inline]] inline void transmitColor(glm::vec4* samples, uint32_t pass, const glm::vec4& src, const glm::vec3& transmittance,
                                                 uint8_t writeMask) {
    const glm::vec3 through = src.a * transmittance + (1.0f - src.a);
    const float seen = (through.r + through.g + through.b) * (1.0f / 3.0f);
    for (int s = 0; s < S; ++s) {
        if (!(pass & (1u << s))) continue;
        const glm::vec4 dst = samples[s];
        const glm::vec4 out(src.r * src.a + dst.r * through.r, src.g * src.a + dst.g * through.g, src.b * src.a + dst.b * through.b,
                            1.0f - seen * (1.0f - dst.a));
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
