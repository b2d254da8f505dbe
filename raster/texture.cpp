#include "raster/texture.h"

#include "raster/srgb.h"
#include "raster/texture_lanes.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <cmath>
#include <stdexcept>

namespace cuberille::raster {

namespace {

/// Byte to linear value: b / 255, as a float image reader divides (UNORM).
const float* unorm8Table() {
    static const auto table = [] {
        std::array<float, 256> t{};
        for (int i = 0; i < 256; ++i) t[i] = float(i) / 255.0f;
        return t;
    }();
    return table.data();
}

/// Byte to linear value through the sRGB transfer function (raster/srgb.h).
const float* srgb8Table() {
    static const auto table = [] {
        std::array<float, 256> t{};
        for (int i = 0; i < 256; ++i) t[i] = decodeSrgb8(uint8_t(i));
        return t;
    }();
    return table.data();
}

uint8_t encodeUnorm8(float linear) {
    if (!(linear > 0.0f)) return 0;  // NaN too
    if (linear >= 1.0f) return 255;
    return uint8_t(linear * 255.0f + 0.5f);  // round to nearest
}

uint32_t pack(const glm::vec4& linear, TexelFormat format) {
    auto rgb = [&](float v) { return format == TexelFormat::Srgb8 ? encodeSrgb8(v) : encodeUnorm8(v); };
    return uint32_t(rgb(linear.r)) | uint32_t(rgb(linear.g)) << 8 | uint32_t(rgb(linear.b)) << 16 |
           uint32_t(encodeUnorm8(linear.a)) << 24;
}

}  // namespace

Texture::Texture(int width, int height, std::vector<glm::vec4> rgba, WrapMode wrapU, WrapMode wrapV,
                 TextureFilter filter)
    : wrapU_(wrapU), wrapV_(wrapV), filter_(filter) {
    if (width <= 0 || height <= 0 || rgba.size() != size_t(width) * size_t(height))
        throw std::invalid_argument("texture: size does not match its texels");
    allocateLevels(width, height);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) texels_[texelIndex(0, x, y)] = rgba[size_t(y) * width + x];
    buildMipChain();
}

Texture::Texture(int width, int height, const std::vector<uint8_t>& rgba8, TexelFormat format, WrapMode wrapU,
                 WrapMode wrapV, TextureFilter filter)
    : wrapU_(wrapU), wrapV_(wrapV), filter_(filter), format_(format) {
    if (format == TexelFormat::LinearFloat) throw std::invalid_argument("texture: bytes need an 8-bit format");
    if (width <= 0 || height <= 0 || rgba8.size() != size_t(width) * size_t(height) * 4)
        throw std::invalid_argument("texture: size does not match its texels");
    decodeRgb_ = format == TexelFormat::Srgb8 ? srgb8Table() : unorm8Table();
    decodeAlpha_ = unorm8Table();
    allocateLevels(width, height);
    static_assert(std::endian::native == std::endian::little, "texels are packed little-endian");
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)  // R in the low byte (little-endian)
            std::memcpy(&packed_[texelIndex(0, x, y)], &rgba8[(size_t(y) * width + x) * 4], 4);
    buildMipChain();
}

// Every level's size and place, down to 1x1; each level's tiles start on a tile.
void Texture::allocateLevels(int width, int height) {
    size_t total = 0;
    for (int w = width, h = height;; w = std::max(1, w / 2), h = std::max(1, h / 2)) {
        const size_t tilesX = (size_t(w) + 3) / 4, tilesY = (size_t(h) + 3) / 4;
        // Texel indices are 32-bit signed lanes in the lane sampler.
        if (total + tilesX * tilesY * 16 > size_t(INT32_MAX)) throw std::invalid_argument("texture: too many texels");
        const int level = levels_.count++;
        levels_.width[level] = w, levels_.height[level] = h;
        levels_.offset[level] = int32_t(total), levels_.tileRowStride[level] = int32_t(tilesX * 16);
        total += tilesX * tilesY * 16;
        if (w == 1 && h == 1) break;
    }
    if (format_ == TexelFormat::LinearFloat)
        texels_.assign(total, glm::vec4(0.0f));
    else
        packed_.assign(total, 0u);
}

