#include "raster/texture_lanes.h"

#include <algorithm>

#include "raster/texture.h"

// Compiled once per instruction set (see raster/tile_raster.cpp for how foreach_target.h works),
// with Highway's operations written out: gathers and per-lane levels are not loops GCC
// vectorises on its own.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "raster/texture_lanes.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/cache_control.h>
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace cuberille::raster {
namespace HWY_NAMESPACE {
namespace {

namespace hn = hwy::HWY_NAMESPACE;
using DF = hn::ScalableTag<float>;
using DI = hn::RebindToSigned<DF>;
using DU = hn::RebindToUnsigned<DF>;
using VF = hn::Vec<DF>;
using VI = hn::Vec<DI>;
using MF = hn::Mask<DF>;

struct Texel {
    VF r, g, b, a;
};

struct Footprint {
    VI index[4];  // (xa, ya), (xb, ya), (xa, yb), (xb, yb), as Texture::BilinearFootprint
    VF ax, ay;
};

HWY_INLINE Footprint footprint(const TexelPyramid& t, VI level, MF nearest, VF u, VF v);
HWY_INLINE Texel bilinear(const TexelPyramid& t, const Footprint& f);
HWY_INLINE Texel texelsAt(const TexelPyramid& t, VI index);
HWY_INLINE VF mix(VF a, VF b, VF weight);

/// The taps one vector of points reads under the texture's filters (Texture::plan): a level and
/// whether its tap is nearest, and for the mipmap-linear filters a second level and the weight.
struct LanePlan {
    VI first, second;
    MF nearest;     // nearest taps (magnification and minification may differ)
    MF mixLevels;   // lanes that mix the two levels
    VF weight;
};

HWY_INLINE LanePlan plan(const TexelPyramid& t, VF lod) {
    const DF df;
    const DI di;
    const TextureFilter& filter = t.filter;
    // lod <= 0 (and NaN) magnifies: level 0. Otherwise lod is clamped to the last level first.
    const MF minify = hn::Gt(lod, hn::Zero(df));
    const MF none = hn::FirstN(df, 0);
    const VF clamped = hn::IfThenElseZero(minify, hn::Min(lod, hn::Set(df, float(t.levelCount - 1))));
    const VI last = hn::Set(di, t.levelCount - 1);
    const bool minifyNearest = filter.minify == MinFilter::Nearest || filter.minify == MinFilter::NearestMipmapNearest ||
                               filter.minify == MinFilter::NearestMipmapLinear;
    const MF magnifyNearestLanes = filter.magnifyNearest ? hn::Not(minify) : none;
    LanePlan p;
    p.nearest = hn::Or(minifyNearest ? minify : none, magnifyNearestLanes);
    p.mixLevels = none;
    p.weight = hn::Zero(df);
    p.first = p.second = hn::Zero(di);
    switch (filter.minify) {
        case MinFilter::Nearest:
        case MinFilter::Linear: break;  // level 0
        case MinFilter::NearestMipmapNearest:
        case MinFilter::LinearMipmapNearest: {
            // OpenGL's nearest level, ceil(lod + 0.5) - 1: lod rounded with ties down.
            const VI rounded = hn::Sub(hn::ConvertTo(di, hn::Ceil(hn::Add(clamped, hn::Set(df, 0.5f)))), hn::Set(di, 1));
            p.first = hn::IfThenElseZero(hn::RebindMask(di, minify), hn::Min(rounded, last));
            break;
        }
        case MinFilter::NearestMipmapLinear:
        case MinFilter::LinearMipmapLinear: {
            p.first = hn::ConvertTo(di, clamped);  // clamped >= 0: truncation is floor
            p.weight = hn::Sub(clamped, hn::ConvertTo(df, p.first));
            p.second = hn::Min(hn::Add(p.first, hn::Set(di, 1)), last);
            // Nearest taps are always mixed; bilinear ones only between levels.
            p.mixLevels = hn::And(minify, minifyNearest ? minify : hn::Gt(p.weight, hn::Zero(df)));
            break;
        }
    }
    return p;
}

/// glm::mix's arithmetic: a (1 - weight) + b weight.
HWY_INLINE VF mix(VF a, VF b, VF weight) {
    const VF one = hn::Set(DF(), 1.0f);
    return hn::Add(hn::Mul(a, hn::Sub(one, weight)), hn::Mul(b, weight));
}

/// An integer texel coordinate f (held exactly in float) wrapped into [0, size).
HWY_INLINE VF wrap(VF f, VF size, WrapMode mode);
/// Where texel (x, y) of a level lies: the tile's row and column, then the texel in the tile.
HWY_INLINE VI tiledIndex(VI x, VI y, VI offset, VI tileRowStride);

/// A level's size and place in every lane.
struct LaneLevels {
    VI width, height, offset, tileRowStride;
};
HWY_INLINE LaneLevels levelsOf(const TexelPyramid& t, VI level);
/// Texel column (or row) f and the next one, wrapped.
HWY_INLINE void wrapPair(VF f, VF size, WrapMode mode, VI& first, VI& next);

HWY_INLINE Footprint footprint(const TexelPyramid& t, VI level, MF nearest, VF u, VF v) {
    const DF df;
    const LaneLevels levels = levelsOf(t, level);
    const VF w = hn::ConvertTo(df, levels.width), h = hn::ConvertTo(df, levels.height);
    // Texel space with texel centres on integers (a nearest tap's: texel corners on integers);
    // non-finite coordinates sample texel 0, and the rest are clamped far beyond any wrap
    // period (Texture::footprint, Texture::nearestIndex).
    const VF half = hn::IfThenZeroElse(nearest, hn::Set(df, 0.5f));
    VF x = hn::Sub(hn::Mul(u, w), half), y = hn::Sub(hn::Mul(v, h), half);
    const MF finite = hn::And(hn::IsFinite(x), hn::IsFinite(y));
    const VF lo = hn::Set(df, -1e6f), hi = hn::Set(df, 1e6f);
    x = hn::Min(hn::Max(hn::IfThenElseZero(finite, x), lo), hi);
    y = hn::Min(hn::Max(hn::IfThenElseZero(finite, y), lo), hi);
    const VF fx = hn::Floor(x), fy = hn::Floor(y);
    VI xa, xb, ya, yb;
    wrapPair(fx, w, t.wrapU, xa, xb);
    wrapPair(fy, h, t.wrapV, ya, yb);
    const VI offset = levels.offset, stride = levels.tileRowStride;
    return {{tiledIndex(xa, ya, offset, stride), tiledIndex(xb, ya, offset, stride), tiledIndex(xa, yb, offset, stride),
             tiledIndex(xb, yb, offset, stride)},
            hn::IfThenZeroElse(nearest, hn::Sub(x, fx)),
            hn::IfThenZeroElse(nearest, hn::Sub(y, fy))};
}

/// Neighbouring points mostly read one level (a shade queue holds pixels of one triangle, often
/// of one tile): then its four values are loaded once and broadcast, not gathered per lane.
HWY_INLINE LaneLevels levelsOf(const TexelPyramid& t, VI level) {
    const DI di;
    const int32_t first = hn::GetLane(level);
    if (hn::AllTrue(di, hn::Eq(level, hn::Set(di, first))))
        return {hn::Set(di, t.width[first]), hn::Set(di, t.height[first]), hn::Set(di, t.offset[first]),
                hn::Set(di, t.tileRowStride[first])};
    return {hn::GatherIndex(di, t.width, level), hn::GatherIndex(di, t.height, level), hn::GatherIndex(di, t.offset, level),
            hn::GatherIndex(di, t.tileRowStride, level)};
}

/// Under Repeat the next texel is the wrapped one plus one, back to 0 at the period: (f + 1) mod n
/// = ((f mod n) + 1) mod n, and modulo() is exact, so this is wrap(f + 1) without a second
/// modulo. The other modes wrap both (a clamp is cheaper than the test).
HWY_INLINE void wrapPair(VF f, VF size, WrapMode mode, VI& first, VI& next) {
    const DF df;
    const DI di;
    const VF a = wrap(f, size, mode);
    first = hn::ConvertTo(di, a);
    if (mode == WrapMode::Repeat) {
        const VF b = hn::Add(a, hn::Set(df, 1.0f));
        next = hn::ConvertTo(di, hn::IfThenZeroElse(hn::Eq(b, size), b));
    } else {
        next = hn::ConvertTo(di, wrap(hn::Add(f, hn::Set(df, 1.0f)), size, mode));
    }
}

/// f mod period for integers held in float: the quotient from a rounded reciprocal is off by at
/// most one (|f| <= 1e6 + 1, so the relative error 2^-22 of f / period is below 1/4 of a
/// period), which one step either way corrects; every product and difference is an integer
/// below 2^24, so exact.
HWY_INLINE VF modulo(VF f, VF period) {
    const DF df;
    // Coordinates inside one period (a texture not tiled across the triangle) are their own
    // remainder: the same value the steps below compute, without the division.
    if (hn::AllTrue(df, hn::And(hn::Ge(f, hn::Zero(df)), hn::Lt(f, period)))) return f;
    const VF quotient = hn::Floor(hn::Mul(f, hn::Div(hn::Set(df, 1.0f), period)));
    VF m = hn::Sub(f, hn::Mul(period, quotient));
    m = hn::IfThenElse(hn::Lt(m, hn::Zero(df)), hn::Add(m, period), m);
    return hn::IfThenElse(hn::Ge(m, period), hn::Sub(m, period), m);
}

HWY_INLINE VF wrap(VF f, VF size, WrapMode mode) {
    const DF df;
    switch (mode) {
        case WrapMode::ClampToEdge: return hn::Min(hn::Max(f, hn::Zero(df)), hn::Sub(size, hn::Set(df, 1.0f)));
        case WrapMode::Repeat: return modulo(f, size);
        case WrapMode::MirroredRepeat: {
            const VF period = hn::Add(size, size);
            const VF m = modulo(f, period);
            return hn::IfThenElse(hn::Lt(m, size), m, hn::Sub(hn::Sub(period, hn::Set(df, 1.0f)), m));
        }
    }
    return hn::Zero(df);
}

HWY_INLINE VI tiledIndex(VI x, VI y, VI offset, VI tileRowStride) {
    const DI di;
    const VI three = hn::Set(di, 3);
    const VI column = hn::Add(hn::ShiftLeft<4>(hn::ShiftRight<2>(x)), hn::And(x, three));
    const VI row = hn::Add(hn::Mul(hn::ShiftRight<2>(y), tileRowStride), hn::ShiftLeft<2>(hn::And(y, three)));
    return hn::Add(hn::Add(offset, row), column);
}

/// One texel per lane, decoded as Texture::texelAt decodes: linear bytes as b / 255 (computed,
/// the value its table holds), sRGB colour bytes through the table (gathered: a gather is the
/// slow part of a fetch, so only the three sRGB channels pay for one).
HWY_INLINE VF unorm8(VI byte) { return hn::Div(hn::ConvertTo(DF(), byte), hn::Set(DF(), 255.0f)); }

HWY_INLINE Texel texelsAt(const TexelPyramid& t, VI index) {
    const DF df;
    const DI di;
    const DU du;
    const VI packed = hn::BitCast(di, hn::GatherIndex(du, t.packed, index));
    const VI byte = hn::Set(di, 0xFF);
    const VI r = hn::And(packed, byte), g = hn::And(hn::ShiftRight<8>(packed), byte);
    const VI b = hn::And(hn::ShiftRight<16>(packed), byte);
    const VF alpha = unorm8(hn::BitCast(di, hn::ShiftRight<24>(hn::BitCast(du, packed))));
    if (!t.srgb) return {unorm8(r), unorm8(g), unorm8(b), alpha};
    return {hn::GatherIndex(df, t.decodeRgb, r), hn::GatherIndex(df, t.decodeRgb, g), hn::GatherIndex(df, t.decodeRgb, b),
            alpha};
}

/// Texture::blend: the top pair and the bottom pair mixed across, then the two down.
HWY_INLINE Texel bilinear(const TexelPyramid& t, const Footprint& f) {
    const Texel t00 = texelsAt(t, f.index[0]), t10 = texelsAt(t, f.index[1]);
    const Texel t01 = texelsAt(t, f.index[2]), t11 = texelsAt(t, f.index[3]);
    auto channel = [&](VF Texel::* c) {
        return mix(mix(t00.*c, t10.*c, f.ax), mix(t01.*c, t11.*c, f.ax), f.ay);
    };
    return {channel(&Texel::r), channel(&Texel::g), channel(&Texel::b), channel(&Texel::a)};
}

/// Planning for SampleFootprints: one vector of points' plan and footprints, stored at point i.
HWY_INLINE void storeFootprint(const Footprint& f, SampleFootprints& out, int tap, int i) {
    const DF df;
    const DI di;
    for (int k = 0; k < 4; ++k) hn::Store(f.index[k], di, out.index[tap][k] + i);
    hn::Store(f.ax, df, out.ax[tap] + i), hn::Store(f.ay, df, out.ay[tap] + i);
}

HWY_INLINE void planVector(const TexelPyramid& t, VF u, VF v, VF lod, SampleFootprints& out, int i) {
    const DF df;
    const DI di;
    const LanePlan p = plan(t, lod);
    hn::Store(hn::VecFromMask(di, hn::RebindMask(di, p.nearest)), di, out.nearest + i);
    hn::Store(hn::VecFromMask(di, hn::RebindMask(di, p.mixLevels)), di, out.mixLevels + i);
    hn::Store(p.weight, df, out.weight + i);
    storeFootprint(footprint(t, p.first, p.nearest, u, v), out, 0, i);
    if (!hn::AllFalse(df, p.mixLevels)) storeFootprint(footprint(t, p.second, p.nearest, u, v), out, 1, i);
}

/// One stored tap per lane: one texel where every lane's tap is nearest (glTF's
/// NEAREST_MIPMAP_LINEAR, common in exported models, reads 2 texels a point and not 8).
HWY_INLINE Texel storedTap(const TexelPyramid& t, const SampleFootprints& f, int tap, int i, MF nearest) {
    const DF df;
    const DI di;
    if (hn::AllTrue(df, nearest)) return texelsAt(t, hn::Load(di, f.index[tap][0] + i));
    const Footprint footprint{{hn::Load(di, f.index[tap][0] + i), hn::Load(di, f.index[tap][1] + i), hn::Load(di, f.index[tap][2] + i),
                               hn::Load(di, f.index[tap][3] + i)},
                              hn::Load(df, f.ax[tap] + i),
                              hn::Load(df, f.ay[tap] + i)};
    return bilinear(t, footprint);
}

/// One vector of points on their stored plan: Texture::gather() after Texture::plan().
HWY_INLINE Texel sampleStored(const TexelPyramid& t, const SampleFootprints& f, int i) {
    const DF df;
    const DI di;
    const MF nearest = hn::RebindMask(df, hn::Ne(hn::Load(di, f.nearest + i), hn::Zero(di)));
    const MF mixLevels = hn::RebindMask(df, hn::Ne(hn::Load(di, f.mixLevels + i), hn::Zero(di)));
    const Texel first = storedTap(t, f, 0, i, nearest);
    if (hn::AllFalse(df, mixLevels)) return first;
    const Texel second = storedTap(t, f, 1, i, nearest);
    const VF weight = hn::Load(df, f.weight + i);
    return {hn::IfThenElse(mixLevels, mix(first.r, second.r, weight), first.r),
            hn::IfThenElse(mixLevels, mix(first.g, second.g, weight), first.g),
            hn::IfThenElse(mixLevels, mix(first.b, second.b, weight), first.b),
            hn::IfThenElse(mixLevels, mix(first.a, second.a, weight), first.a)};
}

/// Asks for the cache lines of every point's footprint before any is gathered. A frame of a
/// model with large textures is bound by these misses (DamagedHelmet at one sample: the first
/// gather of each tap was a third of its cycles, waiting for its line), and a gather waits for its
/// lanes before the next one issues; prefetches do not wait, so the misses of the whole batch are
/// in flight together. The top-left and bottom-right texels' lines cover a footprint but where
/// it crosses a tile corner (1 in 16 at a texel a pixel); a line just asked for is not asked
/// again.
HWY_INLINE void prefetchFootprints(const TexelPyramid& t, const SampleFootprints& f) {
    const int32_t* mixLevels = f.mixLevels;
    intptr_t lastLine = -1;
    auto prefetch = [&](int32_t index) {
        const intptr_t line = intptr_t(index) >> 4;  // 16 texels of 4 bytes: one 64-byte line
        if (line == lastLine) return;
        lastLine = line;
        hwy::Prefetch(t.packed + index);
    };
    for (int i = 0; i < f.count; ++i) prefetch(f.index[0][0][i]), prefetch(f.index[0][3][i]);
    for (int i = 0; i < f.count; ++i)
        if (mixLevels[i]) prefetch(f.index[1][0][i]), prefetch(f.index[1][3][i]);
}

}  // namespace

void planSampleFootprintsOnTarget(const TexelPyramid& t, int count, const float* u, const float* v, const float* lod,
                                  SampleFootprints& out) {
    const DF df;
    const int lanes = int(hn::Lanes(df));
    out.count = count;
    int i = 0;
    for (; i + lanes <= count; i += lanes) planVector(t, hn::LoadU(df, u + i), hn::LoadU(df, v + i), hn::LoadU(df, lod + i), out, i);
    if (i == count) return;
    // The last points, padded to a whole vector with the point (0, 0) at level 0 (kMaxPoints is
    // a multiple of every target's lanes, so the padding fits).
    constexpr int kMaxLanes = HWY_MAX_BYTES / sizeof(float);
    alignas(64) float uTail[kMaxLanes] = {}, vTail[kMaxLanes] = {}, lodTail[kMaxLanes] = {};
    const int rest = count - i;
    std::copy_n(u + i, rest, uTail), std::copy_n(v + i, rest, vTail), std::copy_n(lod + i, rest, lodTail);
    planVector(t, hn::Load(df, uTail), hn::Load(df, vTail), hn::Load(df, lodTail), out, i);
}

void sampleFootprintsOnTarget(const TexelPyramid& t, const SampleFootprints& f, Texture::Channels out) {
    const DF df;
    const int lanes = int(hn::Lanes(df));
    if (t.prefetch) prefetchFootprints(t, f);
    int i = 0;
    for (; i + lanes <= f.count; i += lanes) {
        const Texel s = sampleStored(t, f, i);
        hn::StoreU(s.r, df, out.r + i), hn::StoreU(s.g, df, out.g + i);
        hn::StoreU(s.b, df, out.b + i), hn::StoreU(s.a, df, out.a + i);
    }
    if (i == f.count) return;
    constexpr int kMaxLanes = HWY_MAX_BYTES / sizeof(float);
    alignas(64) float tail[4][kMaxLanes];
    const int rest = f.count - i;
    const Texel s = sampleStored(t, f, i);
    hn::Store(s.r, df, tail[0]), hn::Store(s.g, df, tail[1]), hn::Store(s.b, df, tail[2]), hn::Store(s.a, df, tail[3]);
    std::copy_n(tail[0], rest, out.r + i), std::copy_n(tail[1], rest, out.g + i);
    std::copy_n(tail[2], rest, out.b + i), std::copy_n(tail[3], rest, out.a + i);
}

}  // namespace HWY_NAMESPACE
}  // namespace cuberille::raster
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace cuberille::raster {

HWY_EXPORT(planSampleFootprintsOnTarget);
HWY_EXPORT(sampleFootprintsOnTarget);

void planSampleFootprints(const TexelPyramid& layout, int count, const float* u, const float* v, const float* lod,
                          SampleFootprints& out) {
    HWY_DYNAMIC_DISPATCH(planSampleFootprintsOnTarget)(layout, count, u, v, lod, out);
}

void sampleFootprints(const TexelPyramid& texture, const SampleFootprints& footprints, Texture::Channels out) {
    HWY_DYNAMIC_DISPATCH(sampleFootprintsOnTarget)(texture, footprints, out);
}

// A run of points at a time: planned, then sampled, as the shade stage's shared fetches are.
void sampleLanes(const TexelPyramid& texture, int count, const float* u, const float* v, const float* lod,
                 Texture::Channels out) {
    SampleFootprints footprints;
    for (int first = 0; first < count; first += SampleFootprints::kMaxPoints) {
        const int n = std::min(SampleFootprints::kMaxPoints, count - first);
        planSampleFootprints(texture, n, u + first, v + first, lod + first, footprints);
        sampleFootprints(texture, footprints, {out.r + first, out.g + first, out.b + first, out.a + first});
    }
}

}  // namespace cuberille::raster
#endif  // HWY_ONCE
