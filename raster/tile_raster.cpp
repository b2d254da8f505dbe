#include "raster/tile_raster.h"

#include <algorithm>
#include <limits>
#include <bit>
#include <type_traits>

#include "raster/coarse.h"
#include "raster/depth.h"
#include "raster/fine.h"
#include "raster/output_merge.h"
#include "raster/shade.h"

// The back end is compiled once per instruction set (raster/instruction_set.h): Highway's
// foreach_target.h includes this file again for each target, and HWY_BEFORE_NAMESPACE puts
// that copy's functions under the target's `#pragma GCC target`, in a namespace of its own
// (HWY_NAMESPACE), so no copy's code can stand in for another's. The headers above are
// included once, outside any target: what the loops below inline from them is compiled for
// the loop's target, and anything not inlined stays baseline code. So the per-pixel functions
// of coarse.h, fine.h, depth.h and output_merge.h are always_inline, and each shading model's
// shade() is compiled into this copy by shadeQueue() (raster/shade_queue-inl.h).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "raster/tile_raster.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>

#include "raster/shade_queue-inl.h"  // shadeQueue()

HWY_BEFORE_NAMESPACE();
namespace cuberille::raster {
namespace HWY_NAMESPACE {
namespace {

/// Triangles whose clamped pixel bounds hold at most this many pixels skip the coarse stage and
/// go straight to the fine stage over their bounds: small geometry (dense scans, tessellated
/// shapes, voxel faces) is the common case, not the exception, and for it the coarse stage's
/// classification and hierarchical-Z bound per 8x8 block cost more than the few pixels they
/// could skip. Nothing it does can change the result for such a triangle: a block it would cull
/// as hidden fails the per-sample LESS test pixel by pixel, and its bounds are too small to cover
/// a whole block, the one case where the coarse stage tightens the bound. Measured (raster_bench
/// --no-peer, 1920x1080, AVX-512, three alternating runs): 2 -> 16 pixels took the back end of
/// `field` from 33-43 to 26-31 ms at 1 sample and 93-102 to 85-89 ms at 4, the dragon's from
/// 23-24 to 19 ms and 83-87 to 69-73 ms; 31 pixels measured as 16 within noise.
constexpr int kSmallTrianglePixels = 16;
/// Below this many pixels of bounds in the tile, a triangle's pixels do not wait for a queue of
/// their own: a batch of one or two pixels does not pay for the batch loop. Where the draw has a
/// cross-triangle path (CrossTriangleQueue: the fused Lambert model) they join the tile's shared
/// queue; otherwise they are shaded one at a time as they pass the depth test. Sharing up to 64
/// or 256 pixels of bounds measured no different on `field` and the dragon (raster_bench).
constexpr int kMinPixelsToBatchShading = 16;

/// The depth key of a plane depth z: clamped to the viewport's [0, 1] the way std::clamp does,
/// branch-free so row loops vectorise, then signed by the convention (raster/depth.h).
inline float depthKeyOf(float z, float sign) { return sign * (z < 0.0f ? 0.0f : (z > 1.0f ? 1.0f : z)); }

/// A partial block runs a row at a time (rasterizePartialRows) only when the triangle's bounds
/// give it at least half a block's pixels: the row loops compute every lane, and a small
/// triangle's few pixels are cheaper one at a time, skipping uncovered ones early. Measured
/// (raster_bench, 1920x1080, AVX-512): rows for every partial block made `field` at 4 samples
/// 83 -> 96 ms and `subpixel` 185 -> 229 ms in the back end.
constexpr int kMinPixelsForPartialRows = kBlockSizePixels * kBlockSizePixels / 2;
// A small triangle's bounds may be wider than a block: the fine stage must take them a pixel at a
// time (the row path's lanes are one block row), and its shade queue must hold them.
static_assert(kSmallTrianglePixels < kMinPixelsForPartialRows, "small triangles' bounds must not take the row path");
static_assert(kSmallTrianglePixels <= ShadeQueue::kCapacity, "a small triangle's pixels must fit one shade queue");

/// Everything the per-pixel path needs for one (tile, draw) pair.
struct TileTarget {
    int originX, originY;  // first pixel of the tile
    glm::vec4* color;
    float* depth;
    uint32_t* overdraw;  // image-linear, or null
    uint32_t* blockPartial;
    uint32_t* blockFull;
    float* blockMaxDepth;  // this tile's hierarchical Z, 8x8 blocks row-major
    int imageWidth, imageHeight, blocksX;
    bool hierarchicalDepth;
    const DrawState* state;
    uint64_t* occlusion;  // null when the draw has no slot
    StageCounters* counters;
};

/// Where each lane of a block row lies: lane j is sample j % S of the row's pixel j / S (the
/// tile stores a pixel's samples together, so a row's samples are contiguous), at this offset
/// in subpixels from the row's first pixel centre. The same for every triangle of a frame.
template <int S>
struct BlockRowLanes {
    static constexpr int kLanes = kBlockSizePixels * S;
    int32_t x[kLanes], y[kLanes];
    explicit BlockRowLanes(const SampleSubpixelOffsets<S>& o) {
        for (int j = 0; j < kLanes; ++j) {
            x[j] = (j / S) * kSubpixelsPerPixel + o.x[j % S];
            y[j] = o.y[j % S];
        }
    }
};

/// Output merge of a shared queue's shaded pixels, in the order they were queued, as
/// shadeAndMerge() merges an opaque or blended draw's (alphaAt(i): pixel i's shaded alpha; an
/// opaque surface writes 1). Empties the queue.
template <int S, class Queue, class AlphaAt>
void mergeInQueueOrder(Queue& q, AlphaAt alphaAt, const TileTarget& target) {
    const DrawState& state = *target.state;
    StageCounters& counters = *target.counters;
    counters.pixelsShaded += q.count;
    for (int i = 0; i < q.count; ++i) {
        const glm::vec4 color(q.red[i], q.green[i], q.blue[i], state.alphaMode == AlphaMode::Opaque ? 1.0f : alphaAt(i));
        if (state.alphaMode == AlphaMode::Blend) {
            blendColor<S>(target.color + q.firstSample[i], q.passMask[i], color, state.colorWriteMask);
            ++counters.pixelsBlended;
        } else {
            mergeColor<S>(target.color + q.firstSample[i], q.passMask[i], color, state.colorWriteMask);
        }
    }
    q.count = 0;
}

/// The cross-triangle queue's shade stage, compiled for this copy's instruction set likewise.
template <class Shader>
[[gnu::noinline, gnu::flatten]] void shadeCrossTriangleQueue(const Shader& shader, CrossTriangleQueue& queue,
                                                             StageCounters& counters) {
    shader.shadeAcrossTriangles(queue, counters);
}

/// Shades a tile's CrossTriangleQueue and merges its pixels in the order they were queued (the
/// draws that use one are neither alpha-tested nor transmissive: their depths were written at
/// the depth test, and their colours merge as shadeAndMerge() merges them).
template <int S, class Shader>
[[gnu::noinline]] void shadeAndMergeAcrossTriangles(const Shader& shader, CrossTriangleQueue& q, const TileTarget& target) {
    shadeCrossTriangleQueue(shader, q, *target.counters);
    const float alpha = shader.fusedLambertAlpha();
    mergeInQueueOrder<S>(q, [alpha](int) { return alpha; }, target);
}

/// Lights a tile's InterpolatedQueue and merges its pixels in the order they were queued: the
/// merge of shadeAndMerge() for draws that are neither alpha-tested nor transmissive (their
/// depths were written at the depth test).
template <int S, class Shader>
[[gnu::noinline]] void shadeAndMergeInterpolated(const Shader& shader, InterpolatedQueueFor<Shader>& queue,
                                                 const TileTarget& target) {
    shadeInterpolatedQueue(shader, queue, *target.counters);
    const ShadeQueue& q = queue.pixels;
    mergeInQueueOrder<S>(queue.pixels, [&q](int i) { return q.alpha[i]; }, target);
}

template <int S, class Shader>
class TriangleRaster {
public:
    /// shared: the tile's CrossTriangleQueue where the draw shades small triangles across
    /// triangles (shadesAcrossTriangles), else null; interpolated: the tile's InterpolatedQueue
    /// where the draw lights them across triangles (interpolatesAcrossTriangles), else null.
    TriangleRaster(const TriangleSetup& t, const float* varyings, const Shader& shader,
                   const SamplePattern& sp, const TileTarget& target, const BlockRowLanes<S>& lanes,
                   CrossTriangleQueue* shared, InterpolatedQueueFor<Shader>* interpolated)
        : t_(t), varyings_(varyings), shader_(shader), target_(target), lanes_(lanes), shared_(shared),
          interpolated_(interpolated) {
        computeSampleEdgeOffsets<S>(t, sp, edgeOffsets_);
        computeSampleSubpixelOffsets<S>(sp, sampleOffsets_);
    }

