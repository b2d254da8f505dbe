#include "raster/setup.h"

#include <algorithm>
#include <cmath>

#include "raster/fine.h"

namespace cuberille::raster {
namespace {

// floor(a / 256) and ceil(a / 256): C++20 defines >> on negative values as arithmetic.
int64_t floorPixels(int64_t subpixels) { return subpixels >> kSubpixelBits; }
int64_t ceilPixels(int64_t subpixels) { return -((-subpixels) >> kSubpixelBits); }

// Top-left rule (DESIGN.md): with the inside at E >= 0 and y down, a left edge has A > 0 and a
// top edge is horizontal (A = 0) with B > 0. Samples exactly on any other edge are outside.
int8_t fillBias(int32_t a, int32_t b) { return (a > 0 || (a == 0 && b > 0)) ? 0 : -1; }

void setEdge(TriangleSetup& t, int k, const WindowVertex& from, const WindowVertex& to) {
    const int32_t a = from.y - to.y;
    const int32_t b = to.x - from.x;
    t.edgeA[k] = a;
    t.edgeB[k] = b;
    t.fillBias[k] = fillBias(a, b);
    t.edgeC[k] = -(int64_t{a} * from.x + int64_t{b} * from.y) + t.fillBias[k];
}

// Pixels whose sample span [p*256 + 128 + min*16, p*256 + 128 + max*16] meets [lo, hi].
void samplePixelRange(int32_t lo, int32_t hi, int minOffset, int maxOffset, int32_t& first,
                      int32_t& last) {
    const int64_t centre = kPixelCentreSubpixels;
    first = static_cast<int32_t>(ceilPixels(lo - centre - int64_t{maxOffset} * kSampleOffsetUnitSubpixels));
    last = static_cast<int32_t>(floorPixels(hi - centre - int64_t{minOffset} * kSampleOffsetUnitSubpixels));
}

void setDepthPlane(TriangleSetup& t, const WindowVertex& v0, const WindowVertex& v1,
                   const WindowVertex& v2, double invDoubleArea) {
    const double dx1 = v1.x - v0.x, dy1 = v1.y - v0.y;
    const double dx2 = v2.x - v0.x, dy2 = v2.y - v0.y;
    const double dz1 = double(v1.z) - v0.z, dz2 = double(v2.z) - v0.z;
    t.originXSubpixels = v0.x;
    t.originYSubpixels = v0.y;
    t.depthAtOrigin = v0.z;
    t.depthPerSubpixelX = static_cast<float>((dz1 * dy2 - dz2 * dy1) * invDoubleArea);
    t.depthPerSubpixelY = static_cast<float>((dz2 * dx1 - dz1 * dx2) * invDoubleArea);
}

/// Whether a triangle whose pixel bounds hold at most kSetupCoverageTestPixels pixels covers
/// any of their samples: the fine stage's test (fine.h), evaluated here once so that a triangle
/// falling between sample positions, the common case in dense meshes, is never stored or binned.
bool coversAnySample(const TriangleSetup& t, const SamplePattern& sp) {
    for (int32_t y = t.pixelMinY; y <= t.pixelMaxY; ++y)
        for (int32_t x = t.pixelMinX; x <= t.pixelMaxX; ++x) {
            int64_t centre[3];
            edgesAtPixelCentre(t, x, y, centre);
            for (int s = 0; s < sp.count; ++s) {
                int64_t any = 0;
                for (int k = 0; k < 3; ++k) any |= centre[k] + sampleEdgeOffset(t, sp, k, s);
                if (any >= 0) return true;
            }
        }
    return false;
}

}  // namespace

SetupContext SetupContext::forDraw(PositionSpace space, int widthPixels, int heightPixels,
                                   const SamplePattern& samples, CullMode cull,
                                   int varyingCount) {
    SetupContext c;
    if (space == PositionSpace::Clip) {
        // Direct3D viewport: x = (ndc + 1) W/2, y = (1 - ndc) H/2.
        c.viewportScale = {widthPixels * 0.5f, -heightPixels * 0.5f};
        c.viewportOffset = {widthPixels * 0.5f, heightPixels * 0.5f};
    }
    c.scissorWidth = widthPixels;
    c.scissorHeight = heightPixels;
    c.samples = &samples;
    c.cull = cull;
    c.varyingCount = varyingCount;
    return c;
}

bool projectToWindow(const glm::vec4& p, const SetupContext& c, WindowVertex& out) {
    const float invW = 1.0f / p.w;
    const float x = p.x * invW * c.viewportScale.x + c.viewportOffset.x;
    const float y = p.y * invW * c.viewportScale.y + c.viewportOffset.y;
    const float z = p.z * invW;
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z) || !std::isfinite(invW))
        return false;
    out.x = snapToSubpixels(x);
    out.y = snapToSubpixels(y);
    out.z = std::clamp(z, 0.0f, 1.0f);  // clipping leaves rounding-sized excursions only
    out.invW = invW;
    return true;
}

