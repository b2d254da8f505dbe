#include "raster/resolve.h"

#include <cassert>
#include <algorithm>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "raster/parallel.h"

namespace cuberille::raster {
namespace {

void prepare(const Framebuffer& fb, Image& out) {
    out.width = fb.width();
    out.height = fb.height();
    out.rgba.resize(size_t(out.width) * out.height * 4);
}

void store(Image& out, int x, int y, const glm::vec4& v) {
    float* p = out.pixel(x, y);
    p[0] = v.r, p[1] = v.g, p[2] = v.b, p[3] = v.a;
}

/// One row of one tile, clipped to the image: where it lies in the image and in the tile.
struct TileRow {
    int tile;
    int x0, y;     // its first pixel in the image
    int yInTile;   // its row in the tile
    int width;     // pixels, fewer than a tile's at the image's right edge
};

// Calls f(row) for every row of every tile, one task per row of tiles, in image order within it,
// then finishTask() on the thread that ran the task.
template <class F, class G>
void forEachTileRow(const Framebuffer& fb, F&& f, G&& finishTask) {
    parallelFor(size_t(fb.tilesY()), [&](size_t ty) {
        for (int tx = 0; tx < fb.tilesX(); ++tx) {
            const int x0 = tx * kTileSizePixels, y0 = int(ty) * kTileSizePixels;
            const int w = std::min(fb.width() - x0, kTileSizePixels), h = std::min(fb.height() - y0, kTileSizePixels);
            for (int y = 0; y < h; ++y) f(TileRow{int(ty) * fb.tilesX() + tx, x0, y0 + y, y, w});
        }
        finishTask();
    });
}

template <class F>
void forEachTileRow(const Framebuffer& fb, F&& f) {
    forEachTileRow(fb, f, [] {});
}

// Calls f(x, y, firstSampleIndex, tileIndex) for every pixel.
template <class F>
void forEachPixelByTile(const Framebuffer& fb, F&& f) {
    forEachTileRow(fb, [&](const TileRow& r) {
        for (int x = 0; x < r.width; ++x)
            f(r.x0 + x, r.y, (size_t(r.yInTile) * kTileSizePixels + size_t(x)) * fb.samples(), r.tile);
    });
}

// A row of the resolved image, written past the caches: the image (33 MB at 1920x1080) is not
// read again by this frame, and a plain store first reads each line it writes. Measured at one
// sample, 1920x1080 (raster_bench): a frame of CesiumMan, mostly clear tiles, resolved in 2.1 ms
// with plain stores, 1.0 ms with these.
void streamRow(float* out, const glm::vec4* pixels, int count) {
#if defined(__SSE2__)
    if ((reinterpret_cast<uintptr_t>(out) & 15) == 0) {
        for (int i = 0; i < count; ++i) _mm_stream_ps(out + 4 * i, _mm_loadu_ps(&pixels[i].r));
        return;
    }
#endif
    for (int i = 0; i < count; ++i)
        for (int c = 0; c < 4; ++c) out[4 * i + c] = pixels[i][c];
}

// Once per task, not per row: a fence waits for the write-combining buffers to drain (a fence
// per row took the 1-sample resolve from 1.0 back to 2.3 ms).
void fenceStreamedRows() {
#if defined(__SSE2__)
    _mm_sfence();  // streamed stores are weakly ordered: publish them before the task ends
#endif
}

// Perceptually ordered ramp for heat maps (black → blue → red → yellow → white).
glm::vec4 heat(float t) {
    static const glm::vec3 stops[] = {{0, 0, 0}, {0.0f, 0.05f, 0.6f}, {0.8f, 0.05f, 0.05f},
                                      {1.0f, 0.85f, 0.0f}, {1, 1, 1}};
    t = std::clamp(t, 0.0f, 1.0f) * 4.0f;
    const int i = std::min(3, int(t));
    return glm::vec4(glm::mix(stops[i], stops[i + 1], t - float(i)), 1.0f);
}

}  // namespace

void resolveColor(const Framebuffer& fb, Image& out) {
    prepare(fb, out);
    const int n = fb.samples();
    const double invN = 1.0 / n;
    // A tile row at a time: copied (one sample), averaged into a local row (more), or the clear
    // colour (a tile nothing drew to), then streamed to the image.
    glm::vec4 clearRow[kTileSizePixels];
    std::fill_n(clearRow, kTileSizePixels, fb.desc().clearColor);
    forEachTileRow(fb, [&](const TileRow& r) {
        if (!fb.tileTouched(r.tile) || !fb.hasColor()) return streamRow(out.pixel(r.x0, r.y), clearRow, r.width);
        const glm::vec4* samples = fb.tileColor(r.tile) + size_t(r.yInTile) * kTileSizePixels * n;
        if (n == 1) return streamRow(out.pixel(r.x0, r.y), samples, r.width);
        glm::vec4 averaged[kTileSizePixels];
        for (int x = 0; x < r.width; ++x) {
            const glm::vec4* s = samples + size_t(x) * n;
            double sum[4] = {0, 0, 0, 0};
            for (int i = 0; i < n; ++i)
                for (int c = 0; c < 4; ++c) sum[c] += s[i][c];
            averaged[x] = glm::vec4(float(sum[0] * invN), float(sum[1] * invN), float(sum[2] * invN), float(sum[3] * invN));
        }
        streamRow(out.pixel(r.x0, r.y), averaged, r.width);
    }, fenceStreamedRows);
}

void resolveDepthPlane(const Framebuffer& fb, std::vector<float>& out) {
    out.resize(size_t(fb.width()) * fb.height());
    const int n = fb.samples();
    const bool reversed = fb.desc().depthConvention == DepthConvention::Reversed;
    if (n == 1 && !reversed) {  // a shadow map's case: each tile row is a run of depths already
        forEachTileRow(fb, [&](const TileRow& r) {
            float* row = out.data() + size_t(r.y) * fb.width() + r.x0;
            if (fb.tileTouched(r.tile)) std::copy_n(fb.tileDepth(r.tile) + size_t(r.yInTile) * kTileSizePixels, r.width, row);
            else std::fill_n(row, r.width, fb.desc().clearDepth);
        });
        return;
    }
    forEachPixelByTile(fb, [&](int x, int y, size_t first, int tile) {
        // Keys back to depth as the standard convention reads it (0 near, 1 far), so the view
        // looks the same either way.
        float d = fb.desc().clearDepth;
        if (fb.tileTouched(tile)) {
            const float* keys = fb.tileDepth(tile) + first;
            if (n == 1) {
                d = reversed ? 1.0f + keys[0] : keys[0];
            } else {
                double sum = 0;
                for (int i = 0; i < n; ++i) sum += reversed ? 1.0 + double(keys[i]) : double(keys[i]);
                d = float(sum / n);
            }
        }
        out[size_t(y) * fb.width() + x] = d;
    });
}

void resolveWindowDepth(const Framebuffer& fb, std::vector<float>& out) {
    assert(fb.samples() == 1);
    out.resize(size_t(fb.width()) * fb.height());
    const float sign = depthKeySign(fb.desc().depthConvention);  // window depth = sign x key, exactly
    const float cleared = sign * clearDepthKey(fb.desc());
    forEachTileRow(fb, [&](const TileRow& r) {
        float* row = out.data() + size_t(r.y) * fb.width() + r.x0;
        if (!fb.tileTouched(r.tile)) {
            std::fill_n(row, r.width, cleared);
            return;
        }
        const float* keys = fb.tileDepth(r.tile) + size_t(r.yInTile) * kTileSizePixels;
        for (int x = 0; x < r.width; ++x) row[x] = sign * keys[x];
    });
}

void resolveDepth(const Framebuffer& fb, Image& out) {
    std::vector<float> depth;
    resolveDepthPlane(fb, depth);
    prepare(fb, out);
    parallelFor(size_t(out.height), [&](size_t y) {
        for (int x = 0; x < out.width; ++x) {
            const float d = depth[y * out.width + x];
            store(out, x, int(y), glm::vec4(d, d, d, 1.0f));
        }
    });
}

void resolveViewDistance(const Framebuffer& fb, float nearPlane, float farPlane, Image& out, bool orthographic) {
    prepare(fb, out);
    const int n = fb.samples();
    const bool reversed = fb.desc().depthConvention == DepthConvention::Reversed;
    const double nearD = nearPlane, farD = farPlane;
    forEachPixelByTile(fb, [&](int x, int y, size_t first, int tile) {
        double sum = 0;
        int covered = 0;
        if (fb.tileTouched(tile)) {
            const float* keys = fb.tileDepth(tile) + first;
            for (int i = 0; i < n; ++i) {
                // The key back to standard depth (raster/depth.h); the far plane is "nothing".
                const double d = reversed ? 1.0 + double(keys[i]) : double(keys[i]);
                if (!(d < 1.0)) continue;
                // Inverting d = f (D - n) / ((f - n) D), the perspective depth of distance D, or
                // d = (D - n) / (f - n), the orthographic one.
                sum += orthographic ? nearD + d * (farD - nearD) : farD * nearD / (farD - d * (farD - nearD));
                ++covered;
            }
        }
        const float distance = covered ? float(sum / covered) : 0.0f;
        store(out, x, y, glm::vec4(distance, distance, distance, float(covered) / float(n)));
    });
}

uint64_t coveredPixels(const Framebuffer& fb) {
    const float clear = clearDepthKey(fb.desc());
    const int n = fb.samples();
    std::vector<uint64_t> perTile(size_t(fb.tileCount()), 0);
    raster::parallelFor(size_t(fb.tileCount()), [&](size_t tile) {
        if (!fb.tileTouched(int(tile))) return;
        const float* depth = fb.tileDepth(int(tile));
        const int tx = int(tile) % fb.tilesX(), ty = int(tile) / fb.tilesX();
        const int w = std::min(kTileSizePixels, fb.width() - tx * kTileSizePixels);
        const int h = std::min(kTileSizePixels, fb.height() - ty * kTileSizePixels);
        uint64_t covered = 0;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const float* samples = depth + (size_t(y) * kTileSizePixels + size_t(x)) * size_t(n);
                bool any = false;
                for (int s = 0; s < n; ++s) any = any || samples[s] != clear;
                covered += any;
            }
        perTile[tile] = covered;
    });
    uint64_t total = 0;
    for (uint64_t c : perTile) total += c;
    return total;
}

