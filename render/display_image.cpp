#include "render/display_image.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "raster/parallel.h"
#include "raster/srgb.h"

namespace cuberille::render {
namespace {

/// Straight (unassociated) colour of pixel i's channel c: what PNG stores beside alpha.
float straightChannel(const raster::Image& image, size_t i, int c, bool alpha) {
    const float value = image.rgba[i * 4 + c], a = image.rgba[i * 4 + 3];
    if (!alpha) return value;
    return a > 0.0f ? value / a : 0.0f;
}

}  // namespace

std::vector<uint8_t> encodeDisplayPixels(const raster::Image& image, bool alpha, int bits) {
    const int channels = alpha ? 4 : 3, bytesPerSample = bits / 8;
    std::vector<uint8_t> out(size_t(image.width) * image.height * channels * bytesPerSample);
    if (bits == 8) {
        // A row's colour channels, straight, then encoded in one span (raster::encodeSrgb8).
        raster::parallelFor(size_t(image.height), [&](size_t y) {
            const size_t width = size_t(image.width), first = y * width;
            std::vector<float> colour(width * 3);
            std::vector<uint8_t> encoded(width * 3);
            for (size_t x = 0; x < width; ++x)
                for (int c = 0; c < 3; ++c) colour[x * 3 + c] = straightChannel(image, first + x, c, alpha);
            raster::encodeSrgb8(colour.data(), colour.size(), encoded.data());
            uint8_t* row = out.data() + first * channels;
            if (!alpha) {
                std::memcpy(row, encoded.data(), encoded.size());
                return;
            }
            for (size_t x = 0; x < width; ++x) {
                std::memcpy(row + x * 4, &encoded[x * 3], 3);
                row[x * 4 + 3] = uint8_t(std::lround(std::clamp(image.rgba[(first + x) * 4 + 3], 0.0f, 1.0f) * 255.0f));
            }
        });
        return out;
    }
    raster::parallelFor(size_t(image.height), [&](size_t y) {
        for (size_t i = y * size_t(image.width); i < (y + 1) * size_t(image.width); ++i)
            for (int c = 0; c < channels; ++c) {
                const float v = c == 3 ? std::clamp(image.rgba[i * 4 + 3], 0.0f, 1.0f) : straightChannel(image, i, c, alpha);
                const uint16_t sample = c == 3 ? uint16_t(std::lround(v * 65535.0f)) : raster::encodeSrgb16(v);
                std::memcpy(&out[(i * channels + c) * bytesPerSample], &sample, 2);
            }
    });
    return out;
}


raster::Image legibleDepth(const raster::Image& distances) {
    float nearest = std::numeric_limits<float>::infinity(), farthest = 0.0f;
    for (size_t i = 0; i < distances.rgba.size() / 4; ++i)
        if (distances.rgba[i * 4 + 3] > 0.0f) {
            nearest = std::min(nearest, distances.rgba[i * 4]);
            farthest = std::max(farthest, distances.rgba[i * 4]);
        }
    raster::Image out = distances;
    const float span = farthest > nearest ? farthest - nearest : 1.0f;
    for (size_t i = 0; i < out.rgba.size() / 4; ++i) {
        const bool covered = distances.rgba[i * 4 + 3] > 0.0f;
        // Evenly spaced in the file's codes: the grey is chosen as a display value, then decoded
        // to the linear value the sRGB encoding turns back into it.
        const double grey = covered ? kNearestGrey - (kNearestGrey - kFarthestGrey) * (distances.rgba[i * 4] - nearest) / span : 0.0;
        const float linear = float(raster::decodeSrgb(grey));
        for (int c = 0; c < 3; ++c) out.rgba[i * 4 + c] = linear;
        out.rgba[i * 4 + 3] = 1.0f;
    }
    return out;
}

const raster::Image& displayImage(const raster::Image& image, View view, bool depthIsDistance, raster::Image& legible) {
    if (view != View::Depth || !depthIsDistance) return image;
    legible = legibleDepth(image);
    return legible;
}

std::vector<uint8_t> displayRgba8(const raster::Image& image, bool alpha) {
    const std::vector<uint8_t> encoded = encodeDisplayPixels(image, alpha, 8);
    if (alpha) return encoded;
    std::vector<uint8_t> rgba(size_t(image.width) * image.height * 4, 255);
    for (size_t i = 0; i < size_t(image.width) * image.height; ++i) std::memcpy(&rgba[i * 4], &encoded[i * 3], 3);
    return rgba;
}

}  // namespace cuberille::render