SetupResult setupTriangle(const WindowVertex& w0, const WindowVertex& w1, const WindowVertex& w2,
                          const SetupContext& context, TriangleSetup& t, int order[3]) {
    WindowVertex v[3] = {w0, w1, w2};
    int input[3] = {0, 1, 2};

    int64_t doubleArea = int64_t{v[1].x - v[0].x} * (v[2].y - v[0].y) -
                         int64_t{v[2].x - v[0].x} * (v[1].y - v[0].y);
    if (doubleArea == 0) return SetupResult::Degenerate;

    // doubleArea > 0 is clockwise on screen (y down), i.e. back-facing for CCW-front.
    const bool frontFacing = doubleArea < 0;
    if ((context.cull == CullMode::Back && !frontFacing) ||
        (context.cull == CullMode::Front && frontFacing))
        return SetupResult::Culled;
    if (doubleArea < 0) {
        std::swap(v[1], v[2]);
        std::swap(input[1], input[2]);
        doubleArea = -doubleArea;
    }

    const SamplePattern& sp = *context.samples;
    int32_t minX = std::min({v[0].x, v[1].x, v[2].x}), maxX = std::max({v[0].x, v[1].x, v[2].x});
    int32_t minY = std::min({v[0].y, v[1].y, v[2].y}), maxY = std::max({v[0].y, v[1].y, v[2].y});
    samplePixelRange(minX, maxX, sp.minDx, sp.maxDx, t.pixelMinX, t.pixelMaxX);
    samplePixelRange(minY, maxY, sp.minDy, sp.maxDy, t.pixelMinY, t.pixelMaxY);
    t.pixelMinX = std::max(t.pixelMinX, 0);
    t.pixelMinY = std::max(t.pixelMinY, 0);
    t.pixelMaxX = std::min(t.pixelMaxX, context.scissorWidth - 1);
    t.pixelMaxY = std::min(t.pixelMaxY, context.scissorHeight - 1);
    if (context.rejectWithoutSamples && (t.pixelMinX > t.pixelMaxX || t.pixelMinY > t.pixelMaxY))
        return SetupResult::NoSamples;

    setEdge(t, 0, v[1], v[2]);
    setEdge(t, 1, v[2], v[0]);
    setEdge(t, 2, v[0], v[1]);
    const int64_t boundsPixels = int64_t{t.pixelMaxX - t.pixelMinX + 1} * (t.pixelMaxY - t.pixelMinY + 1);
    if (context.rejectWithoutSamples && boundsPixels <= kSetupCoverageTestPixels && !coversAnySample(t, sp))
        return SetupResult::NoSamples;
    t.invDoubleArea = 1.0 / static_cast<double>(doubleArea);
    setDepthPlane(t, v[0], v[1], v[2], t.invDoubleArea);
    t.depthKeySign = context.depthKeySign;
    t.backFacing = !frontFacing;
    for (int k = 0; k < 3; ++k) {
        t.invW[k] = v[k].invW;
        order[k] = input[k];
    }
    return SetupResult::Accepted;
}

}  // namespace cuberille::raster
