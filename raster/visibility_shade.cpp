#include "raster/visibility_shade.h"

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

constexpr uint32_t kNone = VisibilityBuffer::kNone;
/// The seen triangles of a draw are set up in chunks of this many, one task each.
constexpr size_t kSeenTrianglesPerChunk = 4096;

/// The set-ups one seen triangle became: one, or a fan where a clip plane cut it, or none where
/// it has zero area once snapped. Indices into its chunk's set-ups.
struct SeenPieces {
    uint32_t first = 0;
    uint32_t count = 0;
};

struct SetupChunk {
    std::vector<TriangleSetup> setups;
    std::vector<float> varyings;  // three vertices' a set-up, in set-up order (TriangleSetup::varyingOffset)
};

/// What the frame knows of one draw: which of its triangles the buffer names, their set-ups,
/// and its vertex stage's outputs.
struct SeenDraw {
    std::vector<uint32_t> slotOf;    // per triangle of the draw: its slot among the seen ones, or kNone
    std::vector<uint32_t> seen;      // per slot: the triangle, ascending
    std::vector<SeenPieces> pieces;  // per slot
    std::vector<SetupChunk> chunks;  // slot / kSeenTrianglesPerChunk
    VertexStageOutput vertices;
};

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
template <int S>
void shadeTile(std::span<const DrawCall> draws, const std::vector<SeenDraw>& seenDraws, const VisibilityBuffer& seen,
               int tile, Framebuffer& fb, StageCounters& counters, uint64_t& withoutSetUp);

}  // namespace

// The stages in the order a frame runs them: which triangles are seen, the vertex stage of their
// draws, the set-up of the seen triangles only, then per tile the shade stage and output merge.
VisibilityShadeStats shadeVisibility(std::span<const DrawCall> draws, const VisibilityBuffer& seen, Framebuffer& fb,
                                     StageCounters& counters) {
    if (seen.width != fb.width() || seen.height != fb.height() || seen.samples != fb.samples())
        throw std::invalid_argument("shadeVisibility: the visibility buffer's size or sample count is not the framebuffer's");
    if (!fb.hasColor()) throw std::invalid_argument("shadeVisibility: a depth-only framebuffer");
    for (const DrawCall& call : draws)
        if (call.space != PositionSpace::Clip) throw std::invalid_argument("shadeVisibility: a window-space draw");
    VisibilityShadeStats stats;
    std::vector<SeenDraw> seenDraws(draws.size());
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
        StageCounters& c = tileCounters[tile];
        uint64_t& w = tileWithoutSetUp[tile];
        switch (fb.samples()) {
            case 1: shadeTile<1>(draws, seenDraws, seen, int(tile), fb, c, w); break;
            case 2: shadeTile<2>(draws, seenDraws, seen, int(tile), fb, c, w); break;
            case 4: shadeTile<4>(draws, seenDraws, seen, int(tile), fb, c, w); break;
            case 8: shadeTile<8>(draws, seenDraws, seen, int(tile), fb, c, w); break;
            case 16: shadeTile<16>(draws, seenDraws, seen, int(tile), fb, c, w); break;
        }
    });
    for (size_t tile = 0; tile < tileCounters.size(); ++tile) {
        counters += tileCounters[tile];
        stats.samplesWithoutSetUp += tileWithoutSetUp[tile];
    }
    stats.shadeMs = nowMs() - t2;
    return stats;
}

namespace {

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
        for (uint32_t t = 0; t < d.slotOf.size(); ++t)
            if (d.slotOf[t] != kNone) {
                d.slotOf[t] = uint32_t(d.seen.size());
                d.seen.push_back(t);
            }
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
        for (size_t slot = c * kSeenTrianglesPerChunk; slot < end; ++slot) {
            SeenPieces& p = seenDraw.pieces[slot];
            p.first = uint32_t(chunk.setups.size());
            setUpOne(call, seenDraw.vertices, seenDraw.seen[slot], context, volume, chunk);
            p.count = uint32_t(chunk.setups.size()) - p.first;
        }
    });
}

/// A pixel's samples that see one triangle.
struct SeenPixel {
    uint32_t draw, slot;
    int32_t x, y;
    uint32_t pass;
};

