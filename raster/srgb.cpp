#include "raster/srgb.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <vector>

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

/// Where to start counting thresholds for a linear value: its float bits, from the first
/// threshold's up, in buckets of 2^kBucketShift consecutive floats (256 buckets per octave), each
/// holding how many thresholds lie at or below the bucket's first float. A bucket is narrower
/// than the gap between two thresholds everywhere in [t[0], 1) (the gap is smallest, relative to
/// the value, near 1: 1/255 of the encoded range is 0.9% of linear there, a bucket 0.4%), so at
/// most one more threshold is passed after the lookup.
struct ThresholdIndex {
    static constexpr int kBucketShift = 23 - 8;
    uint32_t firstBits;
    std::vector<uint8_t> countAtBucketStart;
};

uint32_t bitsOf(float f) {
    uint32_t b;
    std::memcpy(&b, &f, sizeof b);
    return b;
}

const ThresholdIndex& thresholdIndex() {
    static const ThresholdIndex index = [] {
        const auto& t = thresholds();
        ThresholdIndex ix;
        ix.firstBits = bitsOf(t[0]);
        const uint32_t buckets = ((bitsOf(1.0f) - ix.firstBits) >> ThresholdIndex::kBucketShift) + 1;
        for (uint32_t b = 0; b < buckets; ++b) {
            float start;
            const uint32_t bits = ix.firstBits + (b << ThresholdIndex::kBucketShift);
            std::memcpy(&start, &bits, sizeof start);
            ix.countAtBucketStart.push_back(uint8_t(std::upper_bound(t.begin(), t.end(), start) - t.begin()));
        }
        return ix;
    }();
    return index;
}

// The number of thresholds at or below `linear` (what a binary search over them returns), found
// through the bucket index and then at most a step or two: exact by construction, since both
// count the same thresholds (Srgb.EncodingCountsTheThresholdsBelowEachValue).
inline uint8_t encodeThroughIndex(const std::array<float, 255>& t, const ThresholdIndex& ix, float linear) {
    if (!(linear >= t[0])) return 0;  // below the first threshold, and NaN
    if (linear >= 1.0f) return 255;   // t[254] < 1
    unsigned count = ix.countAtBucketStart[(bitsOf(linear) - ix.firstBits) >> ThresholdIndex::kBucketShift];
    while (count < 255 && t[count] <= linear) ++count;
    return uint8_t(count);
}

}  // namespace

uint8_t encodeSrgb8(float linear) { return encodeThroughIndex(thresholds(), thresholdIndex(), linear); }

void encodeSrgb8(const float* linear, size_t count, uint8_t* out) {
    const auto& t = thresholds();  // once for the span, not once a value
    const ThresholdIndex& ix = thresholdIndex();
    for (size_t i = 0; i < count; ++i) out[i] = encodeThroughIndex(t, ix, linear[i]);
}

uint16_t encodeSrgb16(float linear) {
    if (!(linear > 0.0f)) return 0;
    if (linear >= 1.0f) return 65535;
    const double l = linear;
    const double encoded = l <= 0.0031308 ? 12.92 * l : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
    return uint16_t(std::lround(std::clamp(encoded, 0.0, 1.0) * 65535.0));
}

double decodeSrgb(double encoded) { return decodeExactly(encoded); }

float decodeSrgb8(uint8_t encoded) { return decoded()[encoded]; }

}  // namespace cuberille::raster
