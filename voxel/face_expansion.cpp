#include "voxel/face_expansion.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>

#include "raster/limits.h"
#include "voxel/face_footprint_lanes.h"
#include "voxel/packing.h"

namespace cuberille::voxel {
namespace {

/// How many faces a voxel's six-bit face mask names. A table, not __builtin_popcount: this file
/// is compiled for baseline x86-64, where that is a call into libgcc (1.5% of a zoom flight).
constexpr uint8_t faceCount(uint8_t faces) {
    constexpr auto kCounts = [] {
        std::array<uint8_t, 64> counts{};
        for (int m = 0; m < 64; ++m) counts[size_t(m)] = uint8_t((m & 1) + (m >> 1 & 1) + (m >> 2 & 1) + (m >> 3 & 1) + (m >> 4 & 1) + (m >> 5 & 1));
        return counts;
    }();
    return kCounts[faces & 63u];
}

/// The faces of a voxel on the sides of a region: the skirt of a stand-in.
uint8_t regionSideFaces(const glm::uvec3& p, const VoxelRegion& r) {
    uint8_t faces = 0;
    for (int axis = 0; axis < 3; ++axis) {
        if (p[axis] + 1 == r.hi[axis]) faces |= uint8_t(1u << (2 * axis));
        if (p[axis] == r.lo[axis]) faces |= uint8_t(2u << (2 * axis));
    }
    return faces;
}

/// Faces whose screen box is wider or taller than kSearchedFacePixels over the samples per pixel
/// are kept without looking for their samples: a face that size nearly always covers one, and
/// the search costs more than drawing the few that do not. The threshold is a fit to two
/// measurements on the 4096³ dragon's flights at pixel error 1 (docs/performance.md), where faces
/// are half a pixel to a pixel: at 1 sample, searching every face under 2 pixels leaves out half
/// of those it searches, for 20% fewer faces at the same frame time as searching under 1 pixel;
/// at 4 samples, where a tenth of the faces under 2 pixels cover no sample, searching them cost 5
/// to 10% more frame time than searching only those under half a pixel (none there).
constexpr double kSearchedFacePixels = 2.0;

/// The pixels [first, last] whose sample at `offset` (pixels from the pixel's corner) lies in
/// [lo, hi] on one axis; empty when first > last.
inline void samplePixels(double lo, double hi, double offset, int pixels, int& first, int& last) {
    // Clamped to the viewport first, so the conversions stay in range; ceil and floor by
    // truncation and one correction (baseline x86-64 has no rounding instruction: std::ceil is a
    // library call there).
    const double from = std::clamp(lo - offset, -1.0, double(pixels)), to = std::clamp(hi - offset, -1.0, double(pixels));
    first = int(from), last = int(to);
    first += double(first) < from;
    last -= double(last) > to;
    first = std::max(first, 0), last = std::min(last, pixels - 1);
}

/// Calls visit(x, y, s) for the samples s of pixels (x, y) that lie in the convex quad (window
/// pixels, either winding) with each edge's line moved outwards by at least `margin` pixels
/// (inwards, when negative: by margin times |dx| + |dy| over the edge's length, which is at least
/// 1: no square root), until visit returns false; returns whether it did. Widened, the samples
/// looked at are those in the quad's box widened by the margin, which holds every sample within
/// the margin of the quad.
template <class Visit>
bool visitSamplesInQuad(const glm::dvec2 (&q)[4], double margin, const SampleFootprint& f, Visit&& visit) {
    double area2 = 0.0;
    for (int i = 0; i < 4; ++i) area2 += q[i].x * q[(i + 1) % 4].y - q[(i + 1) % 4].x * q[i].y;
    const double orientation = area2 >= 0.0 ? 1.0 : -1.0;
    double edgeA[4], edgeB[4], edgeC[4];  // inside: a x + b y + c >= 0
    for (int i = 0; i < 4; ++i) {
        const glm::dvec2 d = q[(i + 1) % 4] - q[i];
        edgeA[i] = -d.y * orientation, edgeB[i] = d.x * orientation;
        edgeC[i] = -(edgeA[i] * q[i].x + edgeB[i] * q[i].y) + margin * (std::abs(d.x) + std::abs(d.y));
    }
    const double widening = std::max(margin, 0.0);
    const glm::dvec2 lo = glm::min(glm::min(q[0], q[1]), glm::min(q[2], q[3])) - widening;
    const glm::dvec2 hi = glm::max(glm::max(q[0], q[1]), glm::max(q[2], q[3])) + widening;
    for (size_t s = 0; s < f.samples.size(); ++s) {
        int x0, x1, y0, y1;
        samplePixels(lo.x, hi.x, f.samples[s].x, f.widthPixels, x0, x1);
        samplePixels(lo.y, hi.y, f.samples[s].y, f.heightPixels, y0, y1);
        for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x) {
                const double sx = x + f.samples[s].x, sy = y + f.samples[s].y;
                bool inside = true;
                for (int i = 0; i < 4 && inside; ++i) inside = edgeA[i] * sx + edgeB[i] * sy + edgeC[i] >= 0.0;
                if (inside && !visit(x, y, s)) return true;
            }
    }
    return false;
}

/// Whether a sample of some pixel may lie under the face: in its quad widened by kFootprintMarginPixels.
bool quadHoldsSample(const glm::dvec2 (&q)[4], const SampleFootprint& f) {
    return visitSamplesInQuad(q, kFootprintMarginPixels, f, [](int, int, size_t) { return false; });
}

/// One voxel as the depth tests see it: its corners in window pixels, their box, and the range
/// of depth keys the rasterizer can give any sample its faces cover (hiddenDepthMargin included).
struct ProjectedVoxel {
    glm::dvec2 window[8];  // corner k at p + (k & 1, k >> 1 & 1, k >> 2 & 1)
    glm::dvec2 lo, hi;
    double nearestKey = 0.0, farthestKey = 0.0;
    bool depthTested = false;  // small and wholly in front of the near plane: the bounds above hold
    bool occludes = false;     // ... and wholly inside the viewport and the far plane: never clipped
};

/// How far inside a face's exact projected quad a sample must lie for the rasterizer's snapped
/// triangles of that face to surely cover it: the quad's float corners, snapped, lie within
/// half a subpixel (1/512 pixel) and the float transform's error (a thousandth of a pixel at 4K,
/// kFootprintMarginPixels) of the exact ones, so each edge within about 1/300 pixel of its exact
/// line; four subpixels is twice that and more. (Widening, kFootprintMarginPixels is far looser:
/// it is paid once per face, this once per sample a voxel hides.)
constexpr double kSurelyInsideMarginPixels = 4.0 / 256.0;

/// A block's faces against a footprint: the clip position of a voxel corner is affine in its
/// grid position, so a voxel's eight corners cost one matrix product and seven additions (in
/// lanes, voxel/face_footprint_lanes.h).
class FaceFootprints {
public:
    FaceFootprints(const SampleFootprint& f, const VoxelBoxes& boxes, uint32_t blockSize, const DepthFootprint* depth)
        : f_(f), depth_(depth) {
        cornerFrame_.origin = f.clipFromModel * glm::dvec4(boxes.blockOrigin, 1.0);
        if (depth) {
            // What the rasterizer's float transform of a corner can be off by, over the whole
            // block (hiddenDepthMargin): 2^-20 of the sums of |matrix entry x coordinate| of the
            // clip z and w rows, at the block's largest coordinates.
            const glm::dvec3 far = boxes.blockOrigin + double(blockSize) * boxes.voxelSize;
            const glm::dvec3 magnitude = glm::max(glm::abs(boxes.blockOrigin), glm::abs(far));
            const glm::dmat4& m = f.clipFromModel;
            clipZError_ = std::abs(m[3][2]), clipWError_ = std::abs(m[3][3]);
            for (int j = 0; j < 3; ++j)
                clipZError_ += std::abs(m[j][2]) * magnitude[j], clipWError_ += std::abs(m[j][3]) * magnitude[j];
            clipZError_ *= kTransformRounding, clipWError_ *= kTransformRounding;
        }
        for (int axis = 0; axis < 3; ++axis) cornerFrame_.step[axis] = f.clipFromModel[axis] * boxes.voxelSize;
        cornerFrame_.halfWidth = 0.5 * f.widthPixels, cornerFrame_.halfHeight = 0.5 * f.heightPixels;
        cornerFrame_.widthPixels = f.widthPixels, cornerFrame_.heightPixels = f.heightPixels;
        searchedFacePixels_ = kSearchedFacePixels / double(std::max<size_t>(f.samples.size(), 1));
    }

