// Textures: exact texel centres, bilinear midpoints, the three wrap modes, the mip chain, the
// level of detail, and a textured draw that maps one texel to one pixel reproducing the texture
// through the whole pipeline.

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <random>

#include "raster/pipeline.h"
#include "raster/resolve.h"
#include "raster/srgb.h"
#include "raster/texture.h"
#include "tests/raster/test_support.h"

namespace cuberille::testing {
namespace {

using raster::Texture;
using raster::WrapMode;

// Texel (x, y) = (x, y, x + y, 1) / 16: every texel distinct and easy to predict.
Texture ramp(int w, int h, WrapMode u = WrapMode::Repeat, WrapMode v = WrapMode::Repeat) {
    std::vector<glm::vec4> t;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) t.emplace_back(x / 16.0f, y / 16.0f, (x + y) / 16.0f, 1.0f);
    return Texture(w, h, std::move(t), u, v);
}

glm::vec2 centre(int x, int y, int w, int h) { return {(x + 0.5f) / w, (y + 0.5f) / h}; }

TEST(Texture, TexelCentresAreExactAndMidpointsAverage) {
    const Texture t = ramp(8, 4);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 8; ++x) EXPECT_EQ(t.sampleBilinear(0, centre(x, y, 8, 4)), t.texel(0, x, y));
    const glm::vec2 mid = (centre(2, 1, 8, 4) + centre(3, 1, 8, 4)) * 0.5f;
    EXPECT_EQ(t.sampleBilinear(0, mid), 0.5f * (t.texel(0, 2, 1) + t.texel(0, 3, 1)));
}

TEST(Texture, WrapModes) {
    const Texture repeat = ramp(8, 4), clamp = ramp(8, 4, WrapMode::ClampToEdge, WrapMode::ClampToEdge),
                  mirror = ramp(8, 4, WrapMode::MirroredRepeat, WrapMode::MirroredRepeat);
    const glm::vec2 c = centre(1, 2, 8, 4);
    EXPECT_EQ(repeat.sampleBilinear(0, c + glm::vec2(3, -2)), repeat.texel(0, 1, 2));
    EXPECT_EQ(clamp.sampleBilinear(0, glm::vec2(5.0f, -3.0f)), clamp.texel(0, 7, 0));
    // Mirrored: u in (1, 2) runs backwards, so texel 1 reappears as texel 8 - 1 - 1 = 6.
    EXPECT_EQ(mirror.sampleBilinear(0, glm::vec2(1.0f, 0.0f) + glm::vec2(1.0f - c.x, c.y)), mirror.texel(0, 1, 2));
    // Non-finite coordinates do not crash or produce NaN.
    const glm::vec4 s = repeat.sampleBilinear(0, glm::vec2(NAN, INFINITY));
    EXPECT_TRUE(std::isfinite(s.r) && std::isfinite(s.a));
}

TEST(Texture, MipChainBoxFiltersDownToOneTexel) {
    const Texture t = ramp(8, 4);
    ASSERT_EQ(t.levelCount(), 4);  // 8x4, 4x2, 2x1, 1x1
    EXPECT_EQ(t.width(3), 1);
    EXPECT_EQ(t.height(3), 1);
    EXPECT_EQ(t.texel(1, 1, 0), 0.25f * (t.texel(0, 2, 0) + t.texel(0, 3, 0) + t.texel(0, 2, 1) + t.texel(0, 3, 1)));
    // Trilinear: integer lods are single levels, halfway blends the two.
    const glm::vec2 uv = centre(1, 0, 4, 2);
    EXPECT_EQ(t.sampleTrilinear(uv, 1.0f), t.sampleBilinear(1, uv));
    EXPECT_EQ(t.sampleTrilinear(uv, 0.5f), glm::mix(t.sampleBilinear(0, uv), t.sampleBilinear(1, uv), 0.5f));
    EXPECT_EQ(t.sampleTrilinear(uv, -3.0f), t.sampleBilinear(0, uv));
    EXPECT_EQ(t.levelOfDetail(glm::vec2(1.0f / 8, 0), glm::vec2(0)), 0.0f);
    EXPECT_EQ(t.levelOfDetail(glm::vec2(0), glm::vec2(0, 4.0f / 4)), 2.0f);
}