glm::vec3 overdrawColor(float layers) {
    // 8 full layers of depth-passing samples saturate the ramp.
    return layers > 0.0f ? glm::vec3(heat(0.1f + 0.9f * layers / 8.0f)) : glm::vec3(0.0f);
}

void visualizeOverdraw(const Framebuffer& fb, Image& out) {
    prepare(fb, out);
    const auto& counts = fb.overdrawCounts();
    // Scale: 8 full layers of depth-passing samples saturate the ramp.
    const float scale = 1.0f / (8.0f * fb.samples());
    for (int y = 0; y < fb.height(); ++y)
        for (int x = 0; x < fb.width(); ++x) {
            const uint32_t c = counts.empty() ? 0 : counts[size_t(y) * fb.width() + x];
            store(out, x, y, c ? heat(0.1f + 0.9f * c * scale) : glm::vec4(0, 0, 0, 1));
        }
}

void visualizeBlockClasses(const Framebuffer& fb, const Image& color, Image& out) {
    prepare(fb, out);
    const glm::vec3 &kEmpty = kBlockUntouchedColor, &kPartial = kBlockPartialColor, &kFull = kBlockFullColor,
                    &kBoth = kBlockBothColor;
    const auto& partial = fb.blockPartial();
    const auto& full = fb.blockFull();
    for (int y = 0; y < fb.height(); ++y)
        for (int x = 0; x < fb.width(); ++x) {
            const size_t b = size_t(y / kBlockSizePixels) * fb.blocksX() + x / kBlockSizePixels;
            const bool p = !partial.empty() && partial[b], f = !full.empty() && full[b];
            glm::vec3 c = p && f ? kBoth : p ? kPartial : f ? kFull : kEmpty;
            const float* src = color.pixel(x, y);
            c = glm::mix(c, glm::vec3(src[0], src[1], src[2]), 0.25f);
            const bool edge = x % kBlockSizePixels == 0 || y % kBlockSizePixels == 0;
            const bool tileEdge = x % kTileSizePixels == 0 || y % kTileSizePixels == 0;
            if (tileEdge) c = glm::vec3(1.0f);
            else if (edge) c *= 0.5f;
            store(out, x, y, glm::vec4(c, 1.0f));
        }
}

}  // namespace cuberille::raster
