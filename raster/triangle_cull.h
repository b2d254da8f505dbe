#pragma once
// Triangle cull: the set-up's rejections decided for many triangles at once, in vector lanes.
//
// In a dense mesh most triangles never reach the back end: half face away, and of the rest
// most fall between sample positions (the Stanford dragon at 1920x1080 with one sample: 871k
// triangles, 436k back-facing, 282k covering no sample, 153k drawn). Set-up rejected them one at
// a time through the same branches as a triangle it keeps, a third of the frame on the dragon.
// This stage takes a chunk of window-space triangles as structure-of-arrays lanes and gives
// each the verdict setupTriangle() would give, in the same order of checks:
//
//   Degenerate  zero doubled area from the snapped vertices;
//   Culled      facing culled;
//   NoSamples   pixel bounds empty after the scissor, or bounds of at most
//               kSetupCoverageTestPixels pixels whose samples its edges all miss;
//   MaySurvive  anything else: set-up proper decides (it may still reject).
//
// Exact: the arithmetic is in double, where every value here is an integer below 2^53 (snapped
// coordinates < 2^24 subpixels, edge coefficients < 2^25, products < 2^50, edge values
// < 2^51, raster/limits.h), so no operation rounds and the verdict is setupTriangle()'s bit for
// bit, on every instruction set (TriangleCull.VerdictsAreSetupsOnRandomAndHardTriangles).
// Compiled once per instruction set like the back end (raster/instruction_set.h).

#include <cstdint>

#include "raster/setup.h"

namespace cuberille::raster {

enum class CullVerdict : uint8_t { MaySurvive, Degenerate, Culled, NoSamples };

/// Triangles per call: a chunk's lanes (13 doubles or ints a triangle) stay in the first-level
/// cache.
inline constexpr int kCullChunkTriangles = 128;

/// Snapped window-space vertices of up to kCullChunkTriangles triangles, lane i = triangle i.
struct TriangleLanes {
    int32_t x[3][kCullChunkTriangles];  // subpixels
    int32_t y[3][kCullChunkTriangles];
};

/// verdicts[i] for lanes [0, count): what setupTriangle() would decide before its depth plane.
void cullTriangles(const TriangleLanes& lanes, int count, const SetupContext& context, CullVerdict* verdicts);

}  // namespace cuberille::raster
