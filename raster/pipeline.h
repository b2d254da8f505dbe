#pragma once
// The software GPU, front to back:
//
//   vertex → clip → setup → bin  (front end, parallel over fixed batches of triangles)
//   coarse → fine → depth → shade → output merge  (back end, parallel over 64x64 tiles)
//   resolve  (parallel over tile rows)
//
// Usage: beginFrame(desc); draw(...) any number of times; endFrame(); then read the
// framebuffer through resolve.h. Like a GPU command buffer, draw() records: the arrays a
// DrawCall points to must stay valid until the next flush() or endFrame() returns. Work runs in
// flushes: once kBatchesPerFlush batches are queued (and at flush() and endFrame), the vertex
// stage shades every draw not yet shaded, the front end sets up and bins all queued batches of
// all draws in one parallel pass, and the back end drains them tile by tile. So many small
// draws still keep every core busy, and memory for binned triangles stays bounded whatever the
// scene size. A flushed draw's vertex-stage storage is recycled for later draws, so a frame's
// memory is bounded by what one flush holds, not by how many triangles the frame draws. Where
// a flush falls never changes the image: batches are cut per draw and every tile consumes them
// in submission order either way.
//
// Determinism: batch boundaries depend on triangle counts only; every tile consumes batches
// in order; counters are integer sums. The image is the same for every thread count.
// Thread-safety: one frame at a time per Pipeline; the calls themselves are not re-entrant.

#include <span>
#include <vector>

#include "raster/bin.h"
#include "raster/draw.h"
#include "raster/framebuffer.h"
#include "raster/stats.h"
#include "raster/tile_raster.h"
#include "raster/vertex.h"
#include "raster/visibility_shade.h"

namespace cuberille::raster {

class Pipeline {
public:
    void beginFrame(const FramebufferDesc& desc);
    void draw(const DrawCall& draw);
    /// Runs every recorded draw through the pipeline now; then the caller may reuse their arrays
    /// (a producer of geometry, such as voxel-face expansion, draws through bounded scratch).
    void flush();
    /// Runs what is recorded (flush()), then sets every touched tile's hierarchical Z to the exact
    /// maximum of its stored depths (Framebuffer::tightenHierarchicalDepth), in parallel over
    /// tiles. The image does not change; later draws' hidden 8x8 blocks are rejected sooner, and
    /// a producer of geometry can read the bounds (Framebuffer::farthestDepthKeyOfBlock) to leave
    /// out what lies behind them before it becomes triangles.
    void flushAndTightenHierarchicalDepth();
    void endFrame();

    /// A deferred frame: draw() records the draws without rasterizing them, and visibility is
    /// found elsewhere (the camera rays of the ray-tracing renderer) and handed to shadeVisible(),
    /// which runs the vertex, set-up and shade stages for what it names
    /// (raster/visibility_shade.h). Draws after it run forward over the shaded frame, tested
    /// against the depths it wrote (a deferred renderer's transparent pass). Then endFrame().
    void beginDeferredFrame(const FramebufferDesc& desc);
    /// The draws recorded since beginDeferredFrame, in order: what a visibility buffer indexes.
    std::span<const DrawCall> recordedDraws() const { return draws_; }
    /// `lighting`, when given, replaces the lighting of the draws the buffer names: what a
    /// deferred frame learns between finding visibility and shading it (the shadow stage's masks,
    /// found for the surfaces the buffer holds). Draws after shadeVisible keep their own.
    VisibilityShadeStats shadeVisible(const VisibilityBuffer& seen, const Lighting* lighting = nullptr);

    const Framebuffer& framebuffer() const { return framebuffer_; }
    const PipelineStats& stats() const { return stats_; }

private:
    /// A queued batch: kTrianglesPerBatch triangles of one draw from firstTriangle on.
    struct BatchRef {
        uint32_t draw;
        size_t firstTriangle;
    };

    void shadeVertices();
    void frontEnd(const BatchRef& ref, TriangleBatch& batch) const;
    void recycleFinishedVertexOutputs();

    Framebuffer framebuffer_;
    PipelineStats stats_;
    std::vector<DrawCall> draws_;
    std::vector<VertexStageOutput> vertexOutputs_;  // per draw; emptied once the draw is flushed
    std::vector<VertexStageOutput> spareVertexOutputs_;  // flushed draws' storage, for later draws
    size_t spareVertexBytes_ = 0;  // their capacity, at most kSpareVertexStorageBytes
    size_t drawsShaded_ = 0;
    size_t drawsRecycled_ = 0;  // draws below this one have given their vertex storage back
    bool deferred_ = false;  // beginDeferredFrame: draws are recorded only
    bool drawInProgress_ = false;  // draw() is queueing; its draw may have batches still to come
    std::vector<BatchRef> queued_;
    std::vector<TriangleBatch> batches_;  // reused across flushes and frames
    std::vector<TileCounters> tileCounters_;
    std::vector<uint8_t> tilesDrawnSinceTightened_;  // per tile: a batch reached it since flushAndTighten...()
    double frameStartMs_ = 0;
    // shadeVisible's tables and vertex outputs, made by the first deferred frame, reused by the next.
    std::unique_ptr<VisibilityShadeStorage, void (*)(VisibilityShadeStorage*)> visibilityShade_{nullptr, nullptr};
};

}  // namespace cuberille::raster