    /// What the corner projection in lanes reads of this block and frame.
    const VoxelCornerFrame& cornerFrame() const { return cornerFrame_; }
    /// ... and the hidden-depth pre-test (its depth is null without a depth footprint).
    HiddenDepthFrame hiddenDepthFrame() const { return {depth_, clipZError_, clipWError_}; }
    const SampleFootprint& sampleFootprint() const { return f_; }
    double searchedFacePixels() const { return searchedFacePixels_; }

    /// The faces of `faces` (of lane i of a projected run, `sampled`: those whose quads the face
    /// search found may cover a sample) that may cover a sample: none when the voxel lies behind
    /// the depth footprint (then `behind`), else `sampled`. With `projected`, what the depth tests
    /// know of the voxel. The voxel's whole box is tested only against the viewport (in the
    /// lanes): the faces' own tests find the rest, and two sample pre-tests of the box (about the
    /// projected centre, then the corners'), which caught a fifth of the voxels at 1 sample and
    /// almost none at 4, cost more than they saved at every sample count.
    uint8_t mayCoverSamples(const VoxelCornerLanes& l, int i, uint8_t faces, uint8_t sampled, DepthPretest pretest,
                            bool& behind, ProjectedVoxel* projected = nullptr) const {
        behind = false;
        if (projected) projected->depthTested = projected->occludes = false;
        if (l.projection[i] == kCrossesNearPlane) return faces;  // clipped by the rasterizer; kept whole
        if (l.projection[i] == kOutsideViewport) return 0;  // no sample (the one test of the whole voxel that pays)
        const glm::dvec2 lo(l.loX[i], l.loY[i]), hi(l.hiX[i], l.hiY[i]);
        const double nearestZ = l.nearestZ[i], farthestZ = l.farthestZ[i], nearestW = l.nearestW[i];
        if (depth_ && hi.x - lo.x <= kDepthTestedVoxelPixels && hi.y - lo.y <= kDepthTestedVoxelPixels) {
            // In front even with the least margin (found in lanes): nothing more to learn here
            // unless the block's own test wants the voxel's bounds.
            if (pretest == kInFront && !projected) return sampled;
            // Behind even with the largest margin any voxel can need: behind with its own, which
            // is never larger (the margin grows with the plane-term ratio, and rounding keeps the
            // order), so its ratio need not be found.
            if (pretest == kBehindWithAnyMargin && !projected) {
                behind = true;
                return 0;
            }
            const double cornerError = this->cornerError(nearestZ, farthestZ, nearestW);
            // The depth key is the window depth clamped to [0, 1], signed (raster/depth.h):
            // monotonic in the depth, so the nearest key is that of the nearest depth (or,
            // reversed, the farthest).
            const double nearKey = depthKeyOf(nearestZ, depth_->keySign), farKey = depthKeyOf(farthestZ, depth_->keySign);
            const double nearestKey = std::min(nearKey, farKey), farthestKey = std::max(nearKey, farKey);
            // The margin grows with the faces' plane-term ratio, which costs more to find than the
            // footprint test: a voxel not behind the footprint with the least margin (ratio 0) is
            // not behind it with its own, and needs the ratio only for the block's own test.
            // The pre-test's verdict where it gave one; where it did not, the same test here.
            const bool mayBeBehind =
                pretest == kTestDepthOnOwn || pretest == kNotDepthTested
                    ? behindFootprint(lo, hi, nearestKey - hiddenDepthMargin(nearestZ, farthestZ, cornerError, 0.0))
                    : pretest != kInFront;
            if (mayBeBehind || projected) {
                ProjectedVoxel local;
                ProjectedVoxel& v = projected ? *projected : local;
                for (int k = 0; k < 8; ++k) v.window[k] = {l.windowX[k][i], l.windowY[k][i]};
                const double margin = hiddenDepthMargin(nearestZ, farthestZ, cornerError, planeTermRatio(v.window, faces));
                v.lo = lo, v.hi = hi;
                v.nearestKey = nearestKey - margin;
                v.farthestKey = farthestKey + margin;
                v.depthTested = true;
                v.occludes = lo.x >= 0.0 && lo.y >= 0.0 && hi.x <= double(f_.widthPixels) &&
                             hi.y <= double(f_.heightPixels) && nearestZ - cornerError > 0.0 && farthestZ + cornerError < 1.0;
                if (mayBeBehind && behindFootprint(lo, hi, v.nearestKey)) {
                    behind = true;
                    return 0;
                }
            }
        }
        return sampled;
    }

