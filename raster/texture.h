#pragma once
// Textures: a linear-RGBA mip chain with glTF's wrap modes and filters.
//
// Texels are stored as the image gave them, as GPUs store them: 8-bit images as 8-bit texels
// (TexelFormat::Srgb8 for colour, whose RGB is sRGB-encoded, Unorm8 for data such as normals,
// metallic-roughness and occlusion), decoded to linear float through a 256-entry table at each
// fetch and filtered in float; other sources (16-bit images, textures made in code) as linear
// float texels. Against float storage, 8-bit texels are a quarter of the memory a fetch touches:
// a 2048x2048 texture is 21 MiB with its mips instead of 85, and five of them were the whole of
// a DamagedHelmet frame's cache misses. The mip levels of an 8-bit texture are box-filtered in
// linear float from the decoded level above and stored again in its format, rounded to nearest
// (sRGB-correct mip generation, as a GPU driver generates them).
//
// Filtering follows the texture's sampler (glTF magFilter / minFilter; trilinear by default).
// Conventions: texture coordinates (u, v) in [0, 1] span the image, v down the rows (glTF's);
// texel (i, j) is centred at ((i + 0.5) / width, (j + 0.5) / height). Level of detail is
// log2 of the texels a pixel step covers, from the UV derivatives the shader computes; level 0
// is the full image and each level halves both sides (2x2 box filter, odd sides rounded down,
// at least 1 texel).
// Layout: each level's texels are stored in tiles of 4x4 (a 64-byte cache line of 8-bit texels,
// the layout GPUs call tiled or swizzled), tiles row-major, all levels in one allocation aligned
// to a cache line. A bilinear footprint then lies in one line 9 times in 16 (row-major: never
// both rows in one line), and the footprints of a block of pixels touch lines in proportion to
// their area instead of one line per texel row they cross (a level of a 2048-texel image has
// rows 8 KiB apart).
// Thread-safety: immutable after construction; sampling is read-only.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <new>
#include <vector>

#include <glm/glm.hpp>

namespace cuberille::raster {

struct TexelPyramid;  // raster/texture_lanes.h

/// The most mip levels a texture has: a side of 2^31 texels.
inline constexpr int kMaxTextureLevels = 32;

enum class WrapMode : uint8_t { Repeat, ClampToEdge, MirroredRepeat };

/// How texels are stored. Srgb8: RGB sRGB-encoded bytes, alpha a linear byte (glTF's base colour
/// and emissive images); Unorm8: four linear bytes; LinearFloat: four floats.
enum class TexelFormat : uint8_t { LinearFloat, Srgb8, Unorm8 };

/// glTF's (OpenGL's) minification filters: within a level, and between levels.
enum class MinFilter : uint8_t {
    Nearest,
    Linear,
    NearestMipmapNearest,
    LinearMipmapNearest,
    NearestMipmapLinear,
    LinearMipmapLinear,
};

struct TextureFilter {
    bool magnifyNearest = false;  // magFilter NEAREST; LINEAR otherwise
    MinFilter minify = MinFilter::LinearMipmapLinear;
    bool operator==(const TextureFilter&) const = default;
};

/// Where a batch of points samples an 8-bit texture: per point, the levels, weights and the four
/// texel places of each level's footprint (raster/texture_lanes.h plans them). They depend only
/// on the texture's layout — its size (which fixes every level's size and place), wraps and
/// filter — and on the points, so the textures of a material that share one layout and one set of
/// texture coordinates (DamagedHelmet binds five 2048x2048 maps to one UV set) are planned once
/// and each only gathers and filters its own texels. The caller owns it and clears it whenever
/// the points change.
struct SampleFootprints {
    static constexpr int kMaxPoints = 64;
    struct Layout {
        int width = 0, height = 0;  // 0: nothing planned
        WrapMode wrapU = WrapMode::Repeat, wrapV = WrapMode::Repeat;
        TextureFilter filter;
        bool operator==(const Layout&) const = default;
    } layout;
    int count = 0;
    // Per point: the first and second level's footprints (as Texture::BilinearFootprint), the
    // weight between them, and the lanes' masks as 0 / -1.
    alignas(64) int32_t index[2][4][kMaxPoints];
    alignas(64) float ax[2][kMaxPoints], ay[2][kMaxPoints];
    alignas(64) float weight[kMaxPoints];
    alignas(64) int32_t nearest[kMaxPoints], mixLevels[kMaxPoints];

