#include "raster/visibility_shade_tables.h"

#include <algorithm>
#include <bit>
#include <limits>
#include <type_traits>

#include "raster/depth.h"
#include "raster/fine.h"
#include "raster/output_merge.h"
#include "raster/sample_pattern.h"
#include "raster/shade.h"

// The deferred shade stage's per-tile half, compiled once per instruction set as the forward back
// end is (raster/tile_raster.cpp says how: Highway's foreach_target.h includes this file again per
// target, each copy in a namespace of its own under the target's `#pragma GCC target`), so its
// shading models run in the same vector code as the forward path's, and give the same bits.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "raster/visibility_shade_tile.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>

#include "raster/shade_queue-inl.h"  // shadeQueue()

HWY_BEFORE_NAMESPACE();
namespace cuberille::raster {
namespace HWY_NAMESPACE {
namespace {

using namespace seen;  // the stage's tables (raster/visibility_shade_tables.h)

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

/// A clipped triangle's fan, ready to split a pixel's samples among its pieces: each piece's
/// sample offsets, found once for all the pixels of the triangle a block holds.
template <int S>
struct FanPieces {
    const SetupChunk* chunk = nullptr;
    SeenPieces pieces;
    SampleEdgeOffsets<S> offsets[kMaxClippedVertices];

    FanPieces(const SetupChunk& c, const SeenPieces& p) : chunk(&c), pieces(p) {
        const SamplePattern& sp = standardSamplePattern(S);
        for (uint32_t i = 0; i < pieces.count; ++i) computeSampleEdgeOffsets<S>(c.setups[pieces.first + i], sp, offsets[i]);
    }

    /// The piece that takes every sample of every pixel in [x0, x1] x [y0, y1] by split()'s rule,
    /// or -1 where no one piece is sure to: one whose edges pass every sample of the rectangle
    /// (edge values are affine, so their least over its pixel centres is at a corner, and the
    /// samples add at least their least offset), with every piece before it failing some edge at
    /// every sample. A large clipped triangle (a floor cut by the guard band) then costs a test a
    /// block instead of its pieces' tests at each pixel.
    int wholeRect(int32_t x0, int32_t y0, int32_t x1, int32_t y1) const {
        for (uint32_t i = 0; i < pieces.count; ++i) {
            const TriangleSetup& t = chunk->setups[pieces.first + i];
            int64_t corners[4][3];
            edgesAtPixelCentre(t, x0, y0, corners[0]);
            edgesAtPixelCentre(t, x1, y0, corners[1]);
            edgesAtPixelCentre(t, x0, y1, corners[2]);
            edgesAtPixelCentre(t, x1, y1, corners[3]);
            bool inside = true, outside = false;
            for (int k = 0; k < 3; ++k) {
                const int64_t least = *std::min_element(offsets[i].edge[k], offsets[i].edge[k] + S);
                const int64_t most = *std::max_element(offsets[i].edge[k], offsets[i].edge[k] + S);
                int64_t low = corners[0][k], high = corners[0][k];
                for (int c = 1; c < 4; ++c) low = std::min(low, corners[c][k]), high = std::max(high, corners[c][k]);
                inside = inside && low + least >= 0;
                outside = outside || high + most < 0;
            }
            if (inside) return int(i);
            if (!outside) return -1;  // this piece may take some samples, and a later one others
        }
        return -1;
    }