/// Of a clipped triangle's fan, the piece whose edges lie nearest the pixel centre: the one
/// holding it, else the one it lies least outside of (the shade stage clamps onto the piece, as
/// it does for a forward pixel whose centre is uncovered).
uint32_t pieceNearestCentre(const SetupChunk& chunk, const SeenPieces& pieces, int32_t x, int32_t y) {
    uint32_t best = pieces.first;
    double bestOutside = -std::numeric_limits<double>::infinity();
    for (uint32_t p = pieces.first; p < pieces.first + pieces.count; ++p) {
        const TriangleSetup& t = chunk.setups[p];
        int64_t e[3];
        edgesAtPixelCentre(t, x, y, e);
        const double least = double(std::min({e[0], e[1], e[2]})) * t.invDoubleArea;
        if (least > bestOutside) bestOutside = least, best = p;
    }
    return best;
}

/// A clipped triangle's samples at one pixel, split among its fan's pieces as the forward path
/// splits them: each sample to the piece that covers it (the fill rule gives a shared edge's
/// samples to one), and any no piece covers (an exact ray met the triangle where the snapped
/// pieces do not reach) to the piece nearest the centre. masks[i] goes to piece first + i.
template <int S>
void splitAmongPieces(const SetupChunk& chunk, const SeenPieces& pieces, int32_t x, int32_t y, uint32_t pass,
                      uint32_t (&masks)[kMaxClippedVertices]) {
    const SamplePattern& sp = standardSamplePattern(S);
    uint32_t left = pass;
    for (uint32_t i = 0; i < pieces.count; ++i) {
        const TriangleSetup& t = chunk.setups[pieces.first + i];
        SampleEdgeOffsets<S> offsets;
        computeSampleEdgeOffsets<S>(t, sp, offsets);
        int64_t e[3];
        edgesAtPixelCentre(t, x, y, e);
        masks[i] = coverageMask<S>(e, offsets) & left;
        left &= ~masks[i];
    }
    if (left) masks[pieceNearestCentre(chunk, pieces, x, y) - pieces.first] |= left;
}

/// One draw's seen pixels of a block, sorted by slot: each slot's pixels shaded as one queue
/// per piece, then merged. Every draw merges as opaque (the header says why).
template <int S, class Shader>
void shadeDrawPixels(const Shader& shader, const DrawCall& call, const SeenDraw& seenDraw, std::span<const SeenPixel> pixels,
                     int originX, int originY, int imageWidth, glm::vec4* color, float* depth, StageCounters& counters,
                     uint64_t& withoutSetUp) {
    constexpr bool kSurface = !std::is_same_v<Shader, ConstantColorShader>;
    SampleSubpixelOffsets<S> offsets;
    computeSampleSubpixelOffsets<S>(standardSamplePattern(S), offsets);
    const DrawState& state = call.state;
    ShadeQueue q;
    uint32_t masks[ShadeQueue::kCapacity][kMaxClippedVertices];
    for (size_t begin = 0; begin < pixels.size();) {
        size_t end = begin;
        while (end < pixels.size() && pixels[end].slot == pixels[begin].slot) ++end;
        const uint32_t slot = pixels[begin].slot;
        const SeenPieces pieces = seenDraw.pieces[slot];
        const SetupChunk& chunk = seenDraw.chunks[slot / kSeenTrianglesPerChunk];
        if (pieces.count == 0) {
            for (size_t i = begin; i < end; ++i) withoutSetUp += uint64_t(std::popcount(pixels[i].pass));
            begin = end;
            continue;
        }
        // Most seen triangles are one piece; a clipped one's pixels are split among its fan.
        for (size_t i = begin; i < end; ++i) {
            if (pieces.count == 1) {
                masks[i - begin][0] = pixels[i].pass;
                continue;
            }
            splitAmongPieces<S>(chunk, pieces, pixels[i].x, pixels[i].y, pixels[i].pass, masks[i - begin]);
        }
        for (uint32_t p = 0; p < pieces.count; ++p) {
            const TriangleSetup& t = chunk.setups[pieces.first + p];
            q.count = 0;
            for (size_t i = begin; i < end; ++i) {
                const uint32_t pass = masks[i - begin][p];
                if (!pass) continue;
                const SeenPixel& px = pixels[i];
                int64_t e[3];
                edgesAtPixelCentre(t, px.x, px.y, e);
                const int n = q.count++;
                q.edge0[n] = e[0], q.edge1[n] = e[1], q.edge2[n] = e[2];
                q.firstSample[n] = uint32_t(((px.y - originY) * kTileSizePixels + (px.x - originX)) * S);
                q.passMask[n] = pass;
                q.pixelIndex[n] = uint32_t(px.y) * uint32_t(imageWidth) + uint32_t(px.x);
            }
            if (q.count == 0) continue;
            shader.shade(t, chunk.varyings.data() + t.varyingOffset, q, counters);
            counters.pixelsShaded += q.count;
            for (int n = 0; n < q.count; ++n) {
                glm::vec4 c(q.red[n], q.green[n], q.blue[n], q.alpha[n]);
                if (kSurface) c.a = 1.0f;
                const uint32_t first = q.firstSample[n], pass = q.passMask[n];
                mergeColor<S>(color + first, pass, c, state.colorWriteMask);
                counters.samplesPassed += uint64_t(std::popcount(pass));
                if (!state.depthWrite) continue;
                const int pixel = int(first) / S;
                float d[S];
                sampleDepths<S>(t, originX + pixel % kTileSizePixels, originY + pixel / kTileSizePixels, offsets, d);
                mergeDepth<S>(depth + first, pass, d);
            }
        }
        begin = end;
    }
}

