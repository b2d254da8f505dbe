// The shade stage's entry for one queue, per instruction set: shadeQueue() converts the queue's
// 64-bit edge values to the float weight numerators shade() reads (raster/shade.h), in vector
// lanes, then runs the shading model. Included by each file that compiles a back end per target
// (raster/tile_raster.cpp, raster/visibility_shade_tile.cpp), once per target, as Highway's
// -inl.h headers are, so both back ends shade through the same code and no caller of shade() can
// leave the numerators unconverted.
//
// Why the conversion is its own step: shade() is written as plain loops the compiler vectorises,
// and a conversion from int64 to float has no vector instruction before AVX-512, so a loop that
// made it stayed scalar — the perspective weights and the texture coordinates' derivatives (three
// points a pixel, nine conversions and three divisions) ran a pixel at a time, a third of a
// textured model's shade stage. Converted here first, those loops read floats and vectorise.
//
// The same bits as the scalar conversion, on every target: an edge value is below 2^51 in
// magnitude (raster/limits.h), and with a pixel's step (|A|·256, |B|·256 < 2^33) below 2^52, so
// its conversion to double is exact, and the one rounding, double to float, is the rounding
// float(int64) makes.

#if defined(CUBERILLE_RASTER_SHADE_QUEUE_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef CUBERILLE_RASTER_SHADE_QUEUE_INL_H_
#undef CUBERILLE_RASTER_SHADE_QUEUE_INL_H_
#else
#define CUBERILLE_RASTER_SHADE_QUEUE_INL_H_
#endif

#include <cstdint>

#include <hwy/highway.h>

#include "raster/limits.h"
#include "raster/setup.h"
#include "raster/shade.h"
#include "raster/stats.h"

HWY_BEFORE_NAMESPACE();
namespace cuberille::raster {
namespace HWY_NAMESPACE {
namespace {

/// out[i] = float(edge[i] + offset) for i < count. Whole vectors: the lanes past `count` (up to
/// the queue's capacity, a multiple of every target's lanes) are converted too, and never read.
HWY_INLINE void convertEdgesToFloat(const int64_t* HWY_RESTRICT edge, int count, int64_t offset,
                                    float* HWY_RESTRICT out) {
    namespace hn = hwy::HWY_NAMESPACE;
    const hn::ScalableTag<int64_t> d64;
    const hn::Rebind<double, decltype(d64)> dd;
    const hn::Rebind<float, decltype(d64)> df;
    static_assert(ShadeQueue::kCapacity % (HWY_MAX_BYTES / sizeof(int64_t)) == 0, "whole vectors fit the queue");
    const auto add = hn::Set(d64, offset);
    const int lanes = int(hn::Lanes(d64));
    for (int i = 0; i < count; i += lanes)
        hn::StoreU(hn::DemoteTo(df, hn::ConvertTo(dd, hn::Add(hn::LoadU(d64, edge + i), add))), df, out + i);
}

/// The numerators `shader` reads (ShadeQueue::numerator and, where it differences texture
/// coordinates, numeratorRight and numeratorDown), for the queue's pixels of triangle `t`.
template <class Shader>
HWY_INLINE void convertWeightNumerators(const Shader& shader, const TriangleSetup& t, ShadeQueue& q) {
    if (!shader.readsWeightNumerators()) return;
    const int64_t* edges[3] = {q.edge0, q.edge1, q.edge2};
    for (int k = 0; k < 3; ++k) convertEdgesToFloat(edges[k], q.count, -int64_t{t.fillBias[k]}, q.numerator[k]);
    if (!shader.differencesTexCoords()) return;
    for (int k = 0; k < 3; ++k) {
        const int64_t right = int64_t{t.edgeA[k]} * kSubpixelsPerPixel, down = int64_t{t.edgeB[k]} * kSubpixelsPerPixel;
        convertEdgesToFloat(edges[k], q.count, right - t.fillBias[k], q.numeratorRight[k]);
        convertEdgesToFloat(edges[k], q.count, down - t.fillBias[k], q.numeratorDown[k]);
    }
}

/// The shade stage of one queue, compiled for this copy's instruction set: flatten inlines the
/// shading model's passes (shade.h) into it. One copy per model and target, shared by every
/// sample count; a shading model is too large to inline into each of them.
template <class Shader>
[[gnu::noinline, gnu::flatten]] void shadeQueue(const Shader& shader, const TriangleSetup& t, const float* varyings,
                                                ShadeQueue& queue, StageCounters& counters) {
    convertWeightNumerators(shader, t, queue);
    shader.shade(t, varyings, queue, counters);
}

/// Appends a pixel of triangle `t` to a queue an InterpolatedQueue shades (raster/shade.h), with
/// the weight numerators `shader` reads converted now: the scalar conversion of
/// convertWeightNumerators(), the same integers and one rounding, so the same floats. The queue
/// must have room.
template <class Shader>
HWY_INLINE void queueForInterpolation(const Shader& shader, const TriangleSetup& t, const int64_t centreEdges[3],
                                      uint32_t firstSample, uint32_t passMask, uint32_t pixelIndex, ShadeQueue& q) {
    const int i = q.count++;
    for (int k = 0; k < 3; ++k) q.numerator[k][i] = float(centreEdges[k] - int64_t{t.fillBias[k]});
    if (shader.differencesTexCoords())
        for (int k = 0; k < 3; ++k) {
            const int64_t e = centreEdges[k] - int64_t{t.fillBias[k]};
            q.numeratorRight[k][i] = float(e + int64_t{t.edgeA[k]} * kSubpixelsPerPixel);
            q.numeratorDown[k][i] = float(e + int64_t{t.edgeB[k]} * kSubpixelsPerPixel);
        }
    q.firstSample[i] = firstSample;
    q.passMask[i] = passMask;
    q.pixelIndex[i] = pixelIndex;
}

/// A triangle's half of an InterpolatedQueue (raster/shade.h): the attributes of its pixels,
/// queued from `begin` on. Its numerators were converted as its pixels were queued.
template <class Shader>
[[gnu::noinline, gnu::flatten]] void interpolateQueueRange(const Shader& shader, const TriangleSetup& t, const float* varyings,
                                                           typename Shader::InterpolatedQueue& queue, int begin,
                                                           StageCounters& counters) {
    shader.interpolateAttributes(t, varyings, queue.pixels, begin, queue.attributes, counters);
}

/// The lights' half of an InterpolatedQueue, over every pixel it holds.
template <class Shader>
[[gnu::noinline, gnu::flatten]] void shadeInterpolatedQueue(const Shader& shader, typename Shader::InterpolatedQueue& queue,
                                                            StageCounters& counters) {
    shader.shadeInterpolated(queue.pixels, queue.attributes, counters);
    queue.forgetFetches();
}

}  // namespace
}  // namespace HWY_NAMESPACE
}  // namespace cuberille::raster
HWY_AFTER_NAMESPACE();

#endif  // include guard per target
