#include "raster/texture.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cuberille::raster {

Texture::Texture(int width, int height, std::vector<glm::vec4> rgba, WrapMode wrapU, WrapMode wrapV,
                 TextureFilter filter)
    : wrapU_(wrapU), wrapV_(wrapV), filter_(filter) {
    if (width <= 0 || height <= 0 || rgba.size() != size_t(width) * size_t(height))
        throw std::invalid_argument("texture: size does not match its texels");
    levels_.push_back({width, height, std::move(rgba)});
    while (levels_.back().width > 1 || levels_.back().height > 1) {
        const Level& src = levels_.back();
        Level dst{std::max(1, src.width / 2), std::max(1, src.height / 2), {}};
        dst.texels.resize(size_t(dst.width) * dst.height);
        for (int y = 0; y < dst.height; ++y)
            for (int x = 0; x < dst.width; ++x) {
                const int x0 = std::min(2 * x, src.width - 1), x1 = std::min(2 * x + 1, src.width - 1);
                const int y0 = std::min(2 * y, src.height - 1), y1 = std::min(2 * y + 1, src.height - 1);
                const auto& t = src.texels;
                dst.texels[size_t(y) * dst.width + x] =
                    0.25f * (t[size_t(y0) * src.width + x0] + t[size_t(y0) * src.width + x1] +
                             t[size_t(y1) * src.width + x0] + t[size_t(y1) * src.width + x1]);
            }
        levels_.push_back(std::move(dst));
    }
}

int Texture::wrap(int i, int size, WrapMode mode) const {
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

glm::vec4 Texture::sample(glm::vec2 uv, float lod) const {
    if (!(lod > 0.0f))  // magnification (also NaN)
        return filter_.magnifyNearest ? sampleNearest(0, uv) : sampleBilinear(0, uv);
    const int last = levelCount() - 1;
    switch (filter_.minify) {
        case MinFilter::Nearest: return sampleNearest(0, uv);
        case MinFilter::Linear: return sampleBilinear(0, uv);
        case MinFilter::NearestMipmapNearest:
        case MinFilter::LinearMipmapNearest: {
            // OpenGL's nearest level: ceil(lod + 0.5) - 1, i.e. lod rounded with ties down.
            const int level = std::min(last, int(std::ceil(lod + 0.5f)) - 1);
            return filter_.minify == MinFilter::NearestMipmapNearest ? sampleNearest(level, uv)
                                                                     : sampleBilinear(level, uv);
        }
        case MinFilter::NearestMipmapLinear: {
            lod = std::min(lod, float(last));
            const int l0 = int(lod), l1 = std::min(l0 + 1, last);
            return glm::mix(sampleNearest(l0, uv), sampleNearest(l1, uv), lod - float(l0));
        }
        case MinFilter::LinearMipmapLinear: break;
    }
    return sampleTrilinear(uv, lod);
}

glm::vec4 Texture::sampleNearest(int level, glm::vec2 uv) const {
    const Level& l = levels_[level];
    float x = uv.x * float(l.width), y = uv.y * float(l.height);
    if (!std::isfinite(x) || !std::isfinite(y)) x = y = 0.0f;
    x = std::clamp(x, -1e6f, 1e6f);
    y = std::clamp(y, -1e6f, 1e6f);
    return texel(level, wrap(int(std::floor(x)), l.width, wrapU_), wrap(int(std::floor(y)), l.height, wrapV_));
}

glm::vec4 Texture::sampleBilinear(int level, glm::vec2 uv) const {
    const Level& l = levels_[level];
    // Texel space with texel centres on integers; non-finite coordinates sample texel 0.
    float x = uv.x * float(l.width) - 0.5f, y = uv.y * float(l.height) - 0.5f;
    if (!std::isfinite(x) || !std::isfinite(y)) x = y = 0.0f;
    x = std::clamp(x, -1e6f, 1e6f);  // far beyond any wrap period; keeps the int conversion defined
    y = std::clamp(y, -1e6f, 1e6f);
    const float fx = std::floor(x), fy = std::floor(y);
    const float ax = x - fx, ay = y - fy;
    const int x0 = int(fx), y0 = int(fy);
    const int xa = wrap(x0, l.width, wrapU_), xb = wrap(x0 + 1, l.width, wrapU_);
    const int ya = wrap(y0, l.height, wrapV_), yb = wrap(y0 + 1, l.height, wrapV_);
    const glm::vec4 top = glm::mix(texel(level, xa, ya), texel(level, xb, ya), ax);
    const glm::vec4 bottom = glm::mix(texel(level, xa, yb), texel(level, xb, yb), ax);
    return glm::mix(top, bottom, ay);
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

float Texture::levelOfDetail(glm::vec2 dUVdx, glm::vec2 dUVdy) const {
    const glm::vec2 size{float(width()), float(height())};
    const float rho = std::max(glm::length(dUVdx * size), glm::length(dUVdy * size));
    return rho > 0.0f ? std::log2(rho) : 0.0f;
}

}  // namespace cuberille::raster