    /// The voxel corner (bit a set for the high side along axis a) at place c around the face on
    /// `axis` and `side` (0 the positive one): the corners' bits along the other two axes.
    static constexpr int quadCorner(int axis, int side, int c) {
        constexpr int kAround[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
        return (side == 0 ? 1 << axis : 0) | kAround[c][0] << ((axis + 1) % 3) | kAround[c][1] << ((axis + 2) % 3);
    }

    /// Calls visit(bit, quad) for each face of `faces` (bit 1 << (2 axis + side), side 0 the
    /// positive one) with its window corners in order around it: the corners' bits along the other
    /// two axes.
    template <class Visit>
    static void forEachFaceQuad(const glm::dvec2 (&window)[8], uint8_t faces, Visit&& visit) {
        for (int axis = 0; axis < 3; ++axis)
            for (int side = 0; side < 2; ++side) {
                const uint8_t bit = uint8_t(1u << (2 * axis + side));
                if (!(faces & bit)) continue;
                glm::dvec2 quad[4];
                for (int c = 0; c < 4; ++c) quad[c] = window[quadCorner(axis, side, c)];
                visit(bit, quad);
            }
    }

private:
    /// Whether no sample under the voxel's box (window pixels) can pass a LESS test against the
    /// depth footprint: `nearestKey`, the least key any of its faces' samples can get, is not below
    /// the farthest key stored in any 8x8 block under the widened box.
    bool behindFootprint(const glm::dvec2& lo, const glm::dvec2& hi, double nearestKey) const {
        const DepthFootprint& d = *depth_;
        // Pixels by truncation: the box lies within a few pixels of the image here (it holds a
        // sample, and is at most kDepthTestedVoxelPixels wide), and a pixel one too far left or up
        // (truncation of a negative value) only adds a block to the test.
        // Divided by a constant where the blocks are the rasterizer's, as they are in a frame: a
        // shift and a sign correction where four integer divisions were a third of this test.
        auto block = [&](int pixel) {
            return d.blockSizePixels == raster::kBlockSizePixels ? pixel / raster::kBlockSizePixels : pixel / d.blockSizePixels;
        };
        const int x0 = std::max(0, block(int(lo.x - kFootprintMarginPixels)));
        const int y0 = std::max(0, block(int(lo.y - kFootprintMarginPixels)));
        const int x1 = std::min(d.blocksX - 1, block(int(hi.x + kFootprintMarginPixels)));
        const int y1 = std::min(d.blocksY - 1, block(int(hi.y + kFootprintMarginPixels)));
        if (x0 > x1 || y0 > y1) return false;
        for (int by = y0; by <= y1; ++by)
            for (int bx = x0; bx <= x1; ++bx)
                if (!(double(d.farthestKey[size_t(by) * size_t(d.blocksX) + size_t(bx)]) <= nearestKey)) return false;
        return true;
    }

    double cornerError(double nearestZ, double farthestZ, double nearestW) const {
        return voxel::cornerError(clipZError_, clipWError_, nearestZ, farthestZ, nearestW);
    }

    /// R = L² / area2 of the worst of the faces' triangles (hiddenDepthMargin), from their exact
    /// window corners: each snapped vertex lies within kSnapSlackSubpixels of the exact one on
    /// each axis, which lengthens a side by at most twice that and shrinks the doubled area by at
    /// most 4 d P + 8 d² (d the slack, P the sum of the sides' |dx| + |dy|). Capped at 2^24, the
    /// bound for any triangle of the tested size.
    static double planeTermRatio(const glm::dvec2 (&window)[8], uint8_t faces) {
        constexpr double kWorst = kLargestPlaneTermRatio, s = raster::kSubpixelsPerPixel, d = kSnapSlackSubpixels;
        double worst = 0.0;
        forEachFaceQuad(window, faces, [&](uint8_t, const glm::dvec2(&q)[4]) {
            static constexpr int kTriangles[2][3] = {{0, 1, 2}, {0, 2, 3}};  // the draw's two per face
            for (const auto& t : kTriangles) {
                const glm::dvec2 a = q[t[0]] * s, b = q[t[1]] * s, c = q[t[2]] * s;
                const glm::dvec2 ab = b - a, ac = c - a, bc = c - b;
                const double sides = std::abs(ab.x) + std::abs(ab.y) + std::abs(ac.x) + std::abs(ac.y) +
                                     std::abs(bc.x) + std::abs(bc.y);
                const double area2 = std::abs(ab.x * ac.y - ab.y * ac.x) - 4.0 * d * sides - 8.0 * d * d;
                const glm::dvec2 extent = glm::max(glm::max(a, b), c) - glm::min(glm::min(a, b), c);
                const double l = std::max(extent.x, extent.y) + 2.0 * d;
                worst = area2 >= 1.0 ? std::max(worst, l * l / area2) : kWorst;  // a sliver: the worst case
            }
        });
        return std::min(worst, kWorst);
    }

    /// How far a snapped window vertex lies from the exact one here, per axis, in subpixels: half
    /// a subpixel of snapping and the float transform's error (about a thousandth of a pixel at
    /// 4K, a quarter of a subpixel: kFootprintMarginPixels).
    static constexpr double kSnapSlackSubpixels = 1.0;

    const SampleFootprint& f_;
    const DepthFootprint* depth_;
    double clipZError_ = 0.0, clipWError_ = 0.0;
    VoxelCornerFrame cornerFrame_;  // the clip position of the block's first corner, a voxel's steps
    double searchedFacePixels_ = 0.0;  // kSearchedFacePixels over the samples per pixel
};

/// A voxel whose faces survived the tests made one at a time, waiting for the block's own
/// occlusion test.
struct KeptVoxel {
    uint32_t index;  // in the block's arrays
    uint8_t faces;   // the faces still to draw
    ProjectedVoxel projected;
};

/// The most sample keys a block's own depth test holds (a block seen at over 1,000 x 1,000 pixels,
/// or 512 x 512 at 16 samples, is left to the rasterizer: its voxels are near and large).
constexpr size_t kMaxBlockDepthSamples = size_t(1) << 24;

/// Same-block occlusion: the far side of a block lies behind its near side, and a block is drawn
/// in one chunk, so the frame's depth footprint (made from the chunks before) cannot see it. The
/// block's voxels are visited front to back (by their nearest key, in kDepthOrderBins bins: the
/// order decides only how many are found, not whether a finding is right); each voxel that may
/// be clipped by nothing records, at every sample its faces surely cover, the farthest key it can
/// write there; a later voxel every one of whose samples already holds a key below its nearest
/// key (strictly: in the draw they may come in either order, and a tie would go to the first)
/// cannot show anywhere, and is left out. The faces drawn are then the same bits as before.
void leaveOutVoxelsBehindTheirBlock(std::vector<KeptVoxel>& kept, const SampleFootprint& f, uint64_t& facesBehind) {
    constexpr int kDepthOrderBins = 1024;
    int x0 = f.widthPixels, y0 = f.heightPixels, x1 = -1, y1 = -1;
    double keyLo = std::numeric_limits<double>::infinity(), keyHi = -keyLo;
    size_t tested = 0;
    // A pixel's samples lie within it, so the pixels whose samples can lie in [lo - m, hi + m]
    // are within [trunc(lo - m) - 1, trunc(hi + m) + 1] (truncation of a negative value only widens it).
    auto pixelsOf = [&](const ProjectedVoxel& v, int& px0, int& py0, int& px1, int& py1) {
        px0 = std::max(0, int(v.lo.x - kFootprintMarginPixels) - 1), py0 = std::max(0, int(v.lo.y - kFootprintMarginPixels) - 1);
        px1 = std::min(f.widthPixels - 1, int(v.hi.x + kFootprintMarginPixels) + 1);
        py1 = std::min(f.heightPixels - 1, int(v.hi.y + kFootprintMarginPixels) + 1);
    };
    for (const KeptVoxel& k : kept) {
        if (!k.projected.depthTested) continue;
        int px0, py0, px1, py1;
        pixelsOf(k.projected, px0, py0, px1, py1);
        x0 = std::min(x0, px0), y0 = std::min(y0, py0), x1 = std::max(x1, px1), y1 = std::max(y1, py1);
        keyLo = std::min(keyLo, k.projected.nearestKey), keyHi = std::max(keyHi, k.projected.nearestKey);
        ++tested;
    }
    if (tested < 2 || x0 > x1 || y0 > y1) return;
    const size_t samples = f.samples.size(), width = size_t(x1 - x0 + 1);
    const size_t keyCount = width * size_t(y1 - y0 + 1) * samples;
    if (keyCount > kMaxBlockDepthSamples) return;
    thread_local std::vector<double> keys;  // per sample of the rectangle: the farthest key drawn there, at most
    thread_local std::vector<uint32_t> order, binStart;
    keys.assign(keyCount, std::numeric_limits<double>::infinity());
    auto keyAt = [&](int x, int y, size_t s) -> double& {
        return keys[(size_t(y - y0) * width + size_t(x - x0)) * samples + s];
    };
    // Front to back: a counting sort of the tested voxels by their nearest key.
    const double binScale = keyHi > keyLo ? (kDepthOrderBins - 1) / (keyHi - keyLo) : 0.0;
    auto binOf = [&](const KeptVoxel& k) { return size_t((k.projected.nearestKey - keyLo) * binScale); };
    binStart.assign(kDepthOrderBins + 1, 0);
    for (const KeptVoxel& k : kept)
        if (k.projected.depthTested) ++binStart[binOf(k) + 1];
    for (int b = 0; b < kDepthOrderBins; ++b) binStart[size_t(b) + 1] += binStart[size_t(b)];
    order.resize(tested);
    for (size_t i = 0; i < kept.size(); ++i)
        if (kept[i].projected.depthTested) order[binStart[binOf(kept[i])]++] = uint32_t(i);

    for (uint32_t i : order) {
        KeptVoxel& k = kept[i];
        const ProjectedVoxel& v = k.projected;
        // Hidden when every sample any of its faces may cover already holds a nearer key.
        bool hidden = true;
        FaceFootprints::forEachFaceQuad(v.window, k.faces, [&](uint8_t, const glm::dvec2(&quad)[4]) {
            hidden = hidden && !visitSamplesInQuad(quad, kFootprintMarginPixels, f, [&](int x, int y, size_t s) {
                return keyAt(x, y, s) < v.nearestKey;
            });
        });
        if (hidden) {
            facesBehind += uint64_t(faceCount(k.faces));
            k.faces = 0;
            continue;
        }
        if (!v.occludes) continue;
        FaceFootprints::forEachFaceQuad(v.window, k.faces, [&](uint8_t, const glm::dvec2(&quad)[4]) {
            // The samples the rasterizer's snapped triangles of the face surely cover (a sample
            // on the quad's diagonal belongs to one of its two by the fill rule).
            visitSamplesInQuad(quad, -kSurelyInsideMarginPixels, f, [&](int x, int y, size_t s) {
                double& key = keyAt(x, y, s);
                key = std::min(key, v.farthestKey);
                return true;
            });
        });
    }
}

/// Up to kFootprintLanes voxels of a block waiting for their footprint tests, which run in lanes:
/// their corners projected together, then their faces' quads searched for samples together.
struct FootprintRun {
    int count = 0;
    uint32_t index[kFootprintLanes];  // in the block's arrays
    glm::dvec3 lo[kFootprintLanes];   // low corner, model units
    uint8_t emit[kFootprintLanes];    // camera-facing active faces; after the tests, those kept
    uint8_t sampled[kFootprintLanes]; // after test(): those of emit that may cover a sample
    uint8_t depthPretest[kFootprintLanes];  // after test(), with a depth footprint: DepthPretest
    VoxelCornerLanes corners;
    FaceQuadLanes quads;
    int quadVoxel[kFootprintLanes];  // the run's voxel each quad belongs to
    uint8_t quadBit[kFootprintLanes];

