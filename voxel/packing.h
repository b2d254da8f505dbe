#pragma once
// Compact encodings shared by the voxel files (.cgs, .cvox): unit vectors as 10-10-10 signed
// normalised integers and colours as 8-bit sRGB. Both are exact round trips of their own output
// (decode(encode(x)) re-encodes to the same bits), which the file tests rely on.

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <glm/glm.hpp>

namespace cuberille::voxel {

/// x in bits 0-9, y in 10-19, z in 20-29, each a two's-complement value in [-511, 511]
/// standing for [-1, 1]. A zero vector stays zero.
inline uint32_t packNormal1010102(const glm::vec3& n) {
    auto field = [](float c) {
        const int v = int(std::lround(std::clamp(c, -1.0f, 1.0f) * 511.0f));
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

/// Linear [0, 1] to 8-bit sRGB, round to nearest (the transfer function of IEC 61966-2-1).
inline uint8_t encodeSrgb8(float linear) {
    const float c = std::clamp(linear, 0.0f, 1.0f);
    const float e = c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
    return uint8_t(std::lround(e * 255.0f));
}

inline float decodeSrgb8(uint8_t encoded) {
    const float e = float(encoded) / 255.0f;
    return e <= 0.04045f ? e / 12.92f : std::pow((e + 0.055f) / 1.055f, 2.4f);
}

/// RGBA8 with R in the lowest byte; RGB sRGB-encoded, alpha linear.
inline uint32_t packSrgba8(const glm::vec3& linear, float alpha = 1.0f) {
    return uint32_t(encodeSrgb8(linear.r)) | (uint32_t(encodeSrgb8(linear.g)) << 8) |
           (uint32_t(encodeSrgb8(linear.b)) << 16) |
           (uint32_t(std::lround(std::clamp(alpha, 0.0f, 1.0f) * 255.0f)) << 24);
}

inline glm::vec3 unpackSrgba8Rgb(uint32_t packed) {
    return {decodeSrgb8(uint8_t(packed)), decodeSrgb8(uint8_t(packed >> 8)), decodeSrgb8(uint8_t(packed >> 16))};
}

}  // namespace cuberille::voxel