    void clear() { layout.width = 0; }
};

class Texture {
public:
    /// `rgba` is width x height linear RGBA, row-major, top row first.
    Texture(int width, int height, std::vector<glm::vec4> rgba, WrapMode wrapU = WrapMode::Repeat,
            WrapMode wrapV = WrapMode::Repeat, TextureFilter filter = {});
    /// `rgba8` is width x height texels of 4 bytes (R, G, B, A), row-major, top row first, in
    /// `format` (Srgb8 or Unorm8).
    Texture(int width, int height, const std::vector<uint8_t>& rgba8, TexelFormat format,
            WrapMode wrapU = WrapMode::Repeat, WrapMode wrapV = WrapMode::Repeat, TextureFilter filter = {});

    /// The same texels under other filters (an accuracy knob: `render --texture-filter`).
    void setFilter(TextureFilter filter) { filter_ = filter; }
    TextureFilter filter() const { return filter_; }
    WrapMode wrapU() const { return wrapU_; }
    WrapMode wrapV() const { return wrapV_; }

    int width(int level = 0) const { return levels_.width[level]; }
    int height(int level = 0) const { return levels_.height[level]; }
    int levelCount() const { return levels_.count; }
    TexelFormat format() const { return format_; }
    /// Texel (x, y) of a level, decoded to linear RGBA.
    glm::vec4 texel(int level, int x, int y) const { return texelAt(texelIndex(level, x, y)); }
    /// A level's texels in an 8-bit format, R in the low byte, row-major (what an upload to a
    /// GPU API takes); empty for LinearFloat.
    std::vector<uint32_t> packedRows(int level) const;

    /// Where texel (x, y) of a level lies in the texture's storage (see Layout above).
    size_t texelIndex(int level, int x, int y) const {
        return size_t(levels_.offset[level]) + size_t(y >> 2) * size_t(levels_.tileRowStride[level]) + size_t((y & 3) << 2) +
               size_t((x >> 2) << 4) + size_t(x & 3);
    }

    /// With the texture's filters: lod <= 0 magnifies (level 0), lod > 0 minifies. This is
    /// what the shade stage calls.
    glm::vec4 sample(glm::vec2 uv, float lod) const;