    void add(uint32_t i, const glm::uvec3& position, const glm::dvec3& low, uint8_t faces) {
        index[count] = i, lo[count] = low, emit[count] = faces;
        corners.x[count] = int32_t(position.x), corners.y[count] = int32_t(position.y), corners.z[count] = int32_t(position.z);
        ++count;
    }

    /// Projects the run's corners, pre-tests their depth, then searches each face of each
    /// projected voxel for a sample: not those of a voxel surely behind the depth footprint,
    /// unless every voxel's bounds are wanted (the block's own test, testWithinBlock).
    void test(const FaceFootprints& footprints, bool testWithinBlock) {
        corners.count = count;
        projectVoxelCorners(footprints.cornerFrame(), corners);
        const bool depth = footprints.hiddenDepthFrame().depth != nullptr;
        if (depth) pretestHiddenDepth(footprints.hiddenDepthFrame(), corners, depthPretest);
        quads.count = 0;
        for (int j = 0; j < count; ++j) {
            sampled[j] = 0;
            if (corners.projection[j] != kProjected) continue;
            if (depth && !testWithinBlock && depthPretest[j] == kBehindWithAnyMargin) continue;
            for (int axis = 0; axis < 3; ++axis)
                for (int side = 0; side < 2; ++side) {
                    const uint8_t bit = uint8_t(1u << (2 * axis + side));
                    if (!(emit[j] & bit)) continue;
                    if (quads.count == kFootprintLanes) searchQuads(footprints);
                    const int q = quads.count++;
                    for (int c = 0; c < 4; ++c) {
                        const int k = FaceFootprints::quadCorner(axis, side, c);
                        quads.x[c][q] = corners.windowX[k][j], quads.y[c][q] = corners.windowY[k][j];
                    }
                    quadVoxel[q] = j, quadBit[q] = bit;
                }
        }
        searchQuads(footprints);
    }

private:
    void searchQuads(const FaceFootprints& footprints) {
        const SampleFootprint& f = footprints.sampleFootprint();
        searchFaceSamples(f, kFootprintMarginPixels, footprints.searchedFacePixels(), quads);
        for (int q = 0; q < quads.count; ++q) {
            bool covers = quads.found[q] == kMayCover;
            if (quads.found[q] == kSearchOnOwn) {
                const glm::dvec2 quad[4] = {{quads.x[0][q], quads.y[0][q]}, {quads.x[1][q], quads.y[1][q]},
                                            {quads.x[2][q], quads.y[2][q]}, {quads.x[3][q], quads.y[3][q]}};
                covers = quadHoldsSample(quad, f);
            }
            if (covers) sampled[quadVoxel[q]] |= quadBit[q];
        }
        quads.count = 0;
    }
};

/// faceCorners() for any precision: the face's corners take their coordinates from lo or hi.
template <class Vec3>
[[gnu::always_inline]] inline void faceCornersOf(const Vec3& lo, const Vec3& hi, int axis, bool positive, Vec3 (&c)[4]) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const auto w = positive ? hi[axis] : lo[axis];
    auto corner = [&](auto a, auto b) {
        Vec3 p;
        p[axis] = w;
        p[u] = a;
        p[v] = b;
        return p;
    };
    if (positive) {
        c[0] = corner(lo[u], lo[v]), c[1] = corner(hi[u], lo[v]), c[2] = corner(hi[u], hi[v]), c[3] = corner(lo[u], hi[v]);
    } else {
        c[0] = corner(lo[u], lo[v]), c[1] = corner(lo[u], hi[v]), c[2] = corner(hi[u], hi[v]), c[3] = corner(hi[u], lo[v]);
    }
}

/// Where faces go in a FaceMesh: room for `faces` more quads, made once for a voxel or a run.
struct FaceSlots {
    glm::vec3 *position, *normal, *color;
    uint32_t* index;
    uint32_t firstVertex;