TEST(Texture, EightBitTexelsDecodeThroughTheTableAndMipInLinear) {
    // Random bytes on odd sides (the last row and column fold into the level below).
    constexpr int kWidth = 13, kHeight = 7;
    std::mt19937 rng(8);
    std::vector<uint8_t> bytes(kWidth * kHeight * 4);
    for (uint8_t& b : bytes) b = uint8_t(rng() & 0xFF);
    for (raster::TexelFormat format : {raster::TexelFormat::Srgb8, raster::TexelFormat::Unorm8}) {
        const bool srgb = format == raster::TexelFormat::Srgb8;
        auto decode = [&](uint8_t b, int channel) {
            return srgb && channel < 3 ? raster::decodeSrgb8(b) : float(b) / 255.0f;
        };
        auto encode = [&](float v, int channel) {
            if (srgb && channel < 3) return raster::encodeSrgb8(v);
            return uint8_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f));
        };
        const Texture t(kWidth, kHeight, bytes, format);
        ASSERT_EQ(t.format(), format);
        // As stored, row-major: the bytes given, R in the low byte.
        const std::vector<uint32_t> rows = t.packedRows(0);
        ASSERT_EQ(rows.size(), size_t(kWidth) * kHeight);
        for (size_t i = 0; i < rows.size(); ++i)
            ASSERT_EQ(rows[i], uint32_t(bytes[4 * i]) | uint32_t(bytes[4 * i + 1]) << 8 | uint32_t(bytes[4 * i + 2]) << 16 |
                                   uint32_t(bytes[4 * i + 3]) << 24)
                << "texel " << i;
        // Level 0: each texel is its bytes through the decode, exactly.
        std::vector<glm::vec4> decoded;
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x) {
                glm::vec4 expected;
                for (int c = 0; c < 4; ++c) expected[c] = decode(bytes[(y * kWidth + x) * 4 + c], c);
                ASSERT_EQ(t.texel(0, x, y), expected) << x << "," << y;
                decoded.push_back(expected);
            }
        // Level 1: the 2x2 average in linear, stored again as bytes of the format.
        ASSERT_EQ(t.width(1), kWidth / 2);
        for (int y = 0; y < t.height(1); ++y)
            for (int x = 0; x < t.width(1); ++x) {
                const glm::vec4 average = 0.25f * (decoded[2 * y * kWidth + 2 * x] + decoded[2 * y * kWidth + 2 * x + 1] +
                                                   decoded[(2 * y + 1) * kWidth + 2 * x] +
                                                   decoded[(2 * y + 1) * kWidth + 2 * x + 1]);
                for (int c = 0; c < 4; ++c)
                    ASSERT_EQ(t.texel(1, x, y)[c], decode(encode(average[c], c), c)) << x << "," << y << " channel " << c;
            }
        ASSERT_EQ(t.width(t.levelCount() - 1), 1);
        // Sampling level 0 is sampling the same values held as floats.
        const Texture asFloat(kWidth, kHeight, decoded);
        for (int i = 0; i < 200; ++i) {
            const glm::vec2 uv(float(rng() % 1000) / 300.0f - 1.0f, float(rng() % 1000) / 300.0f - 1.0f);
            ASSERT_EQ(t.sampleBilinear(0, uv), asFloat.sampleBilinear(0, uv)) << uv.x << "," << uv.y;
        }
    }
}

// glTF's (OpenGL's) filters written out from the per-level samplers, as a reference for the
// texture's own choice of levels and taps.
glm::vec4 filteredReference(const Texture& t, glm::vec2 uv, float lod) {
    const raster::TextureFilter f = t.filter();
    if (!(lod > 0.0f)) return f.magnifyNearest ? t.sampleNearest(0, uv) : t.sampleBilinear(0, uv);
    const int last = t.levelCount() - 1;
    switch (f.minify) {
        case raster::MinFilter::Nearest: return t.sampleNearest(0, uv);
        case raster::MinFilter::Linear: return t.sampleBilinear(0, uv);
        case raster::MinFilter::NearestMipmapNearest:
        case raster::MinFilter::LinearMipmapNearest: {
            const int level = std::min(last, int(std::ceil(std::min(lod, float(last)) + 0.5f)) - 1);
            return f.minify == raster::MinFilter::NearestMipmapNearest ? t.sampleNearest(level, uv) : t.sampleBilinear(level, uv);
        }
        case raster::MinFilter::NearestMipmapLinear: {
            lod = std::min(lod, float(last));
            const int l0 = int(lod), l1 = std::min(l0 + 1, last);
            return glm::mix(t.sampleNearest(l0, uv), t.sampleNearest(l1, uv), lod - float(l0));
        }
        case raster::MinFilter::LinearMipmapLinear: break;
    }
    return t.sampleTrilinear(uv, lod);
}