    /// The samples of pixel (x, y) split as the forward path splits them: each to the piece that
    /// covers it (the fill rule gives a shared edge's samples to one), and any no piece covers (an
    /// exact ray met the triangle where the snapped pieces do not reach) to the piece nearest the
    /// centre. masks[i] goes to piece first + i.
    void split(int32_t x, int32_t y, uint32_t pass, uint32_t (&masks)[kMaxClippedVertices]) const {
        uint32_t left = pass;
        for (uint32_t i = 0; i < pieces.count; ++i) {
            if (!left) {  // every sample has its piece: the later ones get none (a large fan's common case)
                masks[i] = 0;
                continue;
            }
            int64_t e[3];
            edgesAtPixelCentre(chunk->setups[pieces.first + i], x, y, e);
            masks[i] = coverageMask<S>(e, offsets[i]) & left;
            left &= ~masks[i];
        }
        if (left) masks[pieceNearestCentre(*chunk, pieces, x, y) - pieces.first] |= left;
    }
};

/// Each of a slot's pixels' samples split among the triangle's pieces: masks[i][p] goes to piece
/// pieces.first + p. Most seen triangles are one piece; a clipped one's pixels are split among
/// its fan, at a test a block where one piece takes them all (FanPieces::wholeRect).
template <int S>
void splitAmongPieces(const SetupChunk& chunk, const SeenPieces& pieces, std::span<const SeenPixel> pixels,
                      uint32_t (*masks)[kMaxClippedVertices]) {
    if (pieces.count == 1) {
        for (size_t i = 0; i < pixels.size(); ++i) masks[i][0] = pixels[i].pass;
        return;
    }
    const FanPieces<S> fan(chunk, pieces);
    int32_t x0 = pixels[0].x, x1 = x0, y0 = pixels[0].y, y1 = y0;
    for (const SeenPixel& px : pixels.subspan(1))
        x0 = std::min(x0, px.x), x1 = std::max(x1, px.x), y0 = std::min(y0, px.y), y1 = std::max(y1, px.y);
    if (const int whole = fan.wholeRect(x0, y0, x1, y1); whole >= 0) {
        for (size_t i = 0; i < pixels.size(); ++i)
            for (uint32_t p = 0; p < pieces.count; ++p) masks[i][p] = int(p) == whole ? pixels[i].pass : 0;
        return;
    }
    for (size_t i = 0; i < pixels.size(); ++i) fan.split(pixels[i].x, pixels[i].y, pixels[i].pass, masks[i]);
}

/// One draw's shading in one block: its seen pixels, piece by piece, queued and lit. Where the
/// draw lights across triangles (raster/shade.h) every piece's pixels join one InterpolatedQueue,
/// as the forward path's small triangles share their tile's (a block of small triangles would
/// otherwise shade a queue of a pixel or a few per triangle); else each piece has a queue of its
/// own. Every draw merges as opaque here (the header says why), so a pixel's depth and colour are
/// independent writes: its depths are written as it is queued, its colour when its queue is lit.
template <int S, class Shader>
class DrawShading {
public:
    DrawShading(const Shader& shader, const DrawState& state, int originX, int originY, int imageWidth, glm::vec4* color,
                float* depth, StageCounters& counters)
        : shader_(shader), state_(state), originX_(originX), originY_(originY), imageWidth_(imageWidth), color_(color),
          depth_(depth), counters_(counters) {
        computeSampleSubpixelOffsets<S>(standardSamplePattern(S), offsets_);
        if constexpr (Shader::kInterpolatesAcrossTriangles) {
            sharing_ = shader.interpolatesAcrossTriangles();
            shared_.pixels.count = 0;
        }
    }

    /// The samples of `pixels` that masks[i][piece] gives to piece `t`.
    void shadePiece(const TriangleSetup& t, const float* varyings, std::span<const SeenPixel> pixels,
                    const uint32_t (*masks)[kMaxClippedVertices], uint32_t piece) {
        if constexpr (Shader::kInterpolatesAcrossTriangles) {
            if (sharing_) return queueShared(t, varyings, pixels, masks, piece);
        }
        own_.count = 0;
        eachPixel(t, pixels, masks, piece, [&](const int64_t (&e)[3], uint32_t first, uint32_t pass, uint32_t pixelIndex) {
            const int n = own_.count++;
            own_.edge0[n] = e[0], own_.edge1[n] = e[1], own_.edge2[n] = e[2];
            own_.firstSample[n] = first, own_.passMask[n] = pass, own_.pixelIndex[n] = pixelIndex;
        });
        if (own_.count == 0) return;
        shadeQueue(shader_, t, varyings, own_, counters_);
        merge(own_);
    }