    /// The mesh's arrays grow once and are written in place: push_back's capacity test per
    /// element was most of the appends' time, and then resize(n, value)'s fill, whose 12-byte
    /// value GCC 12 assembles on the stack for every element (a store-forwarding stall per
    /// vertex, a third of their samples: perf annotate).
    static FaceSlots grow(FaceMesh& out, size_t faces) {
        const size_t firstVertex = out.positions.size(), firstIndex = out.indices.size();
        out.positions.resize(firstVertex + 4 * faces);
        out.normals.resize(firstVertex + 4 * faces);
        out.colors.resize(firstVertex + 4 * faces);
        out.indices.resize(firstIndex + 6 * faces);
        out.faces += faces;
        return {out.positions.data() + firstVertex, out.normals.data() + firstVertex, out.colors.data() + firstVertex,
                out.indices.data() + firstIndex, uint32_t(firstVertex)};
    }

    /// Writes the voxel's faces `emit` as quads of two triangles carrying its normal and colour,
    /// and moves past them. Each corner coordinate is the box's low or high one, so the six are
    /// rounded to float once a voxel: the positions faceCorners() then glm::vec3 would give, bit
    /// for bit, without a call and twelve double conversions a face (6% of a zoom flight).
    void write(const glm::dvec3& lo, const glm::dvec3& hi, uint8_t emit, const glm::vec3& n, const glm::vec3& c) {
        const glm::vec3 low(lo), high(hi);
        for (int axis = 0; axis < 3; ++axis)
            for (int side = 0; side < 2; ++side) {
                if (!(emit & (1u << (2 * axis + side)))) continue;
                glm::vec3 corners[4];
                faceCornersOf(low, high, axis, side == 0, corners);
                for (const glm::vec3& p : corners) *position++ = p, *normal++ = n, *color++ = c;
                const uint32_t v = firstVertex;
                *index++ = v, *index++ = v + 1, *index++ = v + 2;
                *index++ = v, *index++ = v + 2, *index++ = v + 3;
                firstVertex += 4;
            }
    }
};

}  // namespace

