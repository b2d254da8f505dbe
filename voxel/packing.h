#pragma once
// Compact encodings shared by the voxel files (.cgs, .cvox): unit vectors as 10-10-10 signed
// normalised integers and colours as 8-bit sRGB. Both are exact round trips of their own output
// (decode(encode(x)) re-encodes to the same bits), which the file tests rely on. sRGB is
// raster/srgb.h's exact table encoding.

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <glm/glm.hpp>

#include "raster/srgb.h"

namespace cuberille::voxel {

/// x in bits 0-9, y in 10-19, z in 20-29, each a two's-complement value in [-511, 511]
/// standing for [-1, 1]. A zero vector stays zero.
inline uint32_t packNormal1010102(const glm::vec3& n) {
    auto field = [](float c) {
        const float scaled = std::clamp(c, -1.0f, 1.0f) * 511.0f;  // NaN clamps to NaN: keep it out
        const int v = scaled == scaled ? int(scaled < 0.0f ? scaled - 0.5f : scaled + 0.5f) : 0;
        return uint32_t(v) & 0x3FFu;
    };
    return field(n.x) | (field(n.y) << 10) | (field(n.z) << 20);
}

inline glm::vec3 unpackNormal1010102(uint32_t packed) {
    auto field = [](uint32_t bits) {
        const int v = int(bits & 0x3FFu);
        return float(v >= 512 ? v - 1024 : v) / 511.0f;
    };
    return {field(packed), field(packed >> 10), field(packed >> 20)};
}

/// RGBA8 with R in the lowest byte; RGB sRGB-encoded, alpha linear.
inline uint32_t packSrgba8(const glm::vec3& linear, float alpha = 1.0f) {
    return uint32_t(raster::encodeSrgb8(linear.r)) | (uint32_t(raster::encodeSrgb8(linear.g)) << 8) |
           (uint32_t(raster::encodeSrgb8(linear.b)) << 16) |
           (uint32_t(std::lround(std::clamp(alpha, 0.0f, 1.0f) * 255.0f)) << 24);
}

inline glm::vec3 unpackSrgba8Rgb(uint32_t packed) {
    return {raster::decodeSrgb8(uint8_t(packed)), raster::decodeSrgb8(uint8_t(packed >> 8)), raster::decodeSrgb8(uint8_t(packed >> 16))};
}

}  // namespace cuberille::voxel
