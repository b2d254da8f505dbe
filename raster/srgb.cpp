#include "raster/srgb.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace cuberille::raster {
namespace {

double decodeExactly(double encoded) {
    return encoded <= 0.04045 ? encoded / 12.92 : std::pow((encoded + 0.055) / 1.055, 2.4);
}

// thresholds[c] = the smallest linear value that encodes to c + 1: the decoded midpoint.
const std::array<float, 255>& thresholds() {
    static const std::array<float, 255> table = [] {
        std::array<float, 255> t{};
        for (int c = 0; c < 255; ++c) t[c] = float(decodeExactly((c + 0.5) / 255.0));
        return t;
    }();
    return table;
}

const std::array<float, 256>& decoded() {
    static const std::array<float, 256> table = [] {
        std::array<float, 256> t{};
        for (int c = 0; c < 256; ++c) t[c] = float(decodeExactly(c / 255.0));
        return t;
    }();
    return table;
}

}  // namespace

uint8_t encodeSrgb8(float linear) {
    if (!(linear > 0.0f)) return 0;
    const auto& t = thresholds();
    return uint8_t(std::upper_bound(t.begin(), t.end(), linear) - t.begin());
}

float decodeSrgb8(uint8_t encoded) { return decoded()[encoded]; }

}  // namespace cuberille::raster