    /// Where sampleBatch() writes: one array per channel (structure-of-arrays, what the shade
    /// stage's loops read), each of at least `count` floats.
    struct Channels {
        float *r, *g, *b, *a;
    };
    /// sample() at `count` points: (out.r[i], out.g[i], out.b[i], out.a[i]) = sample({u[i],
    /// v[i]}, lod[i]), bit for bit. The shade stage fetches a queue of pixels at a time this way:
    /// 8-bit texels in vector lanes (raster/texture_lanes.h), float texels a point at a time with
    /// every point's texel addresses found before the texels are read, so the cache misses of
    /// many points overlap instead of each waiting behind the last.
    void sampleBatch(int count, const float* u, const float* v, const float* lod, Channels out) const;
    /// The same, for at most SampleFootprints::kMaxPoints points, with the footprints kept in
    /// `shared`: planned there unless it already holds these points' plan for this texture's
    /// layout (an 8-bit texture of the same size, wraps and filter). Float textures ignore it.
    void sampleBatch(int count, const float* u, const float* v, const float* lod, Channels out, SampleFootprints& shared) const;
    glm::vec4 sampleNearest(int level, glm::vec2 uv) const;
    glm::vec4 sampleBilinear(int level, glm::vec2 uv) const;
    /// lod <= 0 samples level 0; fractional lods blend the two nearest levels.
    glm::vec4 sampleTrilinear(glm::vec2 uv, float lod) const;
    /// Level of detail for UV derivatives per pixel step in x and y:
    /// levelOfFootprint(footprintTexels(...)), the two halves apart so a loop over pixels can
    /// vectorise the first and call log2 in the second.
    float levelOfDetail(glm::vec2 dUVdx, glm::vec2 dUVdy) const { return levelOfFootprint(footprintTexels(dUVdx, dUVdy)); }
    /// The texels of level 0 a pixel step covers, the longer of the two steps.
    float footprintTexels(glm::vec2 dUVdx, glm::vec2 dUVdy) const {
        const glm::vec2 size{float(width()), float(height())};
        return std::max(glm::length(dUVdx * size), glm::length(dUVdy * size));
    }
    static float levelOfFootprint(float texels) { return texels > 0.0f ? std::log2(texels) : 0.0f; }

private:
    /// Storage aligned to a cache line, so that a 4x4 tile of 8-bit texels is one line.
    template <class T>
    struct CacheLineAllocator {
        using value_type = T;
        static constexpr std::align_val_t kAlignment{64};
        CacheLineAllocator() = default;
        template <class U>
        CacheLineAllocator(const CacheLineAllocator<U>&) {}
        T* allocate(size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), kAlignment)); }
        void deallocate(T* p, size_t) { ::operator delete(p, kAlignment); }
        friend bool operator==(const CacheLineAllocator&, const CacheLineAllocator&) { return true; }
    };
    void allocateLevels(int width, int height);
    /// What the lane sampler reads of an 8-bit texture (raster/texture_lanes.h).
    TexelPyramid lanePyramid() const;
    void buildMipChain();
    /// The four texels and weights sampleBilinear(level, uv) blends.
    struct BilinearFootprint {
        uint32_t index[4];  // (xa, ya), (xb, ya), (xa, yb), (xb, yb) in the storage
        float ax, ay;
    };
    BilinearFootprint footprint(int level, glm::vec2 uv) const;
    uint32_t nearestIndex(int level, glm::vec2 uv) const;
    glm::vec4 blend(const BilinearFootprint& f) const;
    /// One texel, or one bilinear footprint, on a level.
    struct Tap {
        BilinearFootprint f;  // a nearest tap uses index[0]
        int level;
        bool nearest;
    };
    /// What sample() reads for one point under the texture's filters: a tap, or two taps on
    /// adjacent levels mixed by `weight`.
    struct SamplePlan {
        Tap first, second;
        bool mix;
        float weight;
    };
    SamplePlan plan(glm::vec2 uv, float lod) const;
    Tap tap(int level, bool nearest, glm::vec2 uv) const;
    glm::vec4 read(const Tap& t) const { return t.nearest ? texelAt(t.f.index[0]) : blend(t.f); }
    glm::vec4 gather(const SamplePlan& p) const {
        const glm::vec4 a = read(p.first);
        return p.mix ? glm::mix(a, read(p.second), p.weight) : a;
    }
    glm::vec4 texelAt(size_t i) const {
        if (format_ == TexelFormat::LinearFloat) return texels_[i];
        const uint32_t p = packed_[i];
        return {decodeRgb_[p & 0xFF], decodeRgb_[(p >> 8) & 0xFF], decodeRgb_[(p >> 16) & 0xFF], decodeAlpha_[p >> 24]};
    }
    int wrap(int i, int size, WrapMode mode) const;

    /// Each level's size and place, a table per field, as the lane sampler gathers them
    /// (raster/texture_lanes.h) and the one-point sampler reads them.
    struct Levels {
        int count = 0;
        int32_t width[kMaxTextureLevels], height[kMaxTextureLevels];
        int32_t offset[kMaxTextureLevels];         // first texel in the storage
        int32_t tileRowStride[kMaxTextureLevels];  // texels per row of tiles: 16 x ceil(width / 4)
    } levels_{};
    std::vector<glm::vec4, CacheLineAllocator<glm::vec4>> texels_;  // LinearFloat: every level
    std::vector<uint32_t, CacheLineAllocator<uint32_t>> packed_;    // 8-bit formats: every level
    WrapMode wrapU_, wrapV_;
    TextureFilter filter_;
    TexelFormat format_ = TexelFormat::LinearFloat;
    const float* decodeRgb_ = nullptr;    // 256 linear values for an 8-bit format's colour bytes
    const float* decodeAlpha_ = nullptr;  // and its alpha bytes
};

}  // namespace cuberille::raster