    void run(const SamplePattern& sp) {
        const PixelRect bounds{std::max(t_.pixelMinX, target_.originX),
                               std::max(t_.pixelMinY, target_.originY),
                               std::min(t_.pixelMaxX, target_.originX + kTileSizePixels - 1),
                               std::min(t_.pixelMaxY, target_.originY + kTileSizePixels - 1)};
        if (bounds.minX > bounds.maxX || bounds.minY > bounds.maxY) return;
        const int pixels = (bounds.maxX - bounds.minX + 1) * (bounds.maxY - bounds.minY + 1);
        const bool few = pixels < kMinPixelsToBatchShading;
        shareQueue_ = few && shared_;
        shadeImmediately_ = few && !shared_ && !interpolated_;
        if constexpr (Shader::kInterpolatesAcrossTriangles) {
            if (interpolated_) rangeBegin_ = interpolated_->pixels.count;
        }
        if (pixels <= kSmallTrianglePixels) {
            ++target_.counters->smallTriangleEntries;
            rasterizePartial(bounds);
        } else {
            coarse(bounds, sp);
        }
        if constexpr (Shader::kInterpolatesAcrossTriangles) {
            if (interpolated_) interpolateOwnRange();
        }
    }

private:
    // Coarse stage over the 8x8 blocks (aligned to the tile) that meet the bounds: classify by
    // coverage, then reject blocks hierarchical Z proves hidden before any sample is touched.
    void coarse(const PixelRect& bounds, const SamplePattern& sp) {
        const DrawState& state = *target_.state;
        const int bx0 = bounds.minX / kBlockSizePixels, bx1 = bounds.maxX / kBlockSizePixels;
        const int by0 = bounds.minY / kBlockSizePixels, by1 = bounds.maxY / kBlockSizePixels;
        for (int by = by0; by <= by1; ++by) {
            for (int bx = bx0; bx <= bx1; ++bx) {
                const PixelRect whole{bx * kBlockSizePixels, by * kBlockSizePixels,
                                      std::min(bx * kBlockSizePixels + kBlockSizePixels, target_.imageWidth) - 1,
                                      std::min(by * kBlockSizePixels + kBlockSizePixels, target_.imageHeight) - 1};
                const PixelRect block{std::max(bounds.minX, whole.minX), std::max(bounds.minY, whole.minY),
                                      std::min(bounds.maxX, whole.maxX), std::min(bounds.maxY, whole.maxY)};
                const SampleBox box = sampleBoxOf(block, sp);
                const BlockClass cls = classifySampleBox(t_, box);
                if (cls == BlockClass::Empty) {
                    ++target_.counters->blocksEmpty;
                    continue;
                }
                float& blockMaxDepth =
                    target_.blockMaxDepth[((by * kBlockSizePixels - target_.originY) / kBlockSizePixels) *
                                              kBlocksPerTileSide +
                                          (bx * kBlockSizePixels - target_.originX) / kBlockSizePixels];
                if (state.depthTest && target_.hierarchicalDepth &&
                    minSampleDepthOverBox(t_, box.loX, box.hiX, box.loY, box.hiY) >= blockMaxDepth) {
                    ++target_.counters->blocksDepthCulled;
                    continue;
                }
                if (cls == BlockClass::Partial) {
                    ++target_.counters->blocksPartial;
                    if (target_.blockPartial) ++target_.blockPartial[by * target_.blocksX + bx];
                    rasterizePartial(block);
                    continue;
                }
                ++target_.counters->blocksFull;
                if (target_.blockFull) ++target_.blockFull[by * target_.blocksX + bx];
                const FullBlockResult r = rasterizeFull(block);
                // LESS only lowers stored depths, so the bound stays valid on its own; it can be
                // tightened when this triangle replaced every sample of the block.
                const bool coversWholeBlock = block.minX == whole.minX && block.minY == whole.minY &&
                                              block.maxX == whole.maxX && block.maxY == whole.maxY;
                if (state.depthTest && state.depthWrite && coversWholeBlock && r.everySamplePassed)
                    blockMaxDepth = r.maxDepthWritten;
            }
        }
    }

