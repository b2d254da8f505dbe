#include "raster/triangle_cull.h"

#include <algorithm>

// Compiled once per instruction set (see raster/tile_raster.cpp for how foreach_target.h works):
// the loops below are plain loops over lanes, which GCC vectorises for each target.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "raster/triangle_cull.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace cuberille::raster {
namespace HWY_NAMESPACE {
namespace {

constexpr int N = kCullChunkTriangles;

/// The verdicts of one chunk: facing and area, then bounds, then the few-pixel coverage test.
void cullChunk(const TriangleLanes& in, int count, const SetupContext& context, CullVerdict* verdicts);

/// One edge of every lane, as setupTriangle's setEdge() makes it: from vertex `from` to `to`,
/// inside at E >= 0, the top-left rule's bias in C.
struct EdgeLanes {
    double a[N], b[N], c[N];
};

void edgeLanes(const int32_t* fromX, const int32_t* fromY, const int32_t* toX, const int32_t* toY,
               int count, EdgeLanes& e) {
    for (int i = 0; i < count; ++i) {
        const int32_t a = fromY[i] - toY[i];
        const int32_t b = toX[i] - fromX[i];
        const double bias = (a > 0 || (a == 0 && b > 0)) ? 0.0 : -1.0;
        e.a[i] = a;
        e.b[i] = b;
        e.c[i] = -(double(a) * fromX[i] + double(b) * fromY[i]) + bias;
    }
}

void cullChunk(const TriangleLanes& in, int count, const SetupContext& context, CullVerdict* verdicts) {
    const SamplePattern& sp = *context.samples;
    const int32_t cullBack = context.cull == CullMode::Back, cullFront = context.cull == CullMode::Front;
    // Pixels whose sample span can meet the bounds (setup.cpp, samplePixelRange).
    const int32_t lowX = kPixelCentreSubpixels + sp.maxDx * kSampleOffsetUnitSubpixels;
    const int32_t highX = kPixelCentreSubpixels + sp.minDx * kSampleOffsetUnitSubpixels;
    const int32_t lowY = kPixelCentreSubpixels + sp.maxDy * kSampleOffsetUnitSubpixels;
    const int32_t highY = kPixelCentreSubpixels + sp.minDy * kSampleOffsetUnitSubpixels;

    // Facing from the doubled area (exact in double), and set-up's vertex order: v1 and v2 swap
    // for a counter-clockwise (front-facing) triangle. Each loop keeps to one or two element
    // types so that it vectorises.
    alignas(64) int32_t front[N], degenerate[N];
    for (int i = 0; i < count; ++i) {
        const int32_t X0 = in.x[0][i], Y0 = in.y[0][i];
        const double doubleArea = double(in.x[1][i] - X0) * double(in.y[2][i] - Y0) -
                                  double(in.x[2][i] - X0) * double(in.y[1][i] - Y0);
        front[i] = doubleArea < 0.0;
        degenerate[i] = doubleArea == 0.0;
    }
    alignas(64) int32_t x1[N], y1[N], x2[N], y2[N];
    alignas(64) int32_t pixelX0[N], pixelY0[N], pixelX1[N], pixelY1[N];
    alignas(64) int32_t verdict[N], testSamples[N];
    for (int i = 0; i < count; ++i) {
        const int32_t X0 = in.x[0][i], Y0 = in.y[0][i], X1 = in.x[1][i], Y1 = in.y[1][i];
        const int32_t X2 = in.x[2][i], Y2 = in.y[2][i];
        const int32_t isFront = front[i];  // 0 or 1
        x1[i] = isFront ? X2 : X1, y1[i] = isFront ? Y2 : Y1;
        x2[i] = isFront ? X1 : X2, y2[i] = isFront ? Y1 : Y2;

        const int32_t minX = std::min(X0, std::min(X1, X2)), maxX = std::max(X0, std::max(X1, X2));
        const int32_t minY = std::min(Y0, std::min(Y1, Y2)), maxY = std::max(Y0, std::max(Y1, Y2));
        // ceil and floor of a division by 256: arithmetic shifts (C++20).
        const int32_t firstX = std::max(-((lowX - minX) >> kSubpixelBits), 0);
        const int32_t lastX = std::min((maxX - highX) >> kSubpixelBits, context.scissorWidth - 1);
        const int32_t firstY = std::max(-((lowY - minY) >> kSubpixelBits), 0);
        const int32_t lastY = std::min((maxY - highY) >> kSubpixelBits, context.scissorHeight - 1);
        pixelX0[i] = firstX, pixelY0[i] = firstY, pixelX1[i] = lastX, pixelY1[i] = lastY;
        const int32_t empty = int32_t(firstX > lastX) | int32_t(firstY > lastY);
        // At most kSetupCoverageTestPixels (2) pixels: one, or two side by side; the second is
        // the last pixel, the first again for one.
        const int32_t width = lastX - firstX + 1, height = lastY - firstY + 1;
        const int32_t few = (1 - empty) & int32_t(width * height <= kSetupCoverageTestPixels);

        // setupTriangle's order of checks, written as selects so the loop runs in lanes.
        const int32_t culled = (cullBack & (1 - isFront)) | (cullFront & isFront);
        int32_t v = empty ? int32_t(CullVerdict::NoSamples) : int32_t(CullVerdict::MaySurvive);
        v = culled ? int32_t(CullVerdict::Culled) : v;
        v = degenerate[i] != 0 ? int32_t(CullVerdict::Degenerate) : v;
        verdict[i] = v;
        testSamples[i] = int32_t(v == int32_t(CullVerdict::MaySurvive)) & few;
    }
    static_assert(kSetupCoverageTestPixels == 2, "the coverage test below visits two pixels");

    alignas(64) EdgeLanes e0, e1, e2;  // edge k opposite vertex k
    edgeLanes(x1, y1, x2, y2, count, e0);
    edgeLanes(x2, y2, in.x[0], in.y[0], count, e1);
    edgeLanes(in.x[0], in.y[0], x1, y1, count, e2);
    alignas(64) int32_t covered[N] = {};
    for (int s = 0; s < sp.count; ++s) {
        const int32_t dx = kPixelCentreSubpixels + sp.dx[s] * kSampleOffsetUnitSubpixels;
        const int32_t dy = kPixelCentreSubpixels + sp.dy[s] * kSampleOffsetUnitSubpixels;
        for (int i = 0; i < count; ++i) {
            const double ax = double(pixelX0[i] * kSubpixelsPerPixel + dx), ay = double(pixelY0[i] * kSubpixelsPerPixel + dy);
            const double bx = double(pixelX1[i] * kSubpixelsPerPixel + dx), by = double(pixelY1[i] * kSubpixelsPerPixel + dy);
            const bool inA = (e0.a[i] * ax + e0.b[i] * ay + e0.c[i] >= 0.0) & (e1.a[i] * ax + e1.b[i] * ay + e1.c[i] >= 0.0) &
                             (e2.a[i] * ax + e2.b[i] * ay + e2.c[i] >= 0.0);
            const bool inB = (e0.a[i] * bx + e0.b[i] * by + e0.c[i] >= 0.0) & (e1.a[i] * bx + e1.b[i] * by + e1.c[i] >= 0.0) &
                             (e2.a[i] * bx + e2.b[i] * by + e2.c[i] >= 0.0);
            covered[i] |= int32_t(inA | inB);
        }
    }
    for (int i = 0; i < count; ++i)
        verdicts[i] = CullVerdict(testSamples[i] & !covered[i] ? int32_t(CullVerdict::NoSamples) : verdict[i]);
}

}  // namespace

void cullTrianglesOnTarget(const TriangleLanes& lanes, int count, const SetupContext& context, CullVerdict* verdicts) {
    cullChunk(lanes, count, context, verdicts);
}

}  // namespace HWY_NAMESPACE
}  // namespace cuberille::raster
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace cuberille::raster {

HWY_EXPORT(cullTrianglesOnTarget);

void cullTriangles(const TriangleLanes& lanes, int count, const SetupContext& context, CullVerdict* verdicts) {
    HWY_DYNAMIC_DISPATCH(cullTrianglesOnTarget)(lanes, count, context, verdicts);
}

}  // namespace cuberille::raster
#endif  // HWY_ONCE