// 2x2 box filter in linear float, down to 1x1; an 8-bit level is stored again in its format.
void Texture::buildMipChain() {
    for (int level = 1; level < levelCount(); ++level) {
        const int srcWidth = width(level - 1), srcHeight = height(level - 1);
        for (int y = 0; y < height(level); ++y)
            for (int x = 0; x < width(level); ++x) {
                const int x0 = std::min(2 * x, srcWidth - 1), x1 = std::min(2 * x + 1, srcWidth - 1);
                const int y0 = std::min(2 * y, srcHeight - 1), y1 = std::min(2 * y + 1, srcHeight - 1);
                const glm::vec4 average = 0.25f * (texel(level - 1, x0, y0) + texel(level - 1, x1, y0) +
                                                   texel(level - 1, x0, y1) + texel(level - 1, x1, y1));
                const size_t i = texelIndex(level, x, y);
                if (format_ == TexelFormat::LinearFloat)
                    texels_[i] = average;
                else
                    packed_[i] = pack(average, format_);
            }
    }
}

std::vector<uint32_t> Texture::packedRows(int level) const {
    if (format_ == TexelFormat::LinearFloat) return {};
    const int w = width(level), h = height(level);
    std::vector<uint32_t> rows(size_t(w) * h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) rows[size_t(y) * w + x] = packed_[texelIndex(level, x, y)];
    return rows;
}

[[gnu::always_inline]] inline int Texture::wrap(int i, int size, WrapMode mode) const {
    if (unsigned(i) < unsigned(size)) return i;  // inside the image: every mode agrees
    switch (mode) {
        case WrapMode::ClampToEdge: return std::clamp(i, 0, size - 1);
        case WrapMode::Repeat: return ((i % size) + size) % size;
        case WrapMode::MirroredRepeat: {
            const int period = 2 * size;
            const int m = ((i % period) + period) % period;
            return m < size ? m : period - 1 - m;
        }
    }
    return 0;
}

glm::vec4 Texture::sample(glm::vec2 uv, float lod) const { return gather(plan(uv, lod)); }

// The glTF (OpenGL) filters for one point: magnification below lod 0 (and for NaN), else the
// minification filter's level or levels.
[[gnu::always_inline]] inline Texture::SamplePlan Texture::plan(glm::vec2 uv, float lod) const {
    SamplePlan p;
    p.mix = false, p.weight = 0.0f;
    if (!(lod > 0.0f)) {  // magnification (also NaN)
        p.first = tap(0, filter_.magnifyNearest, uv);
        return p;
    }
    const int last = levelCount() - 1;
    switch (filter_.minify) {
        case MinFilter::Nearest:
        case MinFilter::Linear: p.first = tap(0, filter_.minify == MinFilter::Nearest, uv); break;
        case MinFilter::NearestMipmapNearest:
        case MinFilter::LinearMipmapNearest:
            // OpenGL's nearest level: ceil(lod + 0.5) - 1, i.e. lod rounded with ties down; lod
            // is clamped to the last level first, so an infinite one (a degenerate derivative)
            // converts to a level and not to an undefined int.
            p.first = tap(std::min(last, int(std::ceil(std::min(lod, float(last)) + 0.5f)) - 1),
                          filter_.minify == MinFilter::NearestMipmapNearest, uv);
            break;
        case MinFilter::NearestMipmapLinear:
        case MinFilter::LinearMipmapLinear: {
            const bool nearest = filter_.minify == MinFilter::NearestMipmapLinear;
            lod = std::min(lod, float(last));
            const int l0 = int(lod);
            p.weight = lod - float(l0);
            p.first = tap(l0, nearest, uv);
            // Nearest taps are always mixed; bilinear ones only between levels (sampleTrilinear).
            p.mix = nearest || p.weight > 0.0f;
            if (p.mix) p.second = tap(std::min(l0 + 1, last), nearest, uv);
            break;
        }
    }
    return p;
}

[[gnu::always_inline]] inline Texture::Tap Texture::tap(int level, bool nearest, glm::vec2 uv) const {
    Tap t;
    t.level = level, t.nearest = nearest;
    if (nearest)
        t.f.index[0] = nearestIndex(level, uv);
    else
        t.f = footprint(level, uv);
    return t;
}

glm::vec4 Texture::sampleNearest(int level, glm::vec2 uv) const { return texelAt(nearestIndex(level, uv)); }

[[gnu::always_inline]] inline uint32_t Texture::nearestIndex(int level, glm::vec2 uv) const {
    const int w = width(level), h = height(level);
    float x = uv.x * float(w), y = uv.y * float(h);
    if (!std::isfinite(x) || !std::isfinite(y)) x = y = 0.0f;
    x = std::clamp(x, -1e6f, 1e6f);
    y = std::clamp(y, -1e6f, 1e6f);
    return uint32_t(texelIndex(level, wrap(int(std::floor(x)), w, wrapU_), wrap(int(std::floor(y)), h, wrapV_)));
}

