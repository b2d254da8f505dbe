#include "apps/image_error.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace cuberille::apps {
namespace {

// The continuous sRGB transfer function (IEC 61966-2-1), clamped to [0, 1].
double encodeSrgb(float linear) {
    const double v = std::clamp(double(linear), 0.0, 1.0);
    return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

// Per pixel, the squared error summed over RGB and the largest channel difference.
struct PixelError {
    double squared;
    double largest;
};

PixelError pixelError(const raster::Image& a, const raster::Image& b, int x, int y) {
    const float* p = a.pixel(x, y);
    const float* q = b.pixel(x, y);
    PixelError e{0.0, 0.0};
    for (int c = 0; c < 3; ++c) {
        const double d = std::abs(encodeSrgb(p[c]) - encodeSrgb(q[c]));
        e.squared += d * d;
        e.largest = std::max(e.largest, d);
    }
    return e;
}

void requireSameSize(const raster::Image& a, const raster::Image& b) {
    if (a.width != b.width || a.height != b.height)
        throw std::runtime_error("images of different sizes: " + std::to_string(a.width) + "x" +
                                 std::to_string(a.height) + " against " + std::to_string(b.width) + "x" +
                                 std::to_string(b.height));
}

}  // namespace

ImageError compareImages(const raster::Image& image, const raster::Image& truth) {
    requireSameSize(image, truth);
    ImageError r;
    double sum = 0.0;
    size_t over1 = 0, over8 = 0;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            const PixelError e = pixelError(image, truth, x, y);
            sum += e.squared;
            r.maxError = std::max(r.maxError, e.largest);
            over1 += e.largest > 1.0 / 255.0;
            over8 += e.largest > 8.0 / 255.0;
        }
    const double pixels = std::max(1.0, double(image.width) * image.height);
    r.rmse = std::sqrt(sum / (3.0 * pixels));
    r.psnrDb = r.rmse > 0.0 ? 20.0 * std::log10(1.0 / r.rmse) : std::numeric_limits<double>::infinity();
    r.shareOver1 = double(over1) / pixels;
    r.shareOver8 = double(over8) / pixels;
    return r;
}

// A summed-area table of the per-pixel squared error gives every window's sum in four lookups.
PixelRect worstRegion(const raster::Image& image, const raster::Image& truth, int sidePixels) {
    requireSameSize(image, truth);
    const int w = image.width, h = image.height;
    const int side = std::max(1, std::min({sidePixels, w, h}));
    std::vector<double> table(size_t(w + 1) * (h + 1), 0.0);
    auto at = [&](int x, int y) -> double& { return table[size_t(y) * (w + 1) + x]; };
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            at(x + 1, y + 1) = pixelError(image, truth, x, y).squared + at(x, y + 1) + at(x + 1, y) - at(x, y);
    PixelRect best{0, 0, side, side};
    double bestSum = -1.0;
    for (int y = 0; y + side <= h; ++y)
        for (int x = 0; x + side <= w; ++x) {
            const double s = at(x + side, y + side) - at(x, y + side) - at(x + side, y) + at(x, y);
            if (s > bestSum) {
                bestSum = s;
                best.x = x;
                best.y = y;
            }
        }
    return best;
}

raster::Image comparisonCrop(const raster::Image& image, const raster::Image& truth, PixelRect region, int scale) {
    requireSameSize(image, truth);
    constexpr int kGapPixels = 4;
    const int panelWidth = region.width * scale;
    raster::Image out;
    out.width = 3 * panelWidth + 2 * kGapPixels;
    out.height = region.height * scale;
    out.rgba.assign(size_t(out.width) * out.height * 4, 1.0f);  // white gaps
    for (int y = 0; y < out.height; ++y)
        for (int panel = 0; panel < 3; ++panel)
            for (int x = 0; x < panelWidth; ++x) {
                const int sx = region.x + x / scale, sy = region.y + y / scale;
                float* d = out.pixel(panel * (panelWidth + kGapPixels) + x, y);
                const float* p = image.pixel(sx, sy);
                const float* q = truth.pixel(sx, sy);
                if (panel < 2) {
                    for (int c = 0; c < 4; ++c) d[c] = panel == 0 ? p[c] : q[c];
                    d[3] = 1.0f;
                    continue;
                }
                double largest = 0.0;
                for (int c = 0; c < 3; ++c) largest = std::max(largest, std::abs(encodeSrgb(p[c]) - encodeSrgb(q[c])));
                d[0] = float(std::min(1.0, 8.0 * largest));
                d[1] = d[2] = 0.0f;
                d[3] = 1.0f;
            }
    return out;
}

}  // namespace cuberille::apps