    struct FullBlockResult {
        bool everySamplePassed = true;
        float maxDepthWritten = -std::numeric_limits<float>::infinity();  // keys are negative when reversed
    };

    // Full block: every sample is covered, no edge test at all.
    FullBlockResult rasterizeFull(const PixelRect& r) {
        if constexpr (S == 1)
            if (isPlainPass()) return rasterizeFullPlain(r);
        if (takesBlockRows()) return rasterizeFullRows(r);
        const uint32_t all = S == 32 ? ~0u : (1u << S) - 1u;
        FullBlockResult result;
        for (int y = r.minY; y <= r.maxY; ++y) {
            int64_t e[3];  // stepped for the shader's barycentrics only
            edgesAtPixelCentre(t_, r.minX, y, e);
            for (int x = r.minX; x <= r.maxX; ++x) {
                float maxDepth = -std::numeric_limits<float>::infinity();
                const uint32_t pass = depthAndQueue(x, y, all, e, &maxDepth);
                result.everySamplePassed = result.everySamplePassed && pass == all;
                result.maxDepthWritten = std::max(result.maxDepthWritten, maxDepth);
                for (int k = 0; k < 3; ++k) e[k] += int64_t{t_.edgeA[k]} * kSubpixelsPerPixel;
            }
        }
        shadeAndMerge();
        return result;
    }

    /// Whether full blocks may run a block row at a time (rasterizeFullRows): a depth-tested
    /// draw whose depth writes do not wait for shading (no alpha test) and that keeps no
    /// per-pixel counts (overdraw, occlusion queries).
    bool takesBlockRows() const {
        const DrawState& state = *target_.state;
        return state.depthTest && state.alphaMode != AlphaMode::Mask && !target_.overdraw && !target_.occlusion;
    }

    // A full block a row at a time: the depth keys of the row's samples, the LESS test and the
    // depth writes are straight loops over up to 8 x S lanes (contiguous in the tile), which the
    // compiler vectorises for this copy's instruction set; only queueing the pixels that passed
    // is per pixel. Each key is sampleDepths()'s expression in its order, the tests and writes
    // are depthAndQueue()'s, and the block's largest written key is taken in the same sample
    // order, so depths, images and counters are those of the per-pixel path bit for bit
    // (EveryInstructionSet runs, goldens, Determinism.SameImageOnEveryInstructionSet).
    FullBlockResult rasterizeFullRows(const PixelRect& r) {
        const DrawState& state = *target_.state;
        constexpr int kLanes = BlockRowLanes<S>::kLanes;
        const int width = r.maxX - r.minX + 1, lanes = width * S;
        const int32_t cx0 = r.minX * kSubpixelsPerPixel + kPixelCentreSubpixels - t_.originXSubpixels;
        const float z0 = t_.depthAtOrigin, dzdx = t_.depthPerSubpixelX, dzdy = t_.depthPerSubpixelY, sign = t_.depthKeySign;
        FullBlockResult result;
        uint64_t passedSamples = 0;
        for (int y = r.minY; y <= r.maxY; ++y) {
            const int32_t cy = y * kSubpixelsPerPixel + kPixelCentreSubpixels - t_.originYSubpixels;
            float key[kLanes];
            for (int j = 0; j < lanes; ++j) {
                const float z = z0 + dzdx * float(cx0 + lanes_.x[j]) + dzdy * float(cy + lanes_.y[j]);
                key[j] = depthKeyOf(z, sign);
            }
            const size_t first = (size_t(y - target_.originY) * kTileSizePixels + size_t(r.minX - target_.originX)) * S;
            float* stored = target_.depth + first;
            uint8_t pass[kLanes];
            int rowPassed = 0;
            for (int j = 0; j < lanes; ++j) {
                pass[j] = key[j] < stored[j];
                rowPassed += pass[j];
            }
            if (state.depthWrite)
                for (int j = 0; j < lanes; ++j) stored[j] = pass[j] ? key[j] : stored[j];
            passedSamples += uint64_t(rowPassed);
            result.everySamplePassed = result.everySamplePassed && rowPassed == lanes;
            if (result.everySamplePassed && state.depthWrite)
                for (int j = 0; j < lanes; ++j) result.maxDepthWritten = std::max(result.maxDepthWritten, key[j]);
            if (!state.colorWriteMask || rowPassed == 0) continue;
            int64_t e[3];  // for the shader's barycentrics
            edgesAtPixelCentre(t_, r.minX, y, e);
            queueRow(r.minX, y, width, first, pass, e);
        }
        StageCounters& c = *target_.counters;
        c.samplesTested += uint64_t(width) * uint64_t(r.maxY - r.minY + 1) * S;
        c.samplesPassed += passedSamples;
        shadeAndMerge();
        if (!result.everySamplePassed) result.maxDepthWritten = -std::numeric_limits<float>::infinity();
        return result;
    }