    /// Lights what the shared queue still holds, at the end of the draw's pixels in the block.
    void finish() {
        if constexpr (Shader::kInterpolatesAcrossTriangles) {
            if (sharing_ && shared_.pixels.count) lightShared();
        }
    }

private:
    static constexpr bool kSurface = !std::is_same_v<Shader, ConstantColorShader>;

    /// A piece's pixels in the shared queue: its range interpolated when the queue fills (then the
    /// whole queue lit) and when its pixels are in.
    void queueShared(const TriangleSetup& t, const float* varyings, std::span<const SeenPixel> pixels,
                     const uint32_t (*masks)[kMaxClippedVertices], uint32_t piece) {
        if constexpr (Shader::kInterpolatesAcrossTriangles) {
            ShadeQueue& q = shared_.pixels;
            int rangeBegin = q.count;
            eachPixel(t, pixels, masks, piece, [&](const int64_t (&e)[3], uint32_t first, uint32_t pass, uint32_t pixelIndex) {
                if (q.count == ShadeQueue::kCapacity) {
                    if (q.count > rangeBegin) interpolateQueueRange(shader_, t, varyings, shared_, rangeBegin, counters_);
                    lightShared();
                    rangeBegin = 0;
                }
                queueForInterpolation(shader_, t, e, first, pass, pixelIndex, q);
            });
            if (q.count > rangeBegin) interpolateQueueRange(shader_, t, varyings, shared_, rangeBegin, counters_);
        }
    }

    void lightShared() {
        if constexpr (Shader::kInterpolatesAcrossTriangles) {
            shadeInterpolatedQueue(shader_, shared_, counters_);
            merge(shared_.pixels);
        }
    }

    /// For each pixel with samples of this piece: queue(edges at its centre, its first sample in
    /// the tile, the samples, its index in the image); then its depths written.
    template <class Queue>
    void eachPixel(const TriangleSetup& t, std::span<const SeenPixel> pixels, const uint32_t (*masks)[kMaxClippedVertices],
                   uint32_t piece, Queue queue) {
        for (size_t i = 0; i < pixels.size(); ++i) {
            const uint32_t pass = masks[i][piece];
            if (!pass) continue;
            const SeenPixel& px = pixels[i];
            int64_t e[3];
            edgesAtPixelCentre(t, px.x, px.y, e);
            const uint32_t first = uint32_t(((px.y - originY_) * kTileSizePixels + (px.x - originX_)) * S);
            queue(e, first, pass, uint32_t(px.y) * uint32_t(imageWidth_) + uint32_t(px.x));
            counters_.samplesPassed += uint64_t(std::popcount(pass));
            if (!state_.depthWrite) continue;
            float d[S];
            sampleDepths<S>(t, px.x, px.y, offsets_, d);
            mergeDepth<S>(depth_ + first, pass, d);
        }
    }

    /// Output merge of a lit queue's colours, opaque; empties the queue.
    void merge(ShadeQueue& q) {
        counters_.pixelsShaded += q.count;
        for (int n = 0; n < q.count; ++n)
            mergeColor<S>(color_ + q.firstSample[n], q.passMask[n],
                          glm::vec4(q.red[n], q.green[n], q.blue[n], kSurface ? 1.0f : q.alpha[n]), state_.colorWriteMask);
        q.count = 0;
    }