template <int S>
void shadeDraw(const DrawCall& call, const SeenDraw& seenDraw, std::span<const SeenPixel> pixels, int originX, int originY,
               int imageWidth, glm::vec4* color, float* depth, StageCounters& counters, uint64_t& withoutSetUp) {
    const DrawState& state = call.state;
    const VaryingLayout& layout = seenDraw.vertices.layout;
    const auto run = [&](const auto& shader) {
        shadeDrawPixels<S>(shader, call, seenDraw, pixels, originX, originY, imageWidth, color, depth, counters, withoutSetUp);
    };
    switch (state.shading) {
        case ShadingModel::ConstantColor: run(ConstantColorShader{}); break;
        case ShadingModel::Unlit: run(SurfaceShader<ShadingModel::Unlit>(state, layout)); break;
        case ShadingModel::Lambert: run(SurfaceShader<ShadingModel::Lambert>(state, layout)); break;
        case ShadingModel::MetallicRoughness: run(SurfaceShader<ShadingModel::MetallicRoughness>(state, layout)); break;
    }
}

// A tile, an 8x8 block at a time: each pixel's samples grouped by the triangle they see, the
// block's groups sorted by draw and triangle, each draw's shaded with one shader.
template <int S>
void shadeTile(std::span<const DrawCall> draws, const std::vector<SeenDraw>& seenDraws, const VisibilityBuffer& seen,
               int tile, Framebuffer& fb, StageCounters& counters, uint64_t& withoutSetUp) {
    const int originX = (tile % fb.tilesX()) * kTileSizePixels, originY = (tile / fb.tilesX()) * kTileSizePixels;
    const int width = fb.width(), height = fb.height();
    fb.touchTile(tile);
    glm::vec4* color = fb.tileColor(tile);
    float* depth = fb.tileDepth(tile);
    std::vector<SeenPixel> pixels;
    pixels.reserve(size_t(kBlockSizePixels * kBlockSizePixels * S));
    for (int by = originY; by < std::min(originY + kTileSizePixels, height); by += kBlockSizePixels)
        for (int bx = originX; bx < std::min(originX + kTileSizePixels, width); bx += kBlockSizePixels) {
            pixels.clear();
            for (int y = by; y < std::min(by + kBlockSizePixels, height); ++y)
                for (int x = bx; x < std::min(bx + kBlockSizePixels, width); ++x) {
                    const size_t base = (size_t(y) * size_t(width) + size_t(x)) * S;
                    uint32_t grouped = 0;
                    for (int s = 0; s < S; ++s) {
                        const uint32_t d = seen.draw[base + s];
                        if ((grouped >> s & 1u) || d == kNone) continue;
                        const uint32_t t = seen.triangle[base + s];
                        uint32_t pass = 1u << s;
                        for (int r = s + 1; r < S; ++r)
                            if (seen.draw[base + r] == d && seen.triangle[base + r] == t) pass |= 1u << r;
                        grouped |= pass;
                        pixels.push_back({d, seenDraws[d].slotOf[t], x, y, pass});
                    }
                }
            // A block's pixels are in row order; a stable sort by (draw, slot) keeps them so.
            std::stable_sort(pixels.begin(), pixels.end(), [](const SeenPixel& a, const SeenPixel& b) {
                return a.draw != b.draw ? a.draw < b.draw : a.slot < b.slot;
            });
            for (size_t begin = 0; begin < pixels.size();) {
                size_t end = begin;
                while (end < pixels.size() && pixels[end].draw == pixels[begin].draw) ++end;
                const uint32_t d = pixels[begin].draw;
                shadeDraw<S>(draws[d], seenDraws[d], std::span(pixels).subspan(begin, end - begin), originX, originY, width,
                             color, depth, counters, withoutSetUp);
                begin = end;
            }
        }
    fb.tightenHierarchicalDepth(tile);
}

}  // namespace
}  // namespace cuberille::raster