    /// A pass with nothing to do per pixel but depth and, at most, one flat colour: one sample,
    /// depth tested and written, no colour or all of it written with the triangle's flat colour
    /// (ConstantColor: visibility buffers), no alpha test, no overdraw or occlusion counts.
    /// Shadow maps and visibility buffers are such passes.
    bool isPlainPass() const {
        const DrawState& state = *target_.state;
        const bool flatColour = std::is_same_v<Shader, ConstantColorShader> && state.colorWriteMask == kWriteAll;
        return (state.colorWriteMask == 0 || flatColour) && state.alphaMode == AlphaMode::Opaque &&
               state.depthTest && state.depthWrite && !target_.overdraw && !target_.occlusion;
    }

    /// One row of a plain pass from pixel (x0, y): where it starts in the tile, and the terms of
    /// sampleDepths() that stay the same along it, copied out of the set-up so that the stores to
    /// the tile's floats (which may alias it, as far as the compiler knows) do not reload them.
    struct PlainRow {
        size_t start;
        float z0, dzdx, rowTerm, sign;
        int32_t cx0;  // subpixels from the depth plane's origin to the row's first sample, in x
        /// The depth key sampleDepths() computes at the row's i-th pixel, in its order of operations.
        float keyAt(int i) const {
            const float z = z0 + dzdx * float(cx0 + i * kSubpixelsPerPixel) + rowTerm;
            return depthKeyOf(z, sign);
        }
    };
    PlainRow plainRow(int x0, int y) const {
        const int32_t cy = y * kSubpixelsPerPixel + kPixelCentreSubpixels - t_.originYSubpixels + sampleOffsets_.y[0];
        return {size_t(y - target_.originY) * kTileSizePixels + size_t(x0 - target_.originX),
                t_.depthAtOrigin,
                t_.depthPerSubpixelX,
                t_.depthPerSubpixelY * float(cy),
                t_.depthKeySign,
                x0 * kSubpixelsPerPixel + kPixelCentreSubpixels - t_.originXSubpixels + sampleOffsets_.x[0]};
    }

    // The full-block loop of such a pass: each block row is a straight run over contiguous
    // depths with no branch, which the compiler turns into SIMD. Each depth is the expression
    // sampleDepths() evaluates, in the same order (floating-point contraction is off), so the
    // depths stored are those of the general path bit for bit (DepthOnlyTarget tests).
    FullBlockResult rasterizeFullPlain(const PixelRect& r) {
        constexpr float kNone = -std::numeric_limits<float>::infinity();
        const int width = r.maxX - r.minX + 1;
        const bool writeColour = target_.state->colorWriteMask != 0;
        int passed = 0;
        for (int y = r.minY; y <= r.maxY; ++y) {
            const PlainRow row = plainRow(r.minX, y);
            float* stored = target_.depth + row.start;
            glm::vec4* colour = writeColour ? target_.color + row.start : nullptr;
            for (int i = 0; i < width; ++i) {
                const float key = row.keyAt(i);
                const bool pass = key < stored[i];
                stored[i] = pass ? key : stored[i];
                if (writeColour) colour[i] = pass ? t_.flatColor : colour[i];
                passed += pass;
            }
        }
        const int pixels = width * (r.maxY - r.minY + 1);
        target_.counters->samplesTested += uint64_t(pixels);
        target_.counters->samplesPassed += uint64_t(passed);
        if (writeColour) target_.counters->pixelsShaded += uint64_t(passed);
        // Hierarchical Z is tightened only when every sample passed: then every depth in the
        // block is this triangle's, and the largest written is the largest stored.
        float maxWritten = kNone;
        if (passed == pixels)
            for (int y = r.minY; y <= r.maxY; ++y) {
                const float* stored = target_.depth + size_t(y - target_.originY) * kTileSizePixels + size_t(r.minX - target_.originX);
                for (int i = 0; i < width; ++i) maxWritten = std::max(maxWritten, stored[i]);
            }
        return {passed == pixels, maxWritten};
    }

