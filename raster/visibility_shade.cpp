#include "raster/visibility_shade.h"

#include "raster/visibility_shade_tables.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <stdexcept>

#include "raster/clip.h"
#include "raster/clock.h"
#include "raster/depth.h"
#include "raster/fine.h"
#include "raster/output_merge.h"
#include "raster/parallel.h"
#include "raster/sample_pattern.h"
#include "raster/setup.h"
#include "raster/shade.h"
#include "raster/vertex.h"

namespace cuberille::raster {
namespace {

using namespace seen;  // the stage's tables (raster/visibility_shade_tables.h)

SetupContext deferredSetupContext(const DrawCall& call, const Framebuffer& fb, int varyingCount) {
    SetupContext c = SetupContext::forDraw(call.space, fb.width(), fb.height(), standardSamplePattern(fb.samples()),
                                           CullMode::None, varyingCount);
    c.depthKeySign = depthKeySign(fb.desc().depthConvention);
    c.rejectWithoutSamples = false;
    return c;
}

void markSeenTriangles(std::span<const DrawCall> draws, const VisibilityBuffer& seen, std::vector<SeenDraw>& out);
void shadeSeenVertices(std::span<const DrawCall> draws, const Framebuffer& fb, std::vector<SeenDraw>& out);
void setUpSeenTriangles(std::span<const DrawCall> draws, const Framebuffer& fb, std::vector<SeenDraw>& out);

}  // namespace

struct VisibilityShadeStorage {
    std::vector<SeenDraw> draws;  // per draw of the frame; each one's vectors keep their capacity
};

std::unique_ptr<VisibilityShadeStorage, void (*)(VisibilityShadeStorage*)> makeVisibilityShadeStorage() {
    return {new VisibilityShadeStorage, [](VisibilityShadeStorage* s) { delete s; }};
}

// The stages in the order a frame runs them: which triangles are seen, the vertex stage of their
// draws, the set-up of the seen triangles only, then per tile the shade stage and output merge.
VisibilityShadeStats shadeVisibility(std::span<const DrawCall> draws, const VisibilityBuffer& seen, Framebuffer& fb,
                                     StageCounters& counters, VisibilityShadeStorage& storage) {
    if (seen.width != fb.width() || seen.height != fb.height() || seen.samples != fb.samples())
        throw std::invalid_argument("shadeVisibility: the visibility buffer's size or sample count is not the framebuffer's");
    if (!fb.hasColor()) throw std::invalid_argument("shadeVisibility: a depth-only framebuffer");
    for (const DrawCall& call : draws)
        if (call.space != PositionSpace::Clip) throw std::invalid_argument("shadeVisibility: a window-space draw");
    VisibilityShadeStats stats;
    std::vector<SeenDraw>& seenDraws = storage.draws;
    seenDraws.resize(draws.size());
    double t0 = nowMs();
    markSeenTriangles(draws, seen, seenDraws);
    shadeSeenVertices(draws, fb, seenDraws);
    double t1 = nowMs();
    stats.vertexMs = t1 - t0;
    setUpSeenTriangles(draws, fb, seenDraws);
    for (const SeenDraw& d : seenDraws) {
        stats.trianglesSeen += d.seen.size();
        for (const SetupChunk& c : d.chunks) counters.trianglesSetUp += c.setups.size();
    }
    double t2 = nowMs();
    stats.setupMs = t2 - t1;
    std::vector<StageCounters> tileCounters(size_t(fb.tileCount()));
    std::vector<uint64_t> tileWithoutSetUp(size_t(fb.tileCount()), 0);
    parallelFor(size_t(fb.tileCount()), [&](size_t tile) {
        seen::shadeTile(draws, seenDraws, seen, int(tile), fb, tileCounters[tile], tileWithoutSetUp[tile]);
    });
    for (size_t tile = 0; tile < tileCounters.size(); ++tile) {
        counters += tileCounters[tile];
        stats.samplesWithoutSetUp += tileWithoutSetUp[tile];
    }
    stats.shadeMs = nowMs() - t2;
    return stats;
}

namespace {

// The marked triangles of a draw numbered in triangle order: ranges of triangles counted in
// parallel, their first slots by a prefix sum, then numbered in parallel (a dense scan's draw has
// a million triangles, a tenth of them seen).
void numberSeen(SeenDraw& d) {
    constexpr size_t kTrianglesPerRange = 1 << 16;
    const size_t triangles = d.slotOf.size(), ranges = (triangles + kTrianglesPerRange - 1) / kTrianglesPerRange;
    std::vector<uint32_t> firstSlot(ranges + 1, 0);
    parallelFor(ranges, [&](size_t r) {
        uint32_t n = 0;
        for (size_t t = r * kTrianglesPerRange; t < std::min(triangles, (r + 1) * kTrianglesPerRange); ++t)
            n += d.slotOf[t] != kNone;
        firstSlot[r + 1] = n;
    });
    for (size_t r = 0; r < ranges; ++r) firstSlot[r + 1] += firstSlot[r];
    d.seen.resize(firstSlot[ranges]);
    parallelFor(ranges, [&](size_t r) {
        uint32_t slot = firstSlot[r];
        for (size_t t = r * kTrianglesPerRange; t < std::min(triangles, (r + 1) * kTrianglesPerRange); ++t)
            if (d.slotOf[t] != kNone) {
                d.slotOf[t] = slot;
                d.seen[slot++] = uint32_t(t);
            }
    });
}

// Which triangles the buffer names, marked in parallel (every writer stores the same 0, so the
// result does not depend on the order), then numbered in triangle order per draw.
void markSeenTriangles(std::span<const DrawCall> draws, const VisibilityBuffer& seen, std::vector<SeenDraw>& out) {
    for (size_t d = 0; d < draws.size(); ++d) out[d].slotOf.assign(draws[d].triangleCount(), kNone);
    std::atomic<bool> invalid{false};
    const size_t rowSamples = size_t(seen.width) * size_t(seen.samples);
    parallelFor(size_t(seen.height), [&](size_t y) {
        for (size_t i = y * rowSamples; i < (y + 1) * rowSamples; ++i) {
            const uint32_t d = seen.draw[i];
            if (d == kNone) continue;
            const uint32_t t = seen.triangle[i];
            if (d >= out.size() || t >= out[d].slotOf.size()) {
                invalid.store(true, std::memory_order_relaxed);
                continue;
            }
            std::atomic_ref<uint32_t>(out[d].slotOf[t]).store(0, std::memory_order_relaxed);
        }
    });
    if (invalid) throw std::invalid_argument("shadeVisibility: a sample names a draw or triangle the frame does not have");
    for (SeenDraw& d : out) {
        numberSeen(d);
        d.pieces.resize(d.seen.size());
        d.chunks.resize((d.seen.size() + kSeenTrianglesPerChunk - 1) / kSeenTrianglesPerChunk);
    }
}

// The vertex stage of every draw with a seen triangle, over fixed vertex ranges of all of them.
void shadeSeenVertices(std::span<const DrawCall> draws, const Framebuffer& fb, std::vector<SeenDraw>& out) {
    std::vector<std::pair<uint32_t, size_t>> tasks;  // (draw, first vertex)
    for (size_t d = 0; d < draws.size(); ++d) {
        if (out[d].seen.empty()) continue;
        out[d].vertices.resize(draws[d].positions.size(), varyingLayoutFor(draws[d]));
        for (size_t v = 0; v < draws[d].positions.size(); v += kVerticesPerTask) tasks.emplace_back(uint32_t(d), v);
    }
    parallelFor(tasks.size(), [&](size_t i) {
        const auto [d, first] = tasks[i];
        const DrawCall& call = draws[d];
        VertexStageOutput& v = out[d].vertices;
        runVertexStage(call, ClipVolume::forViewport(fb.width(), fb.height()), deferredSetupContext(call, fb, v.layout.count),
                       first, std::min(call.positions.size(), first + kVerticesPerTask), v);
    });
}

void appendSetup(const WindowVertex (&w)[3], const float* const (&varyings)[3], const glm::vec4& color,
                 const SetupContext& context, SetupChunk& chunk) {
    TriangleSetup t;
    int order[3];
    if (setupTriangle(w[0], w[1], w[2], context, t, order) != SetupResult::Accepted) return;
    const int count = context.varyingCount;
    t.varyingOffset = uint32_t(chunk.varyings.size());
    t.flatColor = color;
    for (int v = 0; v < 3; ++v) chunk.varyings.insert(chunk.varyings.end(), varyings[order[v]], varyings[order[v]] + count);
    chunk.setups.push_back(t);
}

// One seen triangle's set-ups: the front end's (pipeline.cpp), without culling (the buffer has
// decided what is seen) and without the rejection of triangles that cover no sample.
void setUpOne(const DrawCall& call, const VertexStageOutput& vertices, uint32_t triangle, const SetupContext& context,
              const ClipVolume& volume, SetupChunk& chunk) {
    size_t index[3];
    uint32_t codes = 0;
    for (int i = 0; i < 3; ++i) {
        index[i] = call.indices.empty() ? size_t(triangle) * 3 + i : call.indices[size_t(triangle) * 3 + i];
        codes |= index[i] < vertices.clipPositions.size() ? vertices.outcodes[index[i]] : kInvalidVertex;
    }
    if (codes & kInvalidVertex) return;
    const glm::vec4 color = call.triangleColors.size() > triangle ? call.triangleColors[triangle] : call.state.constantColor;
    const int count = vertices.layout.count;
    if (codes == 0) {
        const WindowVertex w[3] = {vertices.window[index[0]], vertices.window[index[1]], vertices.window[index[2]]};
        const float* base = vertices.varyings.data();
        const float* const v[3] = {base + index[0] * count, base + index[1] * count, base + index[2] * count};
        appendSetup(w, v, color, context, chunk);
        return;
    }
    const uint8_t* outcodes = vertices.outcodes.data();
    if (classifyTriangle(outcodes[index[0]], outcodes[index[1]], outcodes[index[2]]) == ClipOutcome::Rejected) return;
    clipAndProjectFan(vertices, volume, context, index, codes,
                      [&](const WindowVertex (&w)[3], const float* const (&v)[3]) { appendSetup(w, v, color, context, chunk); });
}

void setUpSeenTriangles(std::span<const DrawCall> draws, const Framebuffer& fb, std::vector<SeenDraw>& out) {
    std::vector<std::pair<uint32_t, size_t>> tasks;  // (draw, chunk)
    for (size_t d = 0; d < draws.size(); ++d)
        for (size_t c = 0; c < out[d].chunks.size(); ++c) tasks.emplace_back(uint32_t(d), c);
    parallelFor(tasks.size(), [&](size_t i) {
        const auto [d, c] = tasks[i];
        const DrawCall& call = draws[d];
        SeenDraw& seenDraw = out[d];
        const SetupContext context = deferredSetupContext(call, fb, seenDraw.vertices.layout.count);
        const ClipVolume volume = ClipVolume::forViewport(fb.width(), fb.height());
        SetupChunk& chunk = seenDraw.chunks[c];
        const size_t end = std::min(seenDraw.seen.size(), (c + 1) * kSeenTrianglesPerChunk);
        chunk.setups.clear();  // a frame before's
        chunk.varyings.clear();
        // Room for one set-up a triangle, as almost every seen triangle is (a clipped one's fan
        // grows it), so the chunk is not copied as it fills.
        chunk.setups.reserve(end - c * kSeenTrianglesPerChunk + kMaxClippedVertices);
        chunk.varyings.reserve(chunk.setups.capacity() * 3 * size_t(context.varyingCount));
        for (size_t slot = c * kSeenTrianglesPerChunk; slot < end; ++slot) {
            SeenPieces& p = seenDraw.pieces[slot];
            p.first = uint32_t(chunk.setups.size());
            setUpOne(call, seenDraw.vertices, seenDraw.seen[slot], context, volume, chunk);
            p.count = uint32_t(chunk.setups.size()) - p.first;
        }
    });
}

}  // namespace
}  // namespace cuberille::raster