// The batch sampler (raster/texture_lanes.h for 8-bit texels, one point at a time for float
// ones) against sample() and the per-level reference, bit for bit: every filter, every pair of
// wrap modes, both 8-bit formats, on odd sizes (tiles padded at the right and bottom) and a
// one-texel-wide strip. ctest runs this suite once per instruction set.
TEST(Texture, BatchSamplingIsSampleBitForBitUnderEveryFilter) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> coordinate(-2.5f, 3.5f), level(-2.0f, 9.0f);
    const raster::MinFilter filters[] = {raster::MinFilter::Nearest, raster::MinFilter::Linear,
                                         raster::MinFilter::NearestMipmapNearest, raster::MinFilter::LinearMipmapNearest,
                                         raster::MinFilter::NearestMipmapLinear, raster::MinFilter::LinearMipmapLinear};
    // Scattered points first, then coherent ones as a shade queue holds them: runs of 16 (whole
    // vectors on every instruction set) sharing a level of detail, inside one period of the
    // texture and across its last texel, where Repeat's next texel wraps to the first (the lane
    // sampler reads such runs through its shortcuts). 262 is more than one run of the batch, and
    // not a whole number of vectors.
    constexpr int kScattered = 160, kPoints = 262;
    float u[kPoints], v[kPoints], lod[kPoints];
    for (int i = 0; i < kPoints; ++i) u[i] = coordinate(rng), v[i] = coordinate(rng), lod[i] = level(rng);
    // Edge cases: exact levels, no minification, non-finite coordinates and levels, far tiles.
    lod[0] = 0.0f, lod[1] = 1.0f, lod[2] = 3.0f, lod[3] = NAN, lod[4] = INFINITY, lod[5] = -INFINITY;
    u[6] = NAN, v[7] = INFINITY, u[8] = -1e30f, u[9] = 4097.3f, v[10] = -12345.6f, u[11] = 0.999999f;
    const float runLevels[] = {-1.0f, 0.0f, 0.4f, 1.0f, 2.7f, 5.5f};
    for (int i = kScattered; i < kPoints; ++i) {
        const int run = (i - kScattered) / 16, k = (i - kScattered) % 16;
        lod[i] = runLevels[run % 6];
        const float start = run % 2 ? 0.9f : 0.05f;  // odd runs reach across the last texel
        u[i] = start + 0.006f * float(k), v[i] = 0.3f + 0.0371f * float(k);
    }
    const WrapMode wraps[] = {WrapMode::Repeat, WrapMode::ClampToEdge, WrapMode::MirroredRepeat};
    const raster::TexelFormat formats[] = {raster::TexelFormat::LinearFloat, raster::TexelFormat::Srgb8,
                                           raster::TexelFormat::Unorm8};
    for (const glm::ivec2 size : {glm::ivec2(37, 20), glm::ivec2(1, 9)}) {
        std::vector<uint8_t> bytes(size_t(size.x) * size.y * 4);
        for (uint8_t& b : bytes) b = uint8_t(rng() & 0xFF);
        for (const raster::TexelFormat format : formats)
            for (const WrapMode wrapU : wraps)
                for (const WrapMode wrapV : wraps)
                    for (const bool magnifyNearest : {false, true})
                        for (const raster::MinFilter minify : filters) {
                            Texture t = format == raster::TexelFormat::LinearFloat
                                            ? ramp(size.x, size.y, wrapU, wrapV)
                                            : Texture(size.x, size.y, bytes, format, wrapU, wrapV);
                            t.setFilter({magnifyNearest, minify});
                            float batchChannels[4][kPoints];
                            t.sampleBatch(kPoints, u, v, lod,
                                          {batchChannels[0], batchChannels[1], batchChannels[2], batchChannels[3]});
                            for (int i = 0; i < kPoints; ++i) {
                                const glm::vec4 batch(batchChannels[0][i], batchChannels[1][i], batchChannels[2][i],
                                                      batchChannels[3][i]);
                                const glm::vec4 one = t.sample({u[i], v[i]}, lod[i]);
                                const glm::vec4 reference = filteredReference(t, {u[i], v[i]}, lod[i]);
                                for (int c = 0; c < 4; ++c) {
                                    ASSERT_EQ(std::bit_cast<uint32_t>(batch[c]), std::bit_cast<uint32_t>(one[c]))
                                        << "point " << i << ", size " << size.x << "x" << size.y << ", format "
                                        << int(format) << ", wraps " << int(wrapU) << int(wrapV) << ", filter "
                                        << int(minify) << (magnifyNearest ? " nearest" : "");
                                    ASSERT_EQ(std::bit_cast<uint32_t>(one[c]), std::bit_cast<uint32_t>(reference[c]))
                                        << "point " << i << ", filter " << int(minify) << (magnifyNearest ? " nearest" : "");
                                }
                            }
                        }
    }
}

