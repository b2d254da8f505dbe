#pragma once
// The software GPU, front to back:
//
//   vertex → clip → setup → bin  (front end, parallel over fixed batches of triangles)
//   coarse → fine → depth → shade → output merge  (back end, parallel over 64x64 tiles)
//   resolve  (parallel over tile rows)
//
// Usage: beginFrame(desc); draw(...) any number of times; endFrame(); then read the
// framebuffer through resolve.h. Draws are executed in submission order per tile; the front end
// works ahead by at most kBatchesPerFlush batches, then the back end drains them (a "flush"),
// so memory for binned triangles stays bounded whatever the scene size.
//
// Determinism: batch boundaries depend on triangle counts only; every tile consumes batches
// in order; counters are integer sums. The image is the same for every thread count.
// Thread-safety: one frame at a time per Pipeline; the calls themselves are not re-entrant.

#include <vector>

#include "raster/bin.h"
#include "raster/draw.h"
#include "raster/framebuffer.h"
#include "raster/stats.h"
#include "raster/tile_raster.h"
#include "raster/vertex.h"

namespace cuberille::raster {

class Pipeline {
public:
    void beginFrame(const FramebufferDesc& desc);
    void draw(const DrawCall& draw);
    void endFrame();

    const Framebuffer& framebuffer() const { return framebuffer_; }
    const PipelineStats& stats() const { return stats_; }

private:
    void frontEnd(const DrawCall& draw, int drawIndex, size_t firstTriangle, TriangleBatch& batch);
    void flush();

    Framebuffer framebuffer_;
    PipelineStats stats_;
    std::vector<DrawState> draws_;
    VertexStageOutput vertexOutput_;
    std::vector<TriangleBatch> batches_;  // reused across flushes and frames
    size_t pendingBatches_ = 0;
    std::vector<TileCounters> tileCounters_;
    double frameStartMs_ = 0;
};

}  // namespace cuberille::raster
