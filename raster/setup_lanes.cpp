#include "raster/setup_lanes.h"

#include <algorithm>

// Compiled once per instruction set (see raster/tile_raster.cpp for how foreach_target.h works):
// the loops below are plain loops over lanes, each kept to one or two element types so that GCC
// vectorises it for each target (-fopt-info-vec).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "raster/setup_lanes.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace cuberille::raster {
namespace HWY_NAMESPACE {
namespace {

constexpr int N = kSetupChunkTriangles;

/// Set-up vertex order: v0 as submitted, v1 and v2 swapped for a front-facing lane.
struct OrderedLanes {
    int32_t x1[N], y1[N], x2[N], y2[N];
};

void facingAndArea(const TriangleLanes& in, int count, SetupLanes& out, int32_t* degenerate);
void boundsAndVerdicts(const TriangleLanes& in, int count, const SetupContext& context, SetupLanes& out,
                       const int32_t* degenerate, OrderedLanes& v, int32_t* verdict, int32_t* testSamples);
void edges(const TriangleLanes& in, const OrderedLanes& v, int count, SetupLanes& out);
void coverageOfFewPixels(const SetupLanes& out, int count, const SamplePattern& sp, int32_t* covered);
void depthPlanes(const TriangleLanes& in, const OrderedLanes& v, int count, SetupLanes& out);

void setUpChunk(const TriangleLanes& in, int count, const SetupContext& context, SetupLanes& out) {
    alignas(64) int32_t degenerate[N], verdict[N], testSamples[N], covered[N];
    alignas(64) OrderedLanes v;
    facingAndArea(in, count, out, degenerate);
    boundsAndVerdicts(in, count, context, out, degenerate, v, verdict, testSamples);
    edges(in, v, count, out);
    coverageOfFewPixels(out, count, *context.samples, covered);
    depthPlanes(in, v, count, out);
    for (int i = 0; i < count; ++i)
        out.verdict[i] = SetupResult((testSamples[i] & !covered[i]) ? int32_t(SetupResult::NoSamples) : verdict[i]);
}

/// The doubled signed area from the snapped vertices (exact in double); its sign is the
/// facing, and 1 / |area| scales the depth plane and the barycentrics.
void facingAndArea(const TriangleLanes& in, int count, SetupLanes& out, int32_t* degenerate) {
    for (int i = 0; i < count; ++i) {
        const int32_t X0 = in.x[0][i], Y0 = in.y[0][i];
        const double doubleArea = double(in.x[1][i] - X0) * double(in.y[2][i] - Y0) -
                                  double(in.x[2][i] - X0) * double(in.y[1][i] - Y0);
        out.frontFacing[i] = doubleArea < 0.0;
        degenerate[i] = doubleArea == 0.0;
        out.invDoubleArea[i] = 1.0 / (doubleArea < 0.0 ? -doubleArea : doubleArea);
    }
}

/// Pixel bounds (setup.cpp's samplePixelRange, clamped to the scissor) and the verdict in
/// setupTriangle's order of checks, written as selects.
void boundsAndVerdicts(const TriangleLanes& in, int count, const SetupContext& context, SetupLanes& out,
                       const int32_t* degenerate, OrderedLanes& v, int32_t* verdict, int32_t* testSamples) {
    const SamplePattern& sp = *context.samples;
    const int32_t cullBack = context.cull == CullMode::Back, cullFront = context.cull == CullMode::Front;
    const int32_t lowX = kPixelCentreSubpixels + sp.maxDx * kSampleOffsetUnitSubpixels;
    const int32_t highX = kPixelCentreSubpixels + sp.minDx * kSampleOffsetUnitSubpixels;
    const int32_t lowY = kPixelCentreSubpixels + sp.maxDy * kSampleOffsetUnitSubpixels;
    const int32_t highY = kPixelCentreSubpixels + sp.minDy * kSampleOffsetUnitSubpixels;
    for (int i = 0; i < count; ++i) {
        const int32_t X0 = in.x[0][i], Y0 = in.y[0][i], X1 = in.x[1][i], Y1 = in.y[1][i];
        const int32_t X2 = in.x[2][i], Y2 = in.y[2][i];
        const int32_t front = out.frontFacing[i];  // 0 or 1
        v.x1[i] = front ? X2 : X1, v.y1[i] = front ? Y2 : Y1;
        v.x2[i] = front ? X1 : X2, v.y2[i] = front ? Y1 : Y2;

        const int32_t minX = std::min(X0, std::min(X1, X2)), maxX = std::max(X0, std::max(X1, X2));
        const int32_t minY = std::min(Y0, std::min(Y1, Y2)), maxY = std::max(Y0, std::max(Y1, Y2));
        // ceil and floor of a division by 256: arithmetic shifts (C++20).
        const int32_t firstX = std::max(-((lowX - minX) >> kSubpixelBits), 0);
        const int32_t lastX = std::min((maxX - highX) >> kSubpixelBits, context.scissorWidth - 1);
        const int32_t firstY = std::max(-((lowY - minY) >> kSubpixelBits), 0);
        const int32_t lastY = std::min((maxY - highY) >> kSubpixelBits, context.scissorHeight - 1);
        out.pixelMinX[i] = firstX, out.pixelMinY[i] = firstY, out.pixelMaxX[i] = lastX, out.pixelMaxY[i] = lastY;
        const int32_t empty = int32_t(firstX > lastX) | int32_t(firstY > lastY);
        // Sides clamped to [0, 3] before the product: bounds far off screen on both axes would
        // overflow int32 (2^17 x 2^17), and only "at most 2 pixels" is asked.
        const int32_t width = std::clamp(lastX - firstX + 1, 0, 3), height = std::clamp(lastY - firstY + 1, 0, 3);
        const int32_t few = (1 - empty) & int32_t(width * height <= kSetupCoverageTestPixels);

        const int32_t culled = (cullBack & (1 - front)) | (cullFront & front);
        int32_t r = empty ? int32_t(SetupResult::NoSamples) : int32_t(SetupResult::Accepted);
        r = culled ? int32_t(SetupResult::Culled) : r;
        r = degenerate[i] ? int32_t(SetupResult::Degenerate) : r;
        verdict[i] = r;
        testSamples[i] = int32_t(r == int32_t(SetupResult::Accepted)) & few;
    }
}

/// Edge k of every lane, as setup.cpp's setEdge() makes it: from vertex `from` to `to`, inside
/// at E >= 0, the top-left rule's bias in C.
void edge(const int32_t* __restrict fromX, const int32_t* __restrict fromY, const int32_t* __restrict toX,
          const int32_t* __restrict toY, int count, int32_t* __restrict edgeA, int32_t* __restrict edgeB,
          double* __restrict edgeC, int32_t* __restrict fillBias) {
    for (int i = 0; i < count; ++i) {
        const int32_t a = fromY[i] - toY[i];
        const int32_t b = toX[i] - fromX[i];
        const int32_t bias = (a > 0) | ((a == 0) & (b > 0)) ? 0 : -1;
        edgeA[i] = a, edgeB[i] = b, fillBias[i] = bias;
        edgeC[i] = -(double(a) * fromX[i] + double(b) * fromY[i]) + bias;
    }
}

void edges(const TriangleLanes& in, const OrderedLanes& v, int count, SetupLanes& out) {
    edge(v.x1, v.y1, v.x2, v.y2, count, out.edgeA[0], out.edgeB[0], out.edgeC[0], out.fillBias[0]);
    edge(v.x2, v.y2, in.x[0], in.y[0], count, out.edgeA[1], out.edgeB[1], out.edgeC[1], out.fillBias[1]);
    edge(in.x[0], in.y[0], v.x1, v.y1, count, out.edgeA[2], out.edgeB[2], out.edgeC[2], out.fillBias[2]);
}

/// Whether any sample of a lane's first or last bounds pixel is inside all three edges: for
/// bounds of at most kSetupCoverageTestPixels (2) pixels these are all its pixels (one pixel,
/// or two side by side). Evaluated for every lane; only those with few pixels use it.
void coverageOfFewPixels(const SetupLanes& out, int count, const SamplePattern& sp, int32_t* covered) {
    static_assert(kSetupCoverageTestPixels == 2, "the coverage test visits a first and a last pixel");
    for (int i = 0; i < count; ++i) covered[i] = 0;
    for (int s = 0; s < sp.count; ++s) {
        const int32_t dx = kPixelCentreSubpixels + sp.dx[s] * kSampleOffsetUnitSubpixels;
        const int32_t dy = kPixelCentreSubpixels + sp.dy[s] * kSampleOffsetUnitSubpixels;
        for (int i = 0; i < count; ++i) {
            const double ax = double(out.pixelMinX[i] * kSubpixelsPerPixel + dx);
            const double ay = double(out.pixelMinY[i] * kSubpixelsPerPixel + dy);
            const double bx = double(out.pixelMaxX[i] * kSubpixelsPerPixel + dx);
            const double by = double(out.pixelMaxY[i] * kSubpixelsPerPixel + dy);
            int32_t inA = 1, inB = 1;
            for (int k = 0; k < 3; ++k) {
                const double a = out.edgeA[k][i], b = out.edgeB[k][i], c = out.edgeC[k][i];
                inA &= int32_t(a * ax + b * ay + c >= 0.0);
                inB &= int32_t(a * bx + b * by + c >= 0.0);
            }
            covered[i] |= inA | inB;
        }
    }
}

/// setup.cpp's setDepthPlane(), the same double operations in the same order.
void depthPlanes(const TriangleLanes& in, const OrderedLanes& v, int count, SetupLanes& out) {
    for (int i = 0; i < count; ++i) {
        const int32_t front = out.frontFacing[i];
        const float z0 = in.z[0][i], z1 = front ? in.z[2][i] : in.z[1][i], z2 = front ? in.z[1][i] : in.z[2][i];
        const double dx1 = v.x1[i] - in.x[0][i], dy1 = v.y1[i] - in.y[0][i];
        const double dx2 = v.x2[i] - in.x[0][i], dy2 = v.y2[i] - in.y[0][i];
        const double dz1 = double(z1) - z0, dz2 = double(z2) - z0;
        out.depthPerSubpixelX[i] = static_cast<float>((dz1 * dy2 - dz2 * dy1) * out.invDoubleArea[i]);
        out.depthPerSubpixelY[i] = static_cast<float>((dz2 * dx1 - dz1 * dx2) * out.invDoubleArea[i]);
    }
}

}  // namespace

void setUpLanesOnTarget(const TriangleLanes& in, int count, const SetupContext& context, SetupLanes& out) {
    setUpChunk(in, count, context, out);
}

}  // namespace HWY_NAMESPACE
}  // namespace cuberille::raster
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace cuberille::raster {

HWY_EXPORT(setUpLanesOnTarget);

void setUpLanes(const TriangleLanes& in, int count, const SetupContext& context, SetupLanes& out) {
    HWY_DYNAMIC_DISPATCH(setUpLanesOnTarget)(in, count, context, out);
}

void setupRecord(const TriangleLanes& in, const SetupLanes& lanes, int i, const SetupContext& context,
                 TriangleSetup& t, int order[3]) {
    const bool front = lanes.frontFacing[i] != 0;
    order[0] = 0, order[1] = front ? 2 : 1, order[2] = front ? 1 : 2;
    for (int k = 0; k < 3; ++k) {
        t.edgeA[k] = lanes.edgeA[k][i];
        t.edgeB[k] = lanes.edgeB[k][i];
        t.edgeC[k] = static_cast<int64_t>(lanes.edgeC[k][i]);
        t.fillBias[k] = static_cast<int8_t>(lanes.fillBias[k][i]);
        t.invW[k] = in.invW[order[k]][i];
    }
    t.backFacing = !front;
    t.pixelMinX = lanes.pixelMinX[i], t.pixelMinY = lanes.pixelMinY[i];
    t.pixelMaxX = lanes.pixelMaxX[i], t.pixelMaxY = lanes.pixelMaxY[i];
    t.originXSubpixels = in.x[0][i], t.originYSubpixels = in.y[0][i];
    t.depthAtOrigin = in.z[0][i];
    t.depthPerSubpixelX = lanes.depthPerSubpixelX[i];
    t.depthPerSubpixelY = lanes.depthPerSubpixelY[i];
    t.depthKeySign = context.depthKeySign;
    t.invDoubleArea = lanes.invDoubleArea[i];
}

}  // namespace cuberille::raster
#endif  // HWY_ONCE