    // Fine stage: per-sample masks, stepping the edge values along each row. At most one block
    // (or a small triangle's bounds, kSmallTrianglePixels) at a time, so the shade queue never
    // overflows.
    void rasterizePartial(const PixelRect& r) {
        if constexpr (S == 1)
            if (isPlainPass()) return rasterizePartialPlain(r);
        const int pixels = (r.maxX - r.minX + 1) * (r.maxY - r.minY + 1);
        if (pixels >= kMinPixelsForPartialRows && takesBlockRows()) return rasterizePartialRows(r);
        for (int y = r.minY; y <= r.maxY; ++y) {
            int64_t e[3];
            edgesAtPixelCentre(t_, r.minX, y, e);
            for (int x = r.minX; x <= r.maxX; ++x) {
                const uint32_t mask = coverageMask<S>(e, edgeOffsets_);
                if (mask) depthAndQueue(x, y, mask, e);
                for (int k = 0; k < 3; ++k) e[k] += int64_t{t_.edgeA[k]} * kSubpixelsPerPixel;
            }
        }
        shadeAndMerge();
    }

    // The fine stage a row at a time, as rasterizeFullRows() runs the depth stage: each lane's
    // three edge values (the row's first pixel centre's, plus what the lane adds: whole pixels
    // of A and the sample's offset, the integers the per-pixel path steps to), the coverage test,
    // the depth keys, the LESS test and the depth writes are loops over the row's lanes. Exact:
    // the same int64 edge values, keys, tests, writes and counters as coverageMask() and
    // depthAndQueue() (the instruction-set, golden and exactness suites).
    void rasterizePartialRows(const PixelRect& r) {
        const DrawState& state = *target_.state;
        constexpr int kLanes = BlockRowLanes<S>::kLanes;
        const int width = r.maxX - r.minX + 1, lanes = width * S;
        int64_t laneEdge[3][kLanes];
        for (int k = 0; k < 3; ++k)
            for (int j = 0; j < lanes; ++j)
                laneEdge[k][j] = int64_t{t_.edgeA[k]} * ((j / S) * kSubpixelsPerPixel) + edgeOffsets_.edge[k][j % S];
        const int32_t cx0 = r.minX * kSubpixelsPerPixel + kPixelCentreSubpixels - t_.originXSubpixels;
        const float z0 = t_.depthAtOrigin, dzdx = t_.depthPerSubpixelX, dzdy = t_.depthPerSubpixelY, sign = t_.depthKeySign;
        uint64_t tested = 0, passedSamples = 0;
        for (int y = r.minY; y <= r.maxY; ++y) {
            int64_t e[3];
            edgesAtPixelCentre(t_, r.minX, y, e);
            uint8_t pass[kLanes];
            int rowCovered = 0;
            for (int j = 0; j < lanes; ++j) {
                const int64_t any = (e[0] + laneEdge[0][j]) | (e[1] + laneEdge[1][j]) | (e[2] + laneEdge[2][j]);
                pass[j] = any >= 0;
                rowCovered += pass[j];
            }
            if (rowCovered == 0) continue;
            tested += uint64_t(rowCovered);
            const int32_t cy = y * kSubpixelsPerPixel + kPixelCentreSubpixels - t_.originYSubpixels;
            const size_t first = (size_t(y - target_.originY) * kTileSizePixels + size_t(r.minX - target_.originX)) * S;
            float* stored = target_.depth + first;
            int rowPassed = 0;
            for (int j = 0; j < lanes; ++j) {
                const float z = z0 + dzdx * float(cx0 + lanes_.x[j]) + dzdy * float(cy + lanes_.y[j]);
                const float key = depthKeyOf(z, sign);
                pass[j] = pass[j] & uint8_t(key < stored[j]);
                if (state.depthWrite) stored[j] = pass[j] ? key : stored[j];
                rowPassed += pass[j];
            }
            passedSamples += uint64_t(rowPassed);
            if (!state.colorWriteMask || rowPassed == 0) continue;
            queueRow(r.minX, y, width, first, pass, e);
        }
        StageCounters& c = *target_.counters;
        c.samplesTested += tested;
        c.samplesPassed += passedSamples;
        shadeAndMerge();
    }

    // The fine stage of a plain pass: coverage at the one sample, the depth test and the writes
    // as selects in a row loop, with no shade queue. The edge values are those the general path
    // steps to (the same integers), the depths those of sampleDepths(): the same image, depths
    // and counters bit for bit (PlainPass tests).
    void rasterizePartialPlain(const PixelRect& r) {
        const int64_t step0 = int64_t{t_.edgeA[0]} * kSubpixelsPerPixel, step1 = int64_t{t_.edgeA[1]} * kSubpixelsPerPixel,
                      step2 = int64_t{t_.edgeA[2]} * kSubpixelsPerPixel;
        const int64_t offset0 = edgeOffsets_.edge[0][0], offset1 = edgeOffsets_.edge[1][0], offset2 = edgeOffsets_.edge[2][0];
        const int width = r.maxX - r.minX + 1;
        const bool writeColour = target_.state->colorWriteMask != 0;
        int tested = 0, passed = 0;
        for (int y = r.minY; y <= r.maxY; ++y) {
            int64_t e[3];
            edgesAtPixelCentre(t_, r.minX, y, e);
            const PlainRow row = plainRow(r.minX, y);
            float* stored = target_.depth + row.start;
            glm::vec4* colour = writeColour ? target_.color + row.start : nullptr;
            for (int i = 0; i < width; ++i) {
                const int64_t any = (e[0] + i * step0 + offset0) | (e[1] + i * step1 + offset1) | (e[2] + i * step2 + offset2);
                const bool covered = any >= 0;
                const float key = row.keyAt(i);
                const bool pass = covered && key < stored[i];
                stored[i] = pass ? key : stored[i];
                if (writeColour) colour[i] = pass ? t_.flatColor : colour[i];
                tested += covered;
                passed += pass;
            }
        }
        target_.counters->samplesTested += uint64_t(tested);
        target_.counters->samplesPassed += uint64_t(passed);
        if (writeColour) target_.counters->pixelsShaded += uint64_t(passed);
    }