void faceCorners(const glm::dvec3& lo, const glm::dvec3& hi, int axis, bool positive, glm::dvec3 (&c)[4]) {
    faceCornersOf(lo, hi, axis, positive, c);
}

void expandVoxelFaces(const VoxelModel& model, const BlockVoxels& block, const glm::dvec3& camera, FaceMesh& out,
                      const glm::vec3* overrideColor, const VoxelRegion* region, const SampleFootprint* footprint,
                      const DepthFootprint* depth, bool testWithinBlock) {
    const VoxelBoxes boxes(model, block.level, block.coord);
    std::optional<FaceFootprints> footprints;
    if (footprint) footprints.emplace(*footprint, boxes, model.blockSize, depth);
    // With the block's own occlusion test, the faces are appended after it, in the block's order
    // (the order the draw would have had: ties in depth go the same way).
    testWithinBlock = testWithinBlock && footprints && depth;
    thread_local std::vector<KeptVoxel> kept;
    kept.clear();
    auto write = [&](FaceSlots& slots, size_t i, const glm::dvec3& lo, uint8_t emit) {
        const glm::vec3 normal = unpackNormal1010102(block.normals[i]);
        const glm::vec3 color = overrideColor ? *overrideColor : unpackSrgba8Rgb(block.colors[i]);
        slots.write(lo, lo + boxes.voxelSize, emit, normal, color);
        ++out.voxels;
    };
    auto append = [&](size_t i, const glm::dvec3& lo, uint8_t emit) {
        FaceSlots slots = FaceSlots::grow(out, size_t(faceCount(emit)));
        write(slots, i, lo, emit);
    };
    // With a footprint, the voxels with faces to emit wait in a run, whose tests go through lanes
    // together (testRun); their faces are then appended in the block's order.
    thread_local FootprintRun run;
    run.count = 0;
    auto testRun = [&] {
        if (run.count == 0) return;
        run.test(*footprints, testWithinBlock);
        size_t faces = 0;
        for (int j = 0; j < run.count; ++j) {
            const uint8_t emit = run.emit[j];
            bool behind = false;
            ProjectedVoxel* projected = testWithinBlock ? &kept.emplace_back().projected : nullptr;
            const uint8_t covering = footprints->mayCoverSamples(run.corners, j, emit, run.sampled[j],
                                                                 DepthPretest(run.depthPretest[j]), behind, projected);
            (behind ? out.facesBehindDepth : out.facesBetweenSamples) += uint64_t(faceCount(emit ^ covering));
            run.emit[j] = covering;
            faces += size_t(faceCount(covering));
            if (testWithinBlock) {
                if (covering)
                    kept.back().index = run.index[j], kept.back().faces = covering;
                else
                    kept.pop_back();
            }
        }
        // The run's faces, in its order, into room made once.
        if (!testWithinBlock && faces) {
            FaceSlots slots = FaceSlots::grow(out, faces);
            for (int j = 0; j < run.count; ++j)
                if (run.emit[j]) write(slots, run.index[j], run.lo[j], run.emit[j]);
        }
        run.count = 0;
    };
    // Which sides face the camera, a run of voxels at a time in lanes; then, one voxel at a
    // time, the active ones among them (at most one per axis).
    const VoxelFacingFrame facingFrame{boxes.blockOrigin, camera, boxes.voxelSize};
    uint8_t facing[kFootprintLanes];
    for (size_t first = 0; first < block.voxels.size(); first += kFootprintLanes) {
        const int count = int(std::min<size_t>(kFootprintLanes, block.voxels.size() - first));
        cameraFacingSides(facingFrame, block.voxels.data() + first, count, facing);
        for (int j = 0; j < count; ++j) {
            const size_t i = first + size_t(j);
            const uint32_t packed = block.voxels[i];
            const glm::uvec3 position = voxelPositionInBlock(packed);
            uint8_t mask = voxelFaceMask(packed);
            if (region) {
                if (glm::any(glm::lessThan(position, region->lo)) || glm::any(glm::greaterThanEqual(position, region->hi)))
                    continue;
                mask |= regionSideFaces(position, *region);
            }
            const uint8_t emit = mask & facing[j];
            if (!emit) continue;
            if (!footprints) {
                append(i, boxes.lowCorner(position), emit);
                continue;
            }
            run.add(uint32_t(i), position, boxes.lowCorner(position), emit);
            if (run.count == kFootprintLanes) testRun();
        }
    }
    testRun();
    if (!testWithinBlock) return;
    leaveOutVoxelsBehindTheirBlock(kept, *footprint, out.facesBehindDepth);
    for (const KeptVoxel& k : kept)
        if (k.faces) append(k.index, boxes.lowCorner(voxelPositionInBlock(block.voxels[k.index])), k.faces);
}

}  // namespace cuberille::voxel
