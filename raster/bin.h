#pragma once
// Bin stage: sort a batch's set-up triangles into per-tile lists (64x64 pixel tiles).
//
// Each batch bins into its own lists, as a counting sort (count per tile, prefix sum, fill),
// so batches bin in parallel without sharing anything; the back end then walks, for its tile,
// the batches in submission order and each batch's list in triangle order. That is the whole
// determinism argument for the middle of the pipeline.
//
// A triangle whose bounds span several tiles is entered only in tiles the coarse test cannot
// prove empty (thin diagonal triangles do not flood their bounding box's tiles).

#include <cstdint>
#include <vector>

#include "raster/sample_pattern.h"
#include "raster/setup.h"
#include "raster/stats.h"
#include "raster/uninitialized_allocator.h"
#include "raster/vertex.h"

namespace cuberille::raster {

struct TileGrid {
    int tilesX = 0, tilesY = 0;
    int tileCount() const { return tilesX * tilesY; }
};

/// One fixed-size run of a draw's triangles, after set-up and binning.
struct TriangleBatch {
    int drawIndex = 0;
    VaryingLayout layout;  // the draw's: layout.count floats per vertex in `varyings`
    // Grown a triangle at a time and written in place by set-up (raster/pipeline.cpp), so sized
    // without first writing zeros (raster/uninitialized_allocator.h).
    UninitializedVector<TriangleSetup> triangles;
    UninitializedVector<float> varyings;
    std::vector<uint32_t> tileOffsets;    // tileCount + 1 entries
    std::vector<uint32_t> tileTriangles;  // triangle indices, grouped by tile
    StageCounters counters;

    void clear() {
        triangles.clear();
        varyings.clear();
        tileOffsets.clear();
        tileTriangles.clear();
        counters = {};
    }
};

void binTriangles(TriangleBatch& batch, const TileGrid& grid, const SamplePattern& samples);

}  // namespace cuberille::raster
