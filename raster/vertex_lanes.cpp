#include "raster/vertex_lanes.h"

#include <algorithm>
#include <bit>

// Compiled once per instruction set (see raster/tile_raster.cpp for how foreach_target.h works):
// the loops below are plain loops over lanes of one element type each, which GCC vectorises for
// each target (-fopt-info-vec).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "raster/vertex_lanes.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace cuberille::raster {
namespace HWY_NAMESPACE {
namespace {

constexpr int N = kVertexChunkVertices;

/// One chunk's clip positions, then what post-transform derives from them.
struct VertexChunkLanes {
    float x[N], y[N], z[N], w[N];
    int32_t code[N];  // outcode, or kInvalidVertex
    int32_t snappedX[N], snappedY[N];
    float depth[N], invW[N];
};

void transform(const float* xyz, int count, const VertexTransform& t, VertexChunkLanes& l);
void outcodes(int count, const VertexTransform& t, VertexChunkLanes& l);
void project(int count, const VertexTransform& t, VertexChunkLanes& l);

void transformAndProjectChunk(const float* xyz, int count, const VertexTransform& t, glm::vec4* clipPositions,
                              uint8_t* outcodesOut, WindowVertex* window) {
    alignas(64) VertexChunkLanes l;
    transform(xyz, count, t, l);
    outcodes(count, t, l);
    project(count, t, l);
    for (int i = 0; i < count; ++i) {
        clipPositions[i] = glm::vec4(l.x[i], l.y[i], l.z[i], l.w[i]);
        outcodesOut[i] = uint8_t(l.code[i]);
        if (l.code[i] == 0) window[i] = WindowVertex{l.snappedX[i], l.snappedY[i], l.depth[i], l.invW[i]};
    }
}

/// std::isfinite on the bits: the exponent is not all ones.
inline int32_t finite(float v) { return (std::bit_cast<uint32_t>(v) & 0x7f800000u) != 0x7f800000u; }

/// glm's mat4 * vec4(p, 1), in its order: (m0 x + m1 y) + (m2 z + m3 w), with w = 1.
void transform(const float* xyz, int count, const VertexTransform& t, VertexChunkLanes& l) {
    if (t.window) {
        for (int i = 0; i < count; ++i) {
            l.x[i] = xyz[3 * i], l.y[i] = xyz[3 * i + 1], l.z[i] = xyz[3 * i + 2];
            l.w[i] = 1.0f;
        }
        return;
    }
    float* out[4] = {l.x, l.y, l.z, l.w};
    for (int r = 0; r < 4; ++r) {
        const float m0 = t.m[0][r], m1 = t.m[1][r], m2 = t.m[2][r], m3 = t.m[3][r];
        float* __restrict o = out[r];
        for (int i = 0; i < count; ++i)
            o[i] = (m0 * xyz[3 * i] + m1 * xyz[3 * i + 1]) + (m2 * xyz[3 * i + 2] + m3 * 1.0f);
    }
}

/// clip.cpp's outcode(): bit k where !(planeDistance >= 0); kInvalidVertex where a coordinate
/// is not finite (the scalar stage tests that first).
void outcodes(int count, const VertexTransform& t, VertexChunkLanes& l) {
    for (int i = 0; i < count; ++i) l.code[i] = 0;
    for (int k = 0; k < ClipVolume::kPlaneCount; ++k) {
        const float a = t.plane[k][0], b = t.plane[k][1], c = t.plane[k][2], d = t.plane[k][3];
        for (int i = 0; i < count; ++i) {
            float distance = a * l.x[i] + b * l.y[i] + c * l.z[i] + d * l.w[i];
            if (k == ClipVolume::kMinWPlane) distance = distance - kMinClipW;
            l.code[i] |= int32_t(!(distance >= 0.0f)) << k;
        }
    }
    for (int i = 0; i < count; ++i) {
        const int32_t allFinite = finite(l.x[i]) & finite(l.y[i]) & finite(l.z[i]) & finite(l.w[i]);
        l.code[i] = allFinite ? l.code[i] : int32_t(kInvalidVertex);
    }
}

/// projectToWindow() for the lanes inside the clip volume: the divide, the viewport transform,
/// snapToSubpixels() (inlined here, so vectorised) and the depth clamp; a lane whose result is
/// not finite becomes kInvalidVertex. Other lanes snap 0, so no conversion sees a value out of
/// range.
void project(int count, const VertexTransform& t, VertexChunkLanes& l) {
    for (int i = 0; i < count; ++i) {
        const float invW = 1.0f / l.w[i];
        const float x = l.x[i] * invW * t.scaleX + t.offsetX;
        const float y = l.y[i] * invW * t.scaleY + t.offsetY;
        const float z = l.z[i] * invW;
        const int32_t usable = (l.code[i] == 0) & finite(x) & finite(y) & finite(z) & finite(invW);
        l.snappedX[i] = snapToSubpixels(usable ? x : 0.0f);
        l.snappedY[i] = snapToSubpixels(usable ? y : 0.0f);
        l.depth[i] = z < 0.0f ? 0.0f : (1.0f < z ? 1.0f : z);  // std::clamp(z, 0, 1)
        l.invW[i] = invW;
        l.code[i] = (l.code[i] == 0 && !usable) ? int32_t(kInvalidVertex) : l.code[i];
    }
}

}  // namespace

void transformAndProjectOnTarget(const float* xyz, size_t count, const VertexTransform& t, glm::vec4* clipPositions,
                                 uint8_t* outcodes, WindowVertex* window) {
    for (size_t first = 0; first < count; first += N) {
        const int n = int(std::min<size_t>(N, count - first));
        transformAndProjectChunk(xyz + 3 * first, n, t, clipPositions + first, outcodes + first, window + first);
    }
}

}  // namespace HWY_NAMESPACE
}  // namespace cuberille::raster
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace cuberille::raster {

HWY_EXPORT(transformAndProjectOnTarget);

void transformAndProjectVertices(std::span<const glm::vec3> positions, PositionSpace space, const glm::mat4& clipFromObject,
                                 const ClipVolume& volume, const SetupContext& viewport, size_t begin, size_t end,
                                 glm::vec4* clipPositions, uint8_t* outcodes, WindowVertex* window) {
    static_assert(sizeof(glm::vec3) == 3 * sizeof(float));
    VertexTransform t{};
    t.window = space == PositionSpace::Window;
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) t.m[c][r] = clipFromObject[c][r];
    for (int k = 0; k < ClipVolume::kPlaneCount; ++k)
        for (int j = 0; j < 4; ++j) t.plane[k][j] = volume.planes[k][j];
    t.scaleX = viewport.viewportScale.x, t.scaleY = viewport.viewportScale.y;
    t.offsetX = viewport.viewportOffset.x, t.offsetY = viewport.viewportOffset.y;
    if (end <= begin) return;
    HWY_DYNAMIC_DISPATCH(transformAndProjectOnTarget)(&positions[begin].x, end - begin, t, clipPositions + begin,
                                                      outcodes + begin, window + begin);
}

}  // namespace cuberille::raster
#endif  // HWY_ONCE
