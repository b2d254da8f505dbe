#pragma once
// Triangle set-up: from three clipped vertices to the exact integer description the back end
// rasterizes.
//
// 1. Perspective divide and viewport transform to window space (pixels, y down).
// 2. Snap x and y to 1/256 pixel, rounding to nearest (ties to even), in exact double arithmetic.
// 3. The doubled signed area from the snapped vertices, in int64: zero-area triangles cover
//    nothing and stop here; its sign gives the facing for culling. Clockwise-on-screen order
//    is then enforced (swapping v1 and v2) so that the inside of every edge is E >= 0.
// 4. Three edge functions E_k = A_k X + B_k Y + C_k over sample positions in subpixels, edge k
//    opposite vertex k, with the top-left fill rule folded into C_k as a bias of 0 or -1: a
//    sample is covered iff all three biased values are >= 0 (DESIGN.md, fill rule).
//    A triangle whose bounds hold only a few pixels is tested against their samples here and
//    dropped when it covers none (SetupResult::NoSamples).
// 5. The depth plane over the snapped vertices, and 1/w per vertex for perspective-correct
//    interpolation at shading time.
//
// Thread-safety: a pure function of its inputs.

#include <cstdint>

#include <glm/glm.hpp>

#include "raster/clip.h"
#include "raster/draw.h"
#include "raster/sample_pattern.h"

namespace cuberille::raster {

struct TriangleSetup {
    int32_t edgeA[3];  // subpixels
    int32_t edgeB[3];
    int64_t edgeC[3];  // subpixels², fill-rule bias included
    int8_t fillBias[3];
    bool backFacing;  // clockwise on screen as submitted; double-sided lighting flips the normal

    // Inclusive pixel range whose samples can be covered, already clamped to the scissor.
    int32_t pixelMinX, pixelMinY, pixelMaxX, pixelMaxY;

    // Depth plane: z = depthAtOrigin + depthPerSubpixelX * (X - originX) + ... (Y - originY).
    int32_t originXSubpixels, originYSubpixels;
    float depthAtOrigin, depthPerSubpixelX, depthPerSubpixelY;
    float depthKeySign;  // +1 standard, -1 reversed: the stored key is this times the depth

    float invW[3];         // 1 / clip w per vertex, for perspective-correct barycentrics
    double invDoubleArea;  // 1 / (A·X + B·Y + C of edge k at vertex k), in 1/subpixels²
    uint32_t varyingOffset;  // into the batch's varyings: 3 vertices x varyingCount floats
    glm::vec4 flatColor;     // ConstantColor shading
};

enum class SetupResult : uint8_t {
    Accepted,
    Degenerate,  // zero area after snapping
    Culled,      // facing culled
    NoSamples,   // covers no sample position inside the scissor: none in its bounds, or, for
                 // bounds of at most kSetupCoverageTestPixels pixels, none inside its edges
};

/// Triangles whose pixel bounds hold at most this many pixels have their samples tested at
/// set-up: in a dense mesh most triangles fall between sample positions, and one rejected here
/// costs nothing more (no stored set-up, no bin entry, no back-end visit).
constexpr int kSetupCoverageTestPixels = 2;

struct SetupContext {
    // Window = ndc * scale + offset (x), with the y flip folded into scale.y.
    glm::vec2 viewportScale{1.0f}, viewportOffset{0.0f};
    int scissorWidth = 0, scissorHeight = 0;
    const SamplePattern* samples = nullptr;
    CullMode cull = CullMode::None;
    int varyingCount = 0;
    float depthKeySign = 1.0f;  // the framebuffer's DepthConvention
    /// False: a triangle is set up even where it covers no sample position (never
    /// SetupResult::NoSamples). For the deferred shade (raster/visibility_shade.h), whose samples
    /// an exact ray found inside a triangle that snapping moved off them.
    bool rejectWithoutSamples = true;

    static SetupContext forDraw(PositionSpace space, int widthPixels, int heightPixels,
                                const SamplePattern& samples, CullMode cull, int varyingCount);
};

/// Snaps a window coordinate to subpixels: round to nearest, ties to the even subpixel, exactly
/// (Direct3D's float-to-fixed-point rule). Inline, so the vertex stage's lanes
/// (raster/vertex_lanes.cpp) vectorise this very expression for each instruction set.
[[gnu::always_inline]] inline int32_t snapToSubpixels(float windowCoordinate) {
    // In double, v * 256 is exact for any float v, so the tie is seen exactly and broken to the
    // even subpixel, as Direct3D converts floats to fixed point (and llvmpipe's lrintf does): a
    // tie rounded up instead can collapse a thin sliver to zero area that the same vertices,
    // snapped as a GPU snaps them, give a non-zero one.
    //
    // The rounding is the one of double addition itself: adding 1.5 * 2^52 leaves no fraction
    // bits, so the sum is rounded to an integer by the current rounding mode, round to nearest,
    // ties to even (never changed in this program), and subtracting it again is exact. Valid for
    // |v * 256| < 2^51; clipping keeps vertices inside the guard band, below 2^24 subpixels
    // (raster/limits.h). Two additions instead of floor, a compare and branches: the baseline
    // x86-64 target has no SSE4.1 round instruction, and this ran for 7% of a dragon frame.
    constexpr double kRoundToIntegerBias = 6755399441055744.0;  // 1.5 * 2^52
    const double scaled = double(windowCoordinate) * kSubpixelsPerPixel;
    const double rounded = (scaled + kRoundToIntegerBias) - kRoundToIntegerBias;
    return static_cast<int32_t>(rounded);
}

/// A vertex after the perspective divide and the viewport transform, x and y snapped.
struct WindowVertex {
    int32_t x, y;  // subpixels
    float z;       // [0, 1]
    float invW;    // 1 / clip w
};

/// Projects a clip-space position that lies inside the clip volume; false when the result is
/// not finite.
bool projectToWindow(const glm::vec4& clipPosition, const SetupContext& context, WindowVertex& out);

/// On Accepted, fills `out` and sets order[0..2] to the input vertex each set-up vertex came
/// from (v1 and v2 swap for counter-clockwise input), so the caller copies varyings only for
/// triangles that survive.
SetupResult setupTriangle(const WindowVertex& v0, const WindowVertex& v1, const WindowVertex& v2,
                          const SetupContext& context, TriangleSetup& out, int order[3]);

}  // namespace cuberille::raster