    // Depth stage (early, before shading): test and write the samples' depths, count, and queue
    // the pixel for shading. centreEdges are the biased edge values at the pixel centre. Returns
    // the samples that passed; with maxDepthPassed, also the largest depth among them.
    [[gnu::always_inline]] uint32_t depthAndQueue(int32_t x, int32_t y, uint32_t covered,
                                                 const int64_t centreEdges[3],
                           float* maxDepthPassed = nullptr) {
        const DrawState& state = *target_.state;
        const size_t first =
            (size_t(y - target_.originY) * kTileSizePixels + size_t(x - target_.originX)) * S;
        float depth[S] = {};  // read only when computed; zeroed to keep -Wall quiet
        if (state.depthTest || state.depthWrite) sampleDepths<S>(t_, x, y, sampleOffsets_, depth);
        const uint32_t pass =
            state.depthTest ? depthTestLess<S>(covered, depth, target_.depth + first) : covered;
        StageCounters& c = *target_.counters;
        c.samplesTested += std::popcount(covered);
        if (!pass) return 0;
        if (state.alphaMode == AlphaMode::Mask) {
            // Alpha test: whether the pixel exists is known only after shading, so its samples
            // are counted and its depths written then (late depth write, shadeAndMerge). It
            // reports no pass, so hierarchical Z is not tightened on its account.
            queuePixel(x, y, first, pass, centreEdges);
            return 0;
        }
        if (state.colorWriteMask) queuePixel(x, y, first, pass, centreEdges);
        writeDepthAndCount(x, y, first, pass, depth, maxDepthPassed);
        return pass;
    }

    /// Queues the pixels of a block row whose lanes passed (pass[i * S + s]: sample s of the
    /// row's i-th pixel), from pixel (x0, y) whose samples start at `first` in the tile; e holds
    /// the edge values at that pixel's centre and is stepped along the row. Inlined: called out
    /// of line it took `fill`'s back end at 4 samples from 53 to 59 ms.
    [[gnu::always_inline]] void queueRow(int32_t x0, int32_t y, int width, size_t first, const uint8_t* pass, int64_t e[3]) {
        for (int i = 0; i < width; ++i) {
            uint32_t mask = 0;
            for (int s = 0; s < S; ++s) mask |= uint32_t(pass[i * S + s]) << s;
            if (mask) queuePixel(x0 + i, y, first + size_t(i) * S, mask, e);
            for (int k = 0; k < 3; ++k) e[k] += int64_t{t_.edgeA[k]} * kSubpixelsPerPixel;
        }
    }

    void queuePixel(int32_t x, int32_t y, size_t first, uint32_t pass, const int64_t centreEdges[3]) {
        if constexpr (Shader::kShadesAcrossTriangles) {
            if (shareQueue_) return queueAcross(first, pass, centreEdges);
        }
        if constexpr (Shader::kInterpolatesAcrossTriangles) {
            if (interpolated_) return queueInterpolated(x, y, first, pass, centreEdges);
        }
        const int i = queue_.count++;
        queue_.pixelIndex[i] = uint32_t(y) * uint32_t(target_.imageWidth) + uint32_t(x);
        queue_.edge0[i] = centreEdges[0];
        queue_.edge1[i] = centreEdges[1];
        queue_.edge2[i] = centreEdges[2];
        queue_.firstSample[i] = uint32_t(first);
        queue_.passMask[i] = pass;
        if (shadeImmediately_) shadeAndMerge();
    }

    /// Queues a pixel in the tile's CrossTriangleQueue, shading what it holds first when it is
    /// full; the triangle's inputs are gathered at its first pixel there.
    void queueAcross(size_t first, uint32_t pass, const int64_t centreEdges[3]) {
        if (!haveInputs_) {
            shader_.triangleInputs(t_, varyings_, inputs_);
            haveInputs_ = true;
        }
        if (shared_->count == CrossTriangleQueue::kCapacity) shadeAndMergeAcrossTriangles<S>(shader_, *shared_, target_);
        queueAcrossTriangles(*shared_, inputs_, centreEdges, uint32_t(first), pass);
    }

    /// Queues a pixel in the tile's InterpolatedQueue; when the queue is full, this triangle's
    /// pixels so far are interpolated and the whole queue lit first.
    void queueInterpolated(int32_t x, int32_t y, size_t first, uint32_t pass, const int64_t centreEdges[3]) {
        ShadeQueue& q = interpolated_->pixels;
        if (q.count == ShadeQueue::kCapacity) {
            interpolateOwnRange();
            shadeAndMergeInterpolated<S>(shader_, *interpolated_, target_);
            rangeBegin_ = 0;
        }
        queueForInterpolation(shader_, t_, centreEdges, uint32_t(first), pass,
                              uint32_t(y) * uint32_t(target_.imageWidth) + uint32_t(x), q);
    }

    /// This triangle's half of the InterpolatedQueue: the attributes of the pixels it queued.
    void interpolateOwnRange() {
        const int end = interpolated_->pixels.count;
        if (end > rangeBegin_)
            interpolateQueueRange(shader_, t_, varyings_, *interpolated_, rangeBegin_, *target_.counters);
        rangeBegin_ = end;
    }