// A material's textures of one layout share their footprints (SampleFootprints): each texture
// sampled through a shared plan gets exactly its own sample() values, bit for bit, whether the
// plan was made for it, reused from another texture of that layout (other texels, other 8-bit
// format), or made again because the layout changed (another size, other wraps, another filter).
TEST(Texture, SharedFootprintsGiveEachTextureOfTheLayoutItsOwnSamplesBitForBit) {
    std::mt19937 rng(12);
    std::uniform_real_distribution<float> coordinate(-2.5f, 3.5f), level(-2.0f, 9.0f);
    constexpr int kPoints = raster::SampleFootprints::kMaxPoints;
    const auto randomBytes = [&](glm::ivec2 size) {
        std::vector<uint8_t> bytes(size_t(size.x) * size.y * 4);
        for (uint8_t& b : bytes) b = uint8_t(rng() & 0xFF);
        return bytes;
    };
    const glm::ivec2 size(37, 20);
    std::vector<Texture> textures;
    for (const raster::MinFilter minify : {raster::MinFilter::LinearMipmapLinear, raster::MinFilter::NearestMipmapLinear})
        for (const WrapMode wrap : {WrapMode::Repeat, WrapMode::MirroredRepeat}) {
            // Two textures of each layout, one of each 8-bit format, so the second reuses the plan.
            for (const raster::TexelFormat format : {raster::TexelFormat::Srgb8, raster::TexelFormat::Unorm8}) {
                textures.emplace_back(size.x, size.y, randomBytes(size), format, wrap, WrapMode::ClampToEdge);
                textures.back().setFilter({false, minify});
            }
        }
    textures.emplace_back(16, 16, randomBytes({16, 16}), raster::TexelFormat::Unorm8);  // another size
    for (const int count : {kPoints, 37}) {  // whole vectors, and a tail
        float u[kPoints], v[kPoints], lod[kPoints];
        for (int i = 0; i < count; ++i) u[i] = coordinate(rng), v[i] = coordinate(rng), lod[i] = level(rng);
        raster::SampleFootprints shared;
        int reused = 0;
        for (const Texture& t : textures) {
            const bool samePlan = shared.layout.width == t.width() && shared.layout.wrapU == t.wrapU() &&
                                  shared.layout.filter.minify == t.filter().minify;
            reused += samePlan;
            float channels[4][kPoints];
            t.sampleBatch(count, u, v, lod, {channels[0], channels[1], channels[2], channels[3]}, shared);
            EXPECT_EQ(shared.layout.width, t.width());
            for (int i = 0; i < count; ++i) {
                const glm::vec4 one = t.sample({u[i], v[i]}, lod[i]);
                for (int c = 0; c < 4; ++c)
                    ASSERT_EQ(std::bit_cast<uint32_t>(channels[c][i]), std::bit_cast<uint32_t>(one[c]))
                        << "point " << i << " of " << count << ", texture " << (&t - textures.data());
            }
        }
        EXPECT_EQ(reused, 4) << "the second texture of each of the four layouts reuses the first's plan";
    }
}

TEST(TexturedDraw, OneTexelPerPixelReproducesTheTexture) {
    constexpr int kSize = 32;
    const Texture t = ramp(kSize, kSize, WrapMode::ClampToEdge, WrapMode::ClampToEdge);
    std::vector<glm::vec3> positions = {{0, 0, 0.5f}, {0, kSize, 0.5f}, {kSize, kSize, 0.5f},
                                        {0, 0, 0.5f}, {kSize, kSize, 0.5f}, {kSize, 0, 0.5f}};
    std::vector<glm::vec2> uvs = {{0, 0}, {0, 1}, {1, 1}, {0, 0}, {1, 1}, {1, 0}};
    std::vector<glm::vec3> normals(6, glm::vec3(0, 0, 1));
    raster::DrawCall d;
    d.space = raster::PositionSpace::Window;
    d.positions = positions;
    d.normals = normals;
    d.texCoords = uvs;
    d.state.shading = raster::ShadingModel::Lambert;
    d.state.lighting = raster::Lighting::directional(glm::vec3(0, 0, 1), glm::vec3(1), glm::vec3(0));
    d.state.textures.baseColor.texture = &t;
    raster::Pipeline p;
    p.beginFrame(frame(kSize, kSize, 1));
    p.draw(d);
    p.endFrame();
    raster::Image img;
    raster::resolveColor(p.framebuffer(), img);
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x)
            for (int c = 0; c < 3; ++c)
                ASSERT_NEAR(img.pixel(x, y)[c], t.texel(0, x, y)[c], 1e-4f) << x << "," << y;
}

}  // namespace
}  // namespace cuberille::testing