    const Shader& shader_;
    const DrawState& state_;
    int originX_, originY_, imageWidth_;
    glm::vec4* color_;
    float* depth_;
    StageCounters& counters_;
    SampleSubpixelOffsets<S> offsets_;
    ShadeQueue own_;
    [[maybe_unused]] InterpolatedQueueFor<Shader> shared_;  // an empty stand-in for a shader without one
    bool sharing_ = false;
};

/// One draw's seen pixels of a block, sorted by slot: each slot's pixels split among its
/// triangle's pieces, and each piece's shaded (DrawShading).
template <int S, class Shader>
void shadeDrawPixels(const Shader& shader, const DrawCall& call, const SeenDraw& seenDraw, std::span<const SeenPixel> pixels,
                     int originX, int originY, int imageWidth, glm::vec4* color, float* depth, StageCounters& counters,
                     uint64_t& withoutSetUp) {
    DrawShading<S, Shader> shading(shader, call.state, originX, originY, imageWidth, color, depth, counters);
    uint32_t masks[ShadeQueue::kCapacity][kMaxClippedVertices];
    for (size_t begin = 0; begin < pixels.size();) {
        size_t end = begin;
        while (end < pixels.size() && pixels[end].slot == pixels[begin].slot) ++end;
        const std::span<const SeenPixel> slotPixels = pixels.subspan(begin, end - begin);
        begin = end;
        const uint32_t slot = slotPixels[0].slot;
        const SeenPieces pieces = seenDraw.pieces[slot];
        if (pieces.count == 0) {
            for (const SeenPixel& px : slotPixels) withoutSetUp += uint64_t(std::popcount(px.pass));
            continue;
        }
        const SetupChunk& chunk = seenDraw.chunks[slot / kSeenTrianglesPerChunk];
        splitAmongPieces<S>(chunk, pieces, slotPixels, masks);
        for (uint32_t p = 0; p < pieces.count; ++p) {
            const TriangleSetup& t = chunk.setups[pieces.first + p];
            shading.shadePiece(t, chunk.varyings.data() + t.varyingOffset, slotPixels, masks, p);
        }
    }
    shading.finish();
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

// A block's pixels are in row order; a stable sort by (draw, slot) keeps them so. At one sample
// they are at most 64 and come in runs of one triangle, so an insertion sort, which moves each only
// past the groups it belongs before, does it without the merge sort's buffer (allocated per call);
// with more samples, a pixel's groups can interleave many triangles, and the merge sort bounds it.
void sortByTriangle(std::span<SeenPixel> pixels) {
    const auto before = [](const SeenPixel& a, const SeenPixel& b) {
        return a.draw != b.draw ? a.draw < b.draw : a.slot < b.slot;
    };
    if (pixels.size() > size_t(kBlockSizePixels * kBlockSizePixels)) {
        std::stable_sort(pixels.begin(), pixels.end(), before);
        return;
    }
    for (size_t i = 1; i < pixels.size(); ++i) {
        if (!before(pixels[i], pixels[i - 1])) continue;
        const SeenPixel p = pixels[i];
        size_t j = i;
        for (; j > 0 && before(p, pixels[j - 1]); --j) pixels[j] = pixels[j - 1];
        pixels[j] = p;
    }
}

/// A block's pixels, each pixel's samples grouped by the triangle they see, sorted by draw and slot.
template <int S>
void gatherBlock(const std::vector<SeenDraw>& seenDraws, const VisibilityBuffer& seen, int bx, int by, int width, int height,
                 std::vector<SeenPixel>& pixels) {
    const size_t first = pixels.size();
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
    sortByTriangle(std::span(pixels).subspan(first));
}

/// Asks for the set-ups a tile's pixels will shade with before any is shaded. A dense mesh's seen
/// triangles are scattered over megabytes of set-ups, so each triangle's record (and the entry
/// that finds it) is a cache miss; asked for all at once, the misses overlap instead of stalling
/// the shade stage one after another. First every triangle's pieces entry, then, once those have
/// had the first pass's time to arrive, the set-up records they point at.
void prefetchSetups(const std::vector<SeenDraw>& seenDraws, std::span<const SeenPixel> pixels) {
    const auto eachTriangle = [&](auto&& f) {
        for (size_t i = 0; i < pixels.size(); ++i)
            if (i == 0 || pixels[i].slot != pixels[i - 1].slot || pixels[i].draw != pixels[i - 1].draw)
                f(seenDraws[pixels[i].draw], pixels[i].slot);
    };
    eachTriangle([](const SeenDraw& d, uint32_t slot) { __builtin_prefetch(&d.pieces[slot]); });
    eachTriangle([](const SeenDraw& d, uint32_t slot) {
        const SeenPieces& p = d.pieces[slot];
        if (p.count == 0) return;
        const char* setup = reinterpret_cast<const char*>(&d.chunks[slot / kSeenTrianglesPerChunk].setups[p.first]);
        for (size_t byte = 0; byte < sizeof(TriangleSetup); byte += 64) __builtin_prefetch(setup + byte);
    });
}

// A tile, an 8x8 block at a time: each pixel's samples grouped by the triangle they see, the
// block's groups sorted by draw and triangle, each draw's shaded with one shader. The whole tile's
// groups are found first, so its set-ups can be asked for together (prefetchSetups).
template <int S>
void shadeTileWith(std::span<const DrawCall> draws, const std::vector<SeenDraw>& seenDraws, const VisibilityBuffer& seen,
                   int tile, Framebuffer& fb, StageCounters& counters, uint64_t& withoutSetUp) {
    const int originX = (tile % fb.tilesX()) * kTileSizePixels, originY = (tile / fb.tilesX()) * kTileSizePixels;
    const int width = fb.width(), height = fb.height();
    thread_local std::vector<SeenPixel> pixels;
    thread_local std::vector<size_t> blockEnds;
    pixels.clear();
    blockEnds.clear();
    for (int by = originY; by < std::min(originY + kTileSizePixels, height); by += kBlockSizePixels)
        for (int bx = originX; bx < std::min(originX + kTileSizePixels, width); bx += kBlockSizePixels) {
            gatherBlock<S>(seenDraws, seen, bx, by, width, height, pixels);
            blockEnds.push_back(pixels.size());
        }
    // A tile nothing is seen in stays untouched, as the forward path leaves it: it reads as cleared.
    if (pixels.empty()) return;
    fb.touchTile(tile);
    glm::vec4* color = fb.tileColor(tile);
    float* depth = fb.tileDepth(tile);
    prefetchSetups(seenDraws, pixels);
    size_t begin = 0;
    for (const size_t blockEnd : blockEnds) {
        while (begin < blockEnd) {
            size_t end = begin;
            while (end < blockEnd && pixels[end].draw == pixels[begin].draw) ++end;
            const uint32_t d = pixels[begin].draw;
            shadeDraw<S>(draws[d], seenDraws[d], std::span<const SeenPixel>(pixels).subspan(begin, end - begin), originX,
                         originY, width, color, depth, counters, withoutSetUp);
            begin = end;
        }
    }
    fb.tightenHierarchicalDepth(tile);
}

}  // namespace

void shadeTileOnTarget(std::span<const DrawCall> draws, const std::vector<SeenDraw>& seenDraws, const VisibilityBuffer& buffer,
                       int tile, Framebuffer& fb, StageCounters& counters, uint64_t& withoutSetUp) {
    switch (fb.samples()) {
        case 1: shadeTileWith<1>(draws, seenDraws, buffer, tile, fb, counters, withoutSetUp); break;
        case 2: shadeTileWith<2>(draws, seenDraws, buffer, tile, fb, counters, withoutSetUp); break;
        case 4: shadeTileWith<4>(draws, seenDraws, buffer, tile, fb, counters, withoutSetUp); break;
        case 8: shadeTileWith<8>(draws, seenDraws, buffer, tile, fb, counters, withoutSetUp); break;
        case 16: shadeTileWith<16>(draws, seenDraws, buffer, tile, fb, counters, withoutSetUp); break;
    }
}

}  // namespace HWY_NAMESPACE
}  // namespace cuberille::raster
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace cuberille::raster {

HWY_EXPORT(shadeTileOnTarget);

void seen::shadeTile(std::span<const DrawCall> draws, const std::vector<SeenDraw>& seenDraws, const VisibilityBuffer& buffer,
                     int tile, Framebuffer& fb, StageCounters& counters, uint64_t& withoutSetUp) {
    HWY_DYNAMIC_DISPATCH(shadeTileOnTarget)(draws, seenDraws, buffer, tile, fb, counters, withoutSetUp);
}

}  // namespace cuberille::raster
#endif  // HWY_ONCE
