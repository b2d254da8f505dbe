#pragma once
// The back end for one tile: for each binned triangle, coarse → fine → depth → shade →
// output merge, writing into the tile's samples.
//
// One task owns one tile for the whole flush, so nothing here is shared between threads; the
// per-tile counters are summed afterwards.

#include <cstdint>
#include <vector>

#include "raster/bin.h"
#include "raster/draw.h"
#include "raster/framebuffer.h"
#include "raster/sample_pattern.h"
#include "raster/stats.h"

namespace cuberille::raster {

struct TileCounters {
    StageCounters counters;
    std::vector<uint64_t> occlusionSamplesPassed;  // per slot
};

/// Rasterizes the batch's triangles binned to `tile`, in order.
void rasterizeBatchInTile(const TriangleBatch& batch, const DrawState& state, int tile,
                          Framebuffer& framebuffer, TileCounters& out);

}  // namespace cuberille::raster
