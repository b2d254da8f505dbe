#include "raster/pipeline.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "raster/clip.h"
#include "raster/parallel.h"
#include "raster/setup.h"

namespace cuberille::raster {
namespace {

double nowMs() {
    using namespace std::chrono;
    return duration<double, std::milli>(steady_clock::now().time_since_epoch()).count();
}

struct TriangleInput {
    const DrawCall& draw;
    const VertexStageOutput& vertices;
    ClipVolume volume;
    SetupContext setup;
};

bool fetchVertex(const TriangleInput& in, size_t index, SetupVertex& out) {
    if (index >= in.vertices.clipPositions.size()) return false;
    out.position = in.vertices.clipPositions[index];
    out.varyings = in.vertices.varyings.data() + index * in.vertices.varyingCount;
    return std::isfinite(out.position.x) && std::isfinite(out.position.y) &&
           std::isfinite(out.position.z) && std::isfinite(out.position.w);
}

ClipVertex toClipVertex(const SetupVertex& v, int varyingCount) {
    ClipVertex c;
    c.position = v.position;
    std::copy_n(v.varyings, varyingCount, c.varyings.data());
    return c;
}

SetupVertex fromClipVertex(const ClipVertex& c) { return {c.position, c.varyings.data()}; }

// Set-up of one (possibly clipped) triangle into the batch, counting the outcome. Varyings
// are copied only for triangles that survive set-up.
void setupInto(const TriangleInput& in, const SetupVertex& a, const SetupVertex& b,
               const SetupVertex& c, const glm::vec4& color, TriangleBatch& batch) {
    TriangleSetup t;
    int order[3];
    StageCounters& k = batch.counters;
    switch (setupTriangle(a, b, c, in.setup, t, order)) {
        case SetupResult::Accepted: {
            const SetupVertex* input[3] = {&a, &b, &c};
            t.varyingOffset = uint32_t(batch.varyings.size());
            for (int v = 0; v < 3; ++v)
                batch.varyings.insert(batch.varyings.end(), input[order[v]]->varyings,
                                      input[order[v]]->varyings + batch.varyingCount);
            t.flatColor = color;
            batch.triangles.push_back(t);
            ++k.trianglesSetUp;
            return;
        }
        case SetupResult::Degenerate: ++k.trianglesDegenerate; break;
        case SetupResult::Culled: ++k.trianglesCulled; break;
        case SetupResult::NoSamples: ++k.trianglesNoSamples; break;
        case SetupResult::Invalid: ++k.trianglesInvalid; break;
    }
}

}  // namespace

void Pipeline::beginFrame(const FramebufferDesc& desc) {
    frameStartMs_ = nowMs();
    framebuffer_.reset(desc);
    stats_ = {};
    draws_.clear();
    pendingBatches_ = 0;
    tileCounters_.assign(framebuffer_.tileCount(), {});
}

void Pipeline::draw(const DrawCall& call) {
    const double t0 = nowMs();
    runVertexStage(call, vertexOutput_);
    stats_.counters.verticesShaded += call.positions.size();
    const double t1 = nowMs();
    stats_.times.vertexMs += t1 - t0;

    const int drawIndex = int(draws_.size());
    draws_.push_back(call.state);
    const size_t triangles = call.triangleCount();
    const size_t batchCount = (triangles + kTrianglesPerBatch - 1) / kTrianglesPerBatch;
    for (size_t first = 0; first < batchCount;) {
        const size_t chunk = std::min(batchCount - first, kBatchesPerFlush - pendingBatches_);
        if (batches_.size() < pendingBatches_ + chunk) batches_.resize(pendingBatches_ + chunk);
        const double f0 = nowMs();
        parallelFor(chunk, [&](size_t i) {
            frontEnd(call, drawIndex, (first + i) * kTrianglesPerBatch,
                     batches_[pendingBatches_ + i]);
        });
        stats_.times.frontEndMs += nowMs() - f0;
        pendingBatches_ += chunk;
        first += chunk;
        if (pendingBatches_ == kBatchesPerFlush) flush();
    }
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

void Pipeline::frontEnd(const DrawCall& call, int drawIndex, size_t firstTriangle,
                        TriangleBatch& batch) {
    batch.clear();
    batch.drawIndex = drawIndex;
    batch.varyingCount = vertexOutput_.varyingCount;
    const Framebuffer& fb = framebuffer_;
    const SamplePattern& sp = standardSamplePattern(fb.samples());
    const TriangleInput in{
        call, vertexOutput_,
        call.space == PositionSpace::Window ? ClipVolume::forWindowSpace(fb.width(), fb.height())
                                            : ClipVolume::forViewport(fb.width(), fb.height()),
        SetupContext::forDraw(call.space, fb.width(), fb.height(), sp, call.state.cull,
                              vertexOutput_.varyingCount)};

    const size_t end = std::min(call.triangleCount(), firstTriangle + kTrianglesPerBatch);
    StageCounters& k = batch.counters;
    SetupVertex v[3];
    ClippedPolygon polygon;
    for (size_t tri = firstTriangle; tri < end; ++tri) {
        ++k.trianglesIn;
        bool valid = true;
        for (int i = 0; i < 3; ++i) {
            const size_t index = call.indices.empty() ? tri * 3 + i : call.indices[tri * 3 + i];
            valid = fetchVertex(in, index, v[i]) && valid;
        }
        if (!valid) {
            ++k.trianglesInvalid;
            continue;
        }
        const glm::vec4 color =
            call.triangleColors.empty() ? call.state.constantColor : call.triangleColors[tri];
        const uint32_t c0 = outcode(in.volume, v[0].position);
        const uint32_t c1 = outcode(in.volume, v[1].position);
        const uint32_t c2 = outcode(in.volume, v[2].position);
        switch (classifyTriangle(c0, c1, c2)) {
            case ClipOutcome::Rejected: ++k.trianglesClipRejected; break;
            case ClipOutcome::Inside: setupInto(in, v[0], v[1], v[2], color, batch); break;
            case ClipOutcome::Clipped:
                ++k.trianglesClipped;
                clipTriangle(in.volume, c0 | c1 | c2, toClipVertex(v[0], batch.varyingCount),
                             toClipVertex(v[1], batch.varyingCount),
                             toClipVertex(v[2], batch.varyingCount), batch.varyingCount, polygon);
                for (int i = 2; i < polygon.count; ++i) {
                    ++k.clippedTrianglesOut;
                    setupInto(in, fromClipVertex(polygon.vertices[0]),
                              fromClipVertex(polygon.vertices[i - 1]),
                              fromClipVertex(polygon.vertices[i]), color, batch);
                }
                break;
        }
    }
    binTriangles(batch, TileGrid{fb.tilesX(), fb.tilesY()}, sp);
}

void Pipeline::flush() {
    if (pendingBatches_ == 0) return;
    ++stats_.flushes;
    const double t0 = nowMs();
    parallelFor(size_t(framebuffer_.tileCount()), [&](size_t tile) {
        for (size_t b = 0; b < pendingBatches_; ++b) {
            const TriangleBatch& batch = batches_[b];
            rasterizeBatchInTile(batch, draws_[batch.drawIndex], int(tile), framebuffer_,
                                 tileCounters_[tile]);
        }
    });
    stats_.times.backEndMs += nowMs() - t0;
    for (size_t b = 0; b < pendingBatches_; ++b) stats_.counters += batches_[b].counters;
    pendingBatches_ = 0;
}

}  // namespace cuberille::raster