glm::vec4 Texture::sampleBilinear(int level, glm::vec2 uv) const { return blend(footprint(level, uv)); }

[[gnu::always_inline]] inline Texture::BilinearFootprint Texture::footprint(int level, glm::vec2 uv) const {
    const int w = width(level), h = height(level);
    // Texel space with texel centres on integers; non-finite coordinates sample texel 0.
    float x = uv.x * float(w) - 0.5f, y = uv.y * float(h) - 0.5f;
    if (!std::isfinite(x) || !std::isfinite(y)) x = y = 0.0f;
    x = std::clamp(x, -1e6f, 1e6f);  // far beyond any wrap period; keeps the int conversion defined
    y = std::clamp(y, -1e6f, 1e6f);
    const float fx = std::floor(x), fy = std::floor(y);
    const int x0 = int(fx), y0 = int(fy);
    const int xa = wrap(x0, w, wrapU_), xb = wrap(x0 + 1, w, wrapU_);
    const int ya = wrap(y0, h, wrapV_), yb = wrap(y0 + 1, h, wrapV_);
    return {{uint32_t(texelIndex(level, xa, ya)), uint32_t(texelIndex(level, xb, ya)), uint32_t(texelIndex(level, xa, yb)),
             uint32_t(texelIndex(level, xb, yb))},
            x - fx, y - fy};
}

[[gnu::always_inline]] inline glm::vec4 Texture::blend(const BilinearFootprint& f) const {
    const glm::vec4 top = glm::mix(texelAt(f.index[0]), texelAt(f.index[1]), f.ax);
    const glm::vec4 bottom = glm::mix(texelAt(f.index[2]), texelAt(f.index[3]), f.ax);
    return glm::mix(top, bottom, f.ay);
}

TexelPyramid Texture::lanePyramid() const {
    return {packed_.data(), format_ == TexelFormat::Srgb8, decodeRgb_, levelCount(), wrapU_, wrapV_,
            filter_, levels_.width, levels_.height, levels_.offset, levels_.tileRowStride,
            packed_.size() * sizeof(uint32_t) >= kPrefetchTextureBytes};
}

void Texture::sampleBatch(int count, const float* u, const float* v, const float* lod, Channels out,
                          SampleFootprints& shared) const {
    if (format_ == TexelFormat::LinearFloat || count > SampleFootprints::kMaxPoints) return sampleBatch(count, u, v, lod, out);
    const TexelPyramid pyramid = lanePyramid();
    const SampleFootprints::Layout layout{width(), height(), wrapU_, wrapV_, filter_};
    if (!(shared.layout == layout && shared.count == count)) {
        planSampleFootprints(pyramid, count, u, v, lod, shared);
        shared.layout = layout;
    }
    sampleFootprints(pyramid, shared, out);
}

void Texture::sampleBatch(int count, const float* u, const float* v, const float* lod, Channels out) const {
    if (format_ != TexelFormat::LinearFloat) return sampleLanes(lanePyramid(), count, u, v, lod, out);
    // The plans of a run of points first, then their texels.
    constexpr int kRun = 64;
    SamplePlan plans[kRun];
    for (int start = 0; start < count; start += kRun) {
        const int n = std::min(kRun, count - start);
        for (int i = 0; i < n; ++i) plans[i] = plan({u[start + i], v[start + i]}, lod[start + i]);
        for (int i = 0; i < n; ++i) {
            const glm::vec4 texel = gather(plans[i]);
            out.r[start + i] = texel.r, out.g[start + i] = texel.g, out.b[start + i] = texel.b, out.a[start + i] = texel.a;
        }
    }
}

glm::vec4 Texture::sampleTrilinear(glm::vec2 uv, float lod) const {
    if (!(lod > 0.0f)) return sampleBilinear(0, uv);  // also NaN
    const float maxLevel = float(levelCount() - 1);
    lod = std::min(lod, maxLevel);
    const int l0 = int(lod);
    const int l1 = std::min(l0 + 1, levelCount() - 1);
    const float t = lod - float(l0);
    const glm::vec4 a = sampleBilinear(l0, uv);
    return t > 0.0f ? glm::mix(a, sampleBilinear(l1, uv), t) : a;
}

}  // namespace cuberille::raster
