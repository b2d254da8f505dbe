#pragma once
// Limits of the software GPU, and the arithmetic argument that makes exact integer
// rasterization safe inside them.
//
// Window coordinates. After clipping against the guard band a vertex lies in
//   [-kGuardBandPixels, kMaxFramebufferPixels + kGuardBandPixels]  ⊂  (-2^16, 2^16) pixels,
// so a snapped coordinate fits in (-2^24, 2^24) subpixels (8 fractional bits).
//
// Edge functions. For an edge from vertex i to vertex j
//   E(X, Y) = A·X + B·Y + C,   A = Yi - Yj,   B = Xj - Xi,   C = -(A·Xi + B·Yi)
// with |A|, |B| < 2^25 (int32) and |C| < 2^50. Sample positions lie inside the framebuffer,
// |X|, |Y| < 2^22 subpixels, so |A·X + B·Y| < 2^48 and |E| < 2^51: every edge value, and every
// sum of edge value and per-sample offset, fits in int64 with room to spare. The products are
// formed in int64 (never in int32), which is the one rule the code must keep.

#include <cstddef>
#include <cstdint>

namespace cuberille::raster {

inline constexpr int kSubpixelBits = 8;
inline constexpr int kSubpixelsPerPixel = 1 << kSubpixelBits;
inline constexpr int kPixelCentreSubpixels = kSubpixelsPerPixel / 2;
/// Standard sample offsets are given in 1/16 pixel; one unit is this many subpixels.
inline constexpr int kSampleOffsetUnitSubpixels = kSubpixelsPerPixel / 16;

inline constexpr int kTileSizePixels = 64;   // binning granularity
inline constexpr int kBlockSizePixels = 8;   // coarse-stage granularity
inline constexpr int kBlocksPerTileSide = kTileSizePixels / kBlockSizePixels;
inline constexpr int kPixelsPerTile = kTileSizePixels * kTileSizePixels;
inline constexpr int kBlocksPerTile = kBlocksPerTileSide * kBlocksPerTileSide;

inline constexpr int kMaxFramebufferPixels = 16384;  // per side
inline constexpr int kGuardBandPixels = 32768;       // beyond each side of the viewport
inline constexpr int kMaxSamples = 16;
inline constexpr int kMaxVaryings = 16;  // floats interpolated per vertex

/// Triangles per front-end batch. Batch boundaries depend on the submission alone, never on
/// the thread count, which is what makes binning deterministic (DESIGN.md, determinism).
inline constexpr int kTrianglesPerBatch = 4096;
/// Batches binned before the back end drains them; bounds the memory of binned triangles.
inline constexpr int kBatchesPerFlush = 64;
/// Vertex-stage storage of flushed draws kept for later draws of the frame and of later frames;
/// what is returned past it is freed. A frame's vertex memory is then this plus what one flush
/// holds, whatever the number of draws or triangles (docs/streaming.md, memory).
inline constexpr size_t kSpareVertexStorageBytes = size_t(64) << 20;

static_assert(kTileSizePixels % kBlockSizePixels == 0);
static_assert(kSubpixelsPerPixel % 16 == 0, "sample offsets in 1/16 pixel must be exact in subpixels");
static_assert((int64_t{kMaxFramebufferPixels} + kGuardBandPixels) * kSubpixelsPerPixel < (int64_t{1} << 24),
              "snapped window coordinates must stay below 2^24 subpixels");
static_assert(int64_t{kMaxFramebufferPixels} * kSubpixelsPerPixel <= (int64_t{1} << 22),
              "sample positions must stay below 2^22 subpixels");
static_assert(kMaxSamples <= 32, "coverage masks are 32-bit");

}  // namespace cuberille::raster