    // Counters of depth-passing samples, then the depth writes (output merge's depth half).
    void writeDepthAndCount(int32_t x, int32_t y, size_t first, uint32_t pass, const float* depth,
                            float* maxDepthPassed) {
        const DrawState& state = *target_.state;
        StageCounters& c = *target_.counters;
        const int passed = std::popcount(pass);
        c.samplesPassed += passed;
        if (target_.occlusion) *target_.occlusion += passed;
        if (target_.overdraw) target_.overdraw[size_t(y) * target_.imageWidth + x] += passed;
        if (!state.depthWrite) return;
        mergeDepth<S>(target_.depth + first, pass, depth);
        float written = -std::numeric_limits<float>::infinity();
        for (int s = 0; s < S; ++s)
            if (pass & (1u << s)) written = std::max(written, depth[s]);
        if (maxDepthPassed) *maxDepthPassed = written;
        // Without a depth test a write can raise a depth: keep the block's bound above it.
        if (!state.depthTest) {
            float& bound = target_.blockMaxDepth[((y - target_.originY) / kBlockSizePixels) * kBlocksPerTileSide +
                                                 (x - target_.originX) / kBlockSizePixels];
            bound = std::max(bound, written);
        }
    }

    // Shade stage over the queued pixels in one loop, then output merge. The pixels of one
    // triangle never overlap, so deferring colour (and, for alpha-tested draws, depth) writes
    // to here changes nothing but the order of independent writes.
    void shadeAndMerge() {
        if (queue_.count == 0) return;
        // Earlier triangles' pixels still waiting in the tile's cross-triangle queue merge first:
        // output merge keeps the order the depth stage queued pixels in.
        if constexpr (Shader::kShadesAcrossTriangles) {
            if (shared_ && shared_->count) shadeAndMergeAcrossTriangles<S>(shader_, *shared_, target_);
        }
        const DrawState& state = *target_.state;
        StageCounters& counters = *target_.counters;
        shadeQueue(shader_, t_, varyings_, queue_, counters);
        counters.pixelsShaded += queue_.count;
        if (state.alphaMode == AlphaMode::Mask) counters.pixelsAlphaTested += queue_.count;
        // The alpha written is coverage: an opaque surface writes 1 whatever its colour's alpha
        // (glTF: OPAQUE ignores it), a masked one 1 where it survives the test; only blending
        // composes alpha (blendColor). So a transparent background resolves to each pixel's
        // covered fraction. Flat colours (.tri, visibility buffers) are written as given.
        constexpr bool kSurface = !std::is_same_v<Shader, ConstantColorShader>;
        for (int i = 0; i < queue_.count; ++i) {
            glm::vec4 color(queue_.red[i], queue_.green[i], queue_.blue[i], queue_.alpha[i]);
            const uint32_t first = queue_.firstSample[i], pass = queue_.passMask[i];
            if (kSurface && state.alphaMode == AlphaMode::Opaque) color.a = 1.0f;
            if (state.alphaMode == AlphaMode::Mask) {
                if (!(color.a >= state.alphaCutoff)) continue;  // discarded (NaN too)
                if (kSurface) color.a = 1.0f;
                const int pixel = int(first) / S;
                const int32_t x = target_.originX + pixel % kTileSizePixels, y = target_.originY + pixel / kTileSizePixels;
                float depth[S] = {};
                if (state.depthTest || state.depthWrite) sampleDepths<S>(t_, x, y, sampleOffsets_, depth);
                writeDepthAndCount(x, y, first, pass, depth, nullptr);
                if (!state.colorWriteMask) continue;
            }
            if (kSurface && state.transmits()) {
                const glm::vec3 transmittance(queue_.transmitRed[i], queue_.transmitGreen[i], queue_.transmitBlue[i]);
                transmitColor<S>(target_.color + first, pass, color, transmittance, state.colorWriteMask);
            } else if (state.alphaMode == AlphaMode::Blend) {
                blendColor<S>(target_.color + first, pass, color, state.colorWriteMask);
                ++counters.pixelsBlended;
            } else {
                mergeColor<S>(target_.color + first, pass, color, state.colorWriteMask);
            }
        }
        queue_.count = 0;
    }

