#pragma once
// Triangle set-up in vector lanes: raster/setup.h's set-up for a chunk of triangles at once.
//
// In a dense mesh most triangles never reach the back end: they fall between sample positions,
// and in a culled mesh half of them face away (the Stanford dragon at 1920x1080 with one sample,
// drawn double-sided as scans are: of 871k triangles 490k cover no sample and 379k are set up).
// Set-up one triangle at a time spent a third of that frame on branches. Here a chunk of triangles that no clip plane
// cuts comes in as structure-of-arrays lanes, and every lane gets, by loops the compiler
// vectorises, both what setupTriangle() would decide and what it would compute:
//
//   verdict   Degenerate (zero doubled area from the snapped vertices), Culled (facing),
//             NoSamples (pixel bounds empty after the scissor, or bounds of at most
//             kSetupCoverageTestPixels pixels whose samples its edges all miss), else Accepted;
//   record    for an accepted lane, its TriangleSetup and vertex order (setupRecord()).
//
// The same bits as setupTriangle(): the integer part (area, bounds, edges, coverage) is done
// in double, where every value is an integer below 2^53 (snapped coordinates < 2^24 subpixels,
// edge coefficients < 2^25, products < 2^50, edge values < 2^51: raster/limits.h), so no
// operation rounds; the depth plane is the same double operations in the same order, without
// contraction (the build has -ffp-contract=off), which IEEE arithmetic rounds alike in a lane
// and in a scalar register. SetupLanes.VerdictsAndRecordsAreSetupsOnRandomAndHardTriangles
// checks both on every instruction set. Compiled once per instruction set like the back end
// (raster/instruction_set.h).

#include <cstdint>

#include "raster/setup.h"

namespace cuberille::raster {

/// Triangles per chunk: its lanes (about 60 values a triangle) stay in the first-level cache.
inline constexpr int kSetupChunkTriangles = 128;

/// Window-space vertices of up to kSetupChunkTriangles triangles as submitted, lane i =
/// triangle i.
struct TriangleLanes {
    int32_t x[3][kSetupChunkTriangles];  // subpixels
    int32_t y[3][kSetupChunkTriangles];
    float z[3][kSetupChunkTriangles];
    float invW[3][kSetupChunkTriangles];
};

/// Set-up of every lane, structure of arrays.
struct SetupLanes {
    SetupResult verdict[kSetupChunkTriangles];
    int32_t frontFacing[kSetupChunkTriangles];  // 1: counter-clockwise on screen; v1 and v2 swap
    int32_t pixelMinX[kSetupChunkTriangles], pixelMinY[kSetupChunkTriangles];
    int32_t pixelMaxX[kSetupChunkTriangles], pixelMaxY[kSetupChunkTriangles];
    int32_t edgeA[3][kSetupChunkTriangles], edgeB[3][kSetupChunkTriangles];
    double edgeC[3][kSetupChunkTriangles];  // an exact integer, fill-rule bias included
    int32_t fillBias[3][kSetupChunkTriangles];
    double invDoubleArea[kSetupChunkTriangles];
    float depthPerSubpixelX[kSetupChunkTriangles], depthPerSubpixelY[kSetupChunkTriangles];
};

/// Sets up lanes [0, count).
void setUpLanes(const TriangleLanes& in, int count, const SetupContext& context, SetupLanes& out);

/// Lane i's TriangleSetup and vertex order, as setupTriangle() gives them for an accepted
/// triangle.
void setupRecord(const TriangleLanes& in, const SetupLanes& lanes, int i, const SetupContext& context,
                 TriangleSetup& t, int order[3]);

}  // namespace cuberille::raster
