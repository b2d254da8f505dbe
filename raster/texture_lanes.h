#pragma once
// Texture fetches in vector lanes: raster/texture.h's trilinear filter for many points at once,
// the way a GPU's texture unit serves a warp.
//
// A shade queue asks for one filtered texel per pixel, up to 64 pixels at a time, for each
// texture a material binds (five on DamagedHelmet). One point at a time, that is a footprint,
// two wraps and eight texel decodes in scalar code per point, and it was 61% of a DamagedHelmet
// frame at one sample. Here each lane is a point: level of detail to levels and weight, texel
// space, wrap modes, tiled addresses (Texture's 4x4 tiles) and the blends are lane arithmetic;
// the eight texels and the sRGB decode table are gathers.
//
// The same bits as Texture::sample(), on every instruction set: the same IEEE operations in the
// same order (no contraction), and the integer steps done exactly in float — texel coordinates
// are integers below 2^24 there (texture space is clamped to +-1e6 first), so floor, the wrap's
// modulo (a quotient corrected by one period either way) and the products are exact.
// Texture.BatchSamplingIsSampleBitForBitUnderEveryFilter checks it (ctest runs it per set).
//
// Every filter of glTF's samplers runs here (a nearest tap is a bilinear one with zero weights:
// t00 (1 - 0) + t10 0 is t00 exactly for the finite texels of an 8-bit format); float texels go
// to the one-point sampler, since only procedural textures and 16-bit images have them.

#include <cstddef>
#include <cstdint>

#include <glm/glm.hpp>

#include "raster/texture.h"

namespace cuberille::raster {

/// What the lane sampler reads of a texture: the tiled 8-bit storage, the sRGB decode table and,
/// per level, its size and place (Texture's layout).
struct TexelPyramid {
    const uint32_t* packed;
    bool srgb;                // TexelFormat::Srgb8: RGB through decodeRgb; else every byte is b / 255
    const float* decodeRgb;   // 256 entries
    int levelCount;
    WrapMode wrapU, wrapV;
    TextureFilter filter;
    const int32_t* width;          // [levelCount] each
    const int32_t* height;
    const int32_t* offset;         // first texel of the level in `packed`
    const int32_t* tileRowStride;  // texels per row of 4x4 tiles
    bool prefetch;  // footprints' lines asked for before they are gathered (kPrefetchTextureBytes)
};

/// Textures of at least this many bytes of 8-bit texels (all levels) have their footprints'
/// cache lines prefetched before a batch is gathered. Such a texture is read from beyond the
/// core's caches every frame, and its misses are what a fetch waits for; a smaller one stays
/// cached between frames and the prefetches are only instructions. Measured (raster_bench
/// --no-peer --threads 1, 1920x1080, 1 sample, AVX-512, alternating runs): DamagedHelmet (five
/// 2048x2048 maps, 21 MiB each) back end 40 -> 34.5 ms with them; CesiumMan (one 1024x1024 map,
/// 5.3 MiB) 7.8 -> 8.5 ms with them, so it goes without.
inline constexpr size_t kPrefetchTextureBytes = size_t(16) << 20;

/// Channel values at i = the filtered sample at (u[i], v[i]) with level of detail lod[i] under
/// the texture's filters: Texture::sample(), bit for bit.
void sampleLanes(const TexelPyramid& texture, int count, const float* u, const float* v, const float* lod,
                 Texture::Channels out);

/// sampleLanes in two halves, for textures that share a layout (SampleFootprints): plan the
/// footprints of `count` (at most SampleFootprints::kMaxPoints) points on `layout`'s levels, wraps
/// and filter; then gather and filter any such texture's texels at them. The same bits as
/// sampleLanes: the same operations, their intermediate values kept in memory in between.
void planSampleFootprints(const TexelPyramid& layout, int count, const float* u, const float* v, const float* lod,
                          SampleFootprints& out);
void sampleFootprints(const TexelPyramid& texture, const SampleFootprints& footprints, Texture::Channels out);

}  // namespace cuberille::raster