    const TriangleSetup& t_;
    const float* varyings_;
    const Shader& shader_;
    const TileTarget& target_;
    const BlockRowLanes<S>& lanes_;
    SampleEdgeOffsets<S> edgeOffsets_;
    // A per-triangle copy of a per-frame constant, on purpose: held by reference instead, the
    // compiler must reload it around every sample store, and `field` at 1 sample ran 12% slower.
    SampleSubpixelOffsets<S> sampleOffsets_;
    bool shadeImmediately_ = false;
    CrossTriangleQueue* shared_;
    bool shareQueue_ = false;  // this triangle's pixels go to shared_
    bool haveInputs_ = false;
    CrossTriangleInputs inputs_;
    // Every triangle of a draw that lights across triangles queues there, whatever its size: a
    // large triangle fills the shared queue as it would fill its own, and a small one's few
    // pixels join a full batch (see InterpolatedQueue).
    InterpolatedQueueFor<Shader>* interpolated_;
    int rangeBegin_ = 0;              // its first pixel there not yet interpolated
    ShadeQueue queue_;  // a member, so the compiler sees it alias nothing (the loop vectorises)
};

/// Asks for every cache line of a set-up record, ahead of its use.
inline void prefetchSetup(const TriangleSetup& t) {
    const char* p = reinterpret_cast<const char*>(&t);
    for (size_t line = 0; line < sizeof(TriangleSetup); line += 64) __builtin_prefetch(p + line);
}

template <int S, class Shader>
void rasterizeBinned(const TriangleBatch& batch, int tile, const Shader& shader,
                     const SamplePattern& sp, const TileTarget& target) {
    const uint32_t begin = batch.tileOffsets[tile], end = batch.tileOffsets[tile + 1];
    // A dense mesh's set-ups are read in tile order, far from the order the front end wrote
    // them in: each is a cache miss. Fetching a few ahead overlaps those misses with the
    // rasterization of the triangles before them.
    constexpr uint32_t kPrefetchAhead = 8;
    SampleSubpixelOffsets<S> offsets;
    computeSampleSubpixelOffsets<S>(sp, offsets);
    const BlockRowLanes<S> lanes(offsets);
    // The tile's queue shared across triangles, of the kind the draw takes, if any: never for
    // alpha-tested draws (whose depth writes wait for shading) or transmissive ones (whose merge
    // reads the light passed through).
    const DrawState& state = *target.state;
    const bool mayShare = state.alphaMode != AlphaMode::Mask && !state.transmits() && state.colorWriteMask != 0;
    CrossTriangleQueue* shared = nullptr;
    struct NoQueue {};
    [[maybe_unused]] std::conditional_t<Shader::kShadesAcrossTriangles, CrossTriangleQueue, NoQueue> queue;
    if constexpr (Shader::kShadesAcrossTriangles) {
        if (mayShare && shader.shadesAcrossTriangles()) shared = &queue;
    }
    InterpolatedQueueFor<Shader>* interpolated = nullptr;
    [[maybe_unused]] InterpolatedQueueFor<Shader> interpolatedQueue;  // an empty stand-in for a shader without one
    if constexpr (Shader::kInterpolatesAcrossTriangles) {
        if (mayShare && shader.interpolatesAcrossTriangles()) interpolated = &interpolatedQueue;
    }
    for (uint32_t i = begin; i < end; ++i) {
        if (i + kPrefetchAhead < end) prefetchSetup(batch.triangles[batch.tileTriangles[i + kPrefetchAhead]]);
        const uint32_t index = batch.tileTriangles[i];
        const TriangleSetup& t = batch.triangles[index];
        TriangleRaster<S, Shader>(t, batch.varyings.data() + t.varyingOffset, shader, sp, target, lanes, shared, interpolated)
            .run(sp);
    }
    if constexpr (Shader::kShadesAcrossTriangles) {
        if (shared && shared->count) shadeAndMergeAcrossTriangles<S>(shader, *shared, target);
    }
    if constexpr (Shader::kInterpolatesAcrossTriangles) {
        if (interpolated && interpolated->pixels.count) shadeAndMergeInterpolated<S>(shader, *interpolated, target);
    }
}

template <int S>
void dispatchShader(const TriangleBatch& batch, int tile, const SamplePattern& sp,
                    const TileTarget& target, const VaryingLayout& layout) {
    const DrawState& state = *target.state;
    switch (state.shading) {
        case ShadingModel::ConstantColor:
            rasterizeBinned<S>(batch, tile, ConstantColorShader{}, sp, target);
            break;
        case ShadingModel::Unlit:
            rasterizeBinned<S>(batch, tile, SurfaceShader<ShadingModel::Unlit>(state, layout), sp, target);
            break;
        case ShadingModel::Lambert:
            rasterizeBinned<S>(batch, tile, SurfaceShader<ShadingModel::Lambert>(state, layout), sp, target);
            break;
        case ShadingModel::MetallicRoughness:
            rasterizeBinned<S>(batch, tile, SurfaceShader<ShadingModel::MetallicRoughness>(state, layout), sp,
                               target);
            break;
    }
}

}  // namespace

void rasterizeBatchInTileOnTarget(const TriangleBatch& batch, const DrawState& state, int tile,
                                  Framebuffer& fb, TileCounters& out) {
    if (batch.tileOffsets[tile] == batch.tileOffsets[tile + 1]) return;
    fb.touchTile(tile);
    if (state.occlusionSlot >= 0 && out.occlusionSamplesPassed.size() <= size_t(state.occlusionSlot))
        out.occlusionSamplesPassed.resize(state.occlusionSlot + 1, 0);
    const TileTarget target{
        (tile % fb.tilesX()) * kTileSizePixels,
        (tile / fb.tilesX()) * kTileSizePixels,
        fb.tileColor(tile),
        fb.tileDepth(tile),
        fb.overdraw(),
        fb.blockPartialCounts(),
        fb.blockFullCounts(),
        fb.tileBlockMaxDepth(tile),
        fb.width(),
        fb.height(),
        fb.blocksX(),
        fb.desc().hierarchicalDepth,
        &state,
        state.occlusionSlot >= 0 ? &out.occlusionSamplesPassed[state.occlusionSlot] : nullptr,
        &out.counters,
    };
    const SamplePattern& sp = standardSamplePattern(fb.samples());
    switch (fb.samples()) {
        case 1: dispatchShader<1>(batch, tile, sp, target, batch.layout); break;
        case 2: dispatchShader<2>(batch, tile, sp, target, batch.layout); break;
        case 4: dispatchShader<4>(batch, tile, sp, target, batch.layout); break;
        case 8: dispatchShader<8>(batch, tile, sp, target, batch.layout); break;
        case 16: dispatchShader<16>(batch, tile, sp, target, batch.layout); break;
    }
}

}  // namespace HWY_NAMESPACE
}  // namespace cuberille::raster
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace cuberille::raster {

HWY_EXPORT(rasterizeBatchInTileOnTarget);

void rasterizeBatchInTile(const TriangleBatch& batch, const DrawState& state, int tile,
                          Framebuffer& fb, TileCounters& out) {
    HWY_DYNAMIC_DISPATCH(rasterizeBatchInTileOnTarget)(batch, state, tile, fb, out);
}

}  // namespace cuberille::raster
#endif  // HWY_ONCE
