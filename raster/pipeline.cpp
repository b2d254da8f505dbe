#include "raster/pipeline.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "raster/clock.h"
#include "raster/clip.h"
#include "raster/parallel.h"
#include "raster/setup.h"
#include "raster/setup_lanes.h"

namespace cuberille::raster {
namespace {

struct TriangleInput {
    const VertexStageOutput& vertices;
    ClipVolume volume;
    SetupContext setup;
};

ClipVolume clipVolumeFor(const DrawCall& draw, const Framebuffer& fb) {
    return draw.space == PositionSpace::Window ? ClipVolume::forWindowSpace(fb.width(), fb.height())
                                               : ClipVolume::forViewport(fb.width(), fb.height());
}

SetupContext setupContextFor(const DrawCall& draw, const Framebuffer& fb, const VaryingLayout& layout) {
    SetupContext c = SetupContext::forDraw(draw.space, fb.width(), fb.height(), standardSamplePattern(fb.samples()),
                                           draw.state.cull, layout.count);
    c.depthKeySign = depthKeySign(fb.desc().depthConvention);
    return c;
}

/// Completes the batch's newest triangle record `t`, written in place by set-up: its vertices'
/// varyings in set-up's vertex order, and its flat colour.
void completeTriangle(TriangleSetup& t, const int (&order)[3], const float* const (&varyings)[3], const glm::vec4& color,
                      TriangleBatch& batch) {
    const int count = batch.layout.count;
    const size_t at = batch.varyings.size();
    batch.varyings.resize(at + size_t(3 * count));
    float* out = batch.varyings.data() + at;
    for (int v = 0; v < 3; ++v)
        for (int i = 0; i < count; ++i) out[v * count + i] = varyings[order[v]][i];
    t.varyingOffset = uint32_t(at);
    t.flatColor = color;
    ++batch.counters.trianglesSetUp;
}

// An accepted triangle into the batch: its set-up and its vertices' varyings in set-up order.
void appendTriangle(const TriangleSetup& setup, const int (&order)[3], const float* const (&varyings)[3],
                    const glm::vec4& color, TriangleBatch& batch) {
    completeTriangle(batch.triangles.emplace_back(setup), order, varyings, color, batch);
}

void countRejection(SetupResult result, StageCounters& k) {
    switch (result) {
        case SetupResult::Accepted: return;
        case SetupResult::Degenerate: ++k.trianglesDegenerate; return;
        case SetupResult::Culled: ++k.trianglesCulled; return;
        case SetupResult::NoSamples: ++k.trianglesNoSamples; return;
    }
}

// Set-up of one clipped triangle into the batch, counting the outcome.
void setupInto(const TriangleInput& in, const WindowVertex (&w)[3], const float* const (&varyings)[3],
               const glm::vec4& color, TriangleBatch& batch) {
    TriangleSetup t;
    int order[3];
    const SetupResult result = setupTriangle(w[0], w[1], w[2], in.setup, t, order);
    if (result == SetupResult::Accepted)
        appendTriangle(t, order, varyings, color, batch);
    else
        countRejection(result, batch.counters);
}

// A triangle that crosses a clip plane: clip in homogeneous space, then set up the fan.
void clipAndSetup(const TriangleInput& in, const size_t (&index)[3], uint32_t planes,
                  const glm::vec4& color, TriangleBatch& batch) {
    StageCounters& k = batch.counters;
    ++k.trianglesClipped;
    const bool projected = clipAndProjectFan(in.vertices, in.volume, in.setup, index, planes,
                                             [&](const WindowVertex (&w)[3], const float* const (&v)[3]) {
                                                 ++k.clippedTrianglesOut;
                                                 setupInto(in, w, v, color, batch);
                                             });
    if (!projected) ++k.trianglesInvalid;
}

// One chunk of triangles, in submission order: assembly (indices, outcodes), set-up in lanes for
// the triangles no clip plane cuts (raster/setup_lanes.h), then into the batch in order, with
// clipping for those that cross a plane.
void assembleAndSetUp(const DrawCall& call, const TriangleInput& in, size_t first, int count,
                      TriangleBatch& batch) {
    const VertexStageOutput& vertices = in.vertices;
    const size_t vertexCount = vertices.clipPositions.size();
    size_t index[kSetupChunkTriangles][3];
    uint8_t codes[kSetupChunkTriangles];  // the corners' outcodes or'ed, kInvalidVertex for a bad index
    TriangleLanes lanes{};  // lanes past `count` are never read; zeroed so no compiler doubts it
    for (int j = 0; j < count; ++j) {
        const size_t tri = first + size_t(j);
        uint8_t code = 0;
        for (int i = 0; i < 3; ++i) {
            const size_t v = call.indices.empty() ? tri * 3 + i : call.indices[tri * 3 + i];
            index[j][i] = v;
            code |= v < vertexCount ? vertices.outcodes[v] : kInvalidVertex;
        }
        codes[j] = code;
        if (code != 0) continue;
        for (int i = 0; i < 3; ++i) {
            const WindowVertex& w = vertices.window[index[j][i]];
            lanes.x[i][j] = w.x, lanes.y[i][j] = w.y, lanes.z[i][j] = w.z, lanes.invW[i][j] = w.invW;
        }
    }
    SetupLanes setup;
    setUpLanes(lanes, count, in.setup, setup);

    StageCounters& k = batch.counters;
    const float* varyingBase = vertices.varyings.data();
    const int varyingCount = batch.layout.count;
    // The accepted triangles' varyings are read by vertex index, scattered over the vertex
    // stage's output: asking for all of them before copying any lets the cache misses overlap
    // (they were most of the copy's time on the dragon).
    if (varyingCount > 0)
        for (int j = 0; j < count; ++j)
            if (codes[j] == 0 && setup.verdict[j] == SetupResult::Accepted)
                for (int i = 0; i < 3; ++i) __builtin_prefetch(varyingBase + index[j][i] * varyingCount);
    for (int j = 0; j < count; ++j) {
        const size_t tri = first + size_t(j);
        ++k.trianglesIn;
        if (codes[j] & kInvalidVertex) {
            ++k.trianglesInvalid;
            continue;
        }
        const size_t (&corner)[3] = index[j];
        if (codes[j] == 0 && setup.verdict[j] != SetupResult::Accepted) {
            countRejection(setup.verdict[j], k);
            continue;
        }
        const glm::vec4 color =
            call.triangleColors.size() > tri ? call.triangleColors[tri] : call.state.constantColor;
        if (codes[j] == 0) {
            // The record is written once, where the back end will read it.
            TriangleSetup& t = batch.triangles.emplace_back();
            int order[3];
            setupRecord(lanes, setup, j, in.setup, t, order);
            const float* const v[3] = {varyingBase + corner[0] * varyingCount, varyingBase + corner[1] * varyingCount,
                                       varyingBase + corner[2] * varyingCount};
            completeTriangle(t, order, v, color, batch);
            continue;
        }
        const uint8_t* outcodes = vertices.outcodes.data();
        if (classifyTriangle(outcodes[corner[0]], outcodes[corner[1]], outcodes[corner[2]]) == ClipOutcome::Rejected)
            ++k.trianglesClipRejected;
        else
            clipAndSetup(in, corner, codes[j], color, batch);
    }
}

}  // namespace

void Pipeline::beginFrame(const FramebufferDesc& desc) {
    frameStartMs_ = nowMs();
    deferred_ = false;
    framebuffer_.reset(desc);
    stats_ = {};
    drawInProgress_ = false;  // an earlier frame may have ended by an exception, mid-draw
    recycleFinishedVertexOutputs();
    draws_.clear();
    drawsShaded_ = 0;
    drawsRecycled_ = 0;
    queued_.clear();
    tileCounters_.assign(framebuffer_.tileCount(), {});
    tilesDrawnSinceTightened_.assign(size_t(framebuffer_.tileCount()), 0);
}

void Pipeline::beginDeferredFrame(const FramebufferDesc& desc) {
    beginFrame(desc);
    deferred_ = true;
}

VisibilityShadeStats Pipeline::shadeVisible(const VisibilityBuffer& seen, const Lighting* lighting) {
    if (!deferred_) throw std::logic_error("shadeVisible: not a deferred frame (beginDeferredFrame)");
    if (lighting)
        for (DrawCall& d : draws_) d.state.lighting = *lighting;
    if (!visibilityShade_) visibilityShade_ = makeVisibilityShadeStorage();
    const VisibilityShadeStats s = shadeVisibility(draws_, seen, framebuffer_, stats_.counters, *visibilityShade_);
    stats_.times.vertexMs += s.vertexMs;
    stats_.times.frontEndMs += s.setupMs;
    stats_.times.backEndMs += s.shadeMs;
    // Later draws run forward, over what was shaded; the recorded ones are finished.
    deferred_ = false;
    drawsShaded_ = drawsRecycled_ = draws_.size();
    return s;
}

void Pipeline::draw(const DrawCall& call) {
    if (call.state.colorWriteMask != 0 && !framebuffer_.hasColor())
        throw std::invalid_argument("a draw with colour writes into a depth-only framebuffer");
    if (deferred_) {
        draws_.push_back(call);
        return;
    }
    const uint32_t drawIndex = uint32_t(draws_.size());
    draws_.push_back(call);
    const size_t triangles = call.triangleCount();
    drawInProgress_ = true;
    for (size_t first = 0; first < triangles; first += kTrianglesPerBatch) {
        queued_.push_back({drawIndex, first});
        if (queued_.size() == kBatchesPerFlush) flush();
    }
    drawInProgress_ = false;
}

void Pipeline::endFrame() {
    flush();
    for (const TileCounters& t : tileCounters_) {
        stats_.counters += t.counters;
        if (stats_.occlusionSamplesPassed.size() < t.occlusionSamplesPassed.size())
            stats_.occlusionSamplesPassed.resize(t.occlusionSamplesPassed.size(), 0);
        for (size_t i = 0; i < t.occlusionSamplesPassed.size(); ++i)
            stats_.occlusionSamplesPassed[i] += t.occlusionSamplesPassed[i];
    }
    stats_.times.frameMs = nowMs() - frameStartMs_;
}

// Vertex stage for every draw recorded since the last flush, in one parallel pass over
// fixed vertex ranges of all of them.
void Pipeline::shadeVertices() {
    if (vertexOutputs_.size() < draws_.size()) vertexOutputs_.resize(draws_.size());
    std::vector<std::pair<uint32_t, size_t>> tasks;  // (draw, first vertex)
    for (size_t d = drawsShaded_; d < draws_.size(); ++d) {
        const DrawCall& call = draws_[d];
        if (!spareVertexOutputs_.empty()) {
            spareVertexBytes_ -= spareVertexOutputs_.back().capacityBytes();
            vertexOutputs_[d] = std::move(spareVertexOutputs_.back());
            spareVertexOutputs_.pop_back();
        }
        vertexOutputs_[d].resize(call.positions.size(), varyingLayoutFor(call));
        stats_.counters.verticesShaded += call.positions.size();
        for (size_t v = 0; v < call.positions.size(); v += kVerticesPerTask)
            tasks.emplace_back(uint32_t(d), v);
    }
    parallelFor(tasks.size(), [&](size_t i) {
        const auto [d, first] = tasks[i];
        const DrawCall& call = draws_[d];
        runVertexStage(call, clipVolumeFor(call, framebuffer_),
                       setupContextFor(call, framebuffer_, vertexOutputs_[d].layout), first, std::min(call.positions.size(), first + kVerticesPerTask),
                       vertexOutputs_[d]);
    });
    drawsShaded_ = draws_.size();
}

void Pipeline::frontEnd(const BatchRef& ref, TriangleBatch& batch) const {
    const DrawCall& call = draws_[ref.draw];
    const VertexStageOutput& vertices = vertexOutputs_[ref.draw];
    batch.clear();
    batch.drawIndex = int(ref.draw);
    batch.layout = vertices.layout;
    const TriangleInput in{vertices, clipVolumeFor(call, framebuffer_),
                           setupContextFor(call, framebuffer_, vertices.layout)};
    const size_t end = std::min(call.triangleCount(), ref.firstTriangle + kTrianglesPerBatch);
    for (size_t first = ref.firstTriangle; first < end; first += kSetupChunkTriangles)
        assembleAndSetUp(call, in, first, int(std::min(end - first, size_t(kSetupChunkTriangles))), batch);
    binTriangles(batch, TileGrid{framebuffer_.tilesX(), framebuffer_.tilesY()},
                 standardSamplePattern(framebuffer_.samples()));
}

void Pipeline::flush() {
    if (queued_.empty()) return;
    ++stats_.flushes;
    const double t0 = nowMs();
    shadeVertices();
    const double t1 = nowMs();
    if (batches_.size() < queued_.size()) batches_.resize(queued_.size());
    parallelFor(queued_.size(), [&](size_t i) { frontEnd(queued_[i], batches_[i]); });
    const double t2 = nowMs();
    parallelFor(size_t(framebuffer_.tileCount()), [&](size_t tile) {
        for (size_t b = 0; b < queued_.size(); ++b) {
            const TriangleBatch& batch = batches_[b];
            if (batch.tileOffsets[tile] != batch.tileOffsets[tile + 1]) tilesDrawnSinceTightened_[tile] = 1;
            rasterizeBatchInTile(batch, draws_[batch.drawIndex].state, int(tile), framebuffer_,
                                 tileCounters_[tile]);
        }
    });
    const double t3 = nowMs();
    stats_.times.vertexMs += t1 - t0;
    stats_.times.frontEndMs += t2 - t1;
    stats_.times.backEndMs += t3 - t2;
    for (size_t b = 0; b < queued_.size(); ++b) stats_.counters += batches_[b].counters;
    queued_.clear();
    recycleFinishedVertexOutputs();
}

// Only tiles a batch reached since the last tightening can have changed: a frame that flushes
// often (voxel chunks) would otherwise read every tile's depths at each flush.
void Pipeline::flushAndTightenHierarchicalDepth() {
    flush();
    const double t0 = nowMs();
    parallelFor(size_t(framebuffer_.tileCount()), [&](size_t tile) {
        if (!tilesDrawnSinceTightened_[tile]) return;
        tilesDrawnSinceTightened_[tile] = 0;
        framebuffer_.tightenHierarchicalDepth(int(tile));
    });
    stats_.times.backEndMs += nowMs() - t0;
}

// After a flush every shaded draw is finished but the one draw() may still be queueing: their
// vertex storage goes to the spares (its capacity kept), so a frame of a million small draws
// holds the vertices of one flush, not of the frame.
void Pipeline::recycleFinishedVertexOutputs() {
    const size_t finished = drawsShaded_ - (drawInProgress_ && drawsShaded_ > 0 ? 1 : 0);
    for (; drawsRecycled_ < finished; ++drawsRecycled_) {
        VertexStageOutput& done = vertexOutputs_[drawsRecycled_];
        const size_t bytes = done.capacityBytes();
        if (spareVertexBytes_ + bytes <= kSpareVertexStorageBytes) {
            spareVertexBytes_ += bytes;
            spareVertexOutputs_.push_back(std::move(done));
        }
        done = VertexStageOutput{};  // past the cap (or moved from): its storage is freed
    }
}

}  // namespace cuberille::raster
