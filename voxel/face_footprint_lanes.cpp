#include "voxel/face_footprint_lanes.h"

#include "raster/limits.h"
#include "voxel/face_expansion.h"
#include "voxel/voxel_model.h"

// Compiled once per instruction set (see raster/tile_raster.cpp for how foreach_target.h works):
// the loops below are plain loops over lanes of one element type each, which GCC vectorises for
// each target (-fopt-info-vec).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "voxel/face_footprint_lanes.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace cuberille::voxel {
namespace HWY_NAMESPACE {
namespace {

constexpr int N = kFootprintLanes;

// std::min and std::max as they choose (the first argument on a tie), so a lane picks the value
// the scalar code picks, signed zeros included.
inline double minOf(double a, double b) { return b < a ? b : a; }
inline double maxOf(double a, double b) { return a < b ? b : a; }

/// Corner K of every lane: the base corner plus one voxel step along each axis K names, added
/// in the order x, y, z (as the scalar code adds them), then divided by w and mapped to pixels.
template <int K>
void projectCorner(const VoxelCornerFrame& f, int n, const double* bx, const double* by, const double* bz,
                   const double* bw, int32_t* crosses, VoxelCornerLanes& l) {
    double* __restrict wx = l.windowX[K];
    double* __restrict wy = l.windowY[K];
    for (int i = 0; i < n; ++i) {
        double cx = bx[i], cy = by[i], cz = bz[i], cw = bw[i];
        if constexpr ((K & 1) != 0) cx = cx + f.step[0].x, cy = cy + f.step[0].y, cz = cz + f.step[0].z, cw = cw + f.step[0].w;
        if constexpr ((K & 2) != 0) cx = cx + f.step[1].x, cy = cy + f.step[1].y, cz = cz + f.step[1].z, cw = cw + f.step[1].w;
        if constexpr ((K & 4) != 0) cx = cx + f.step[2].x, cy = cy + f.step[2].y, cz = cz + f.step[2].z, cw = cw + f.step[2].w;
        crosses[i] |= int32_t(!(cw > 0.0)) | int32_t(cz < 0.0);
        const double invW = 1.0 / cw;
        const double x = (cx * invW + 1.0) * f.halfWidth, y = (1.0 - cy * invW) * f.halfHeight;
        wx[i] = x, wy[i] = y;
        l.loX[i] = minOf(l.loX[i], x), l.loY[i] = minOf(l.loY[i], y);
        l.hiX[i] = maxOf(l.hiX[i], x), l.hiY[i] = maxOf(l.hiY[i], y);
        const double z = cz * invW;
        l.nearestZ[i] = minOf(l.nearestZ[i], z), l.farthestZ[i] = maxOf(l.farthestZ[i], z);
        l.nearestW[i] = minOf(l.nearestW[i], cw);
    }
}

}  // namespace

void cameraFacingSidesOnTarget(const VoxelFacingFrame& f, const uint32_t* packed, int count, uint8_t* sides) {
    const double size = f.voxelSize;
    for (int i = 0; i < count; ++i) {
        const uint32_t p = packed[i];
        // VoxelBoxes::lowCorner's blockOrigin + position * size, then + size, per axis.
        const double loX = f.blockOrigin.x + double(p & 0xFFu) * size, hiX = loX + size;
        const double loY = f.blockOrigin.y + double((p >> 8) & 0xFFu) * size, hiY = loY + size;
        const double loZ = f.blockOrigin.z + double((p >> 16) & 0xFFu) * size, hiZ = loZ + size;
        const uint32_t bits = uint32_t(f.camera.x > hiX) * kFacePosX | uint32_t(f.camera.x < loX) * kFaceNegX |
                              uint32_t(f.camera.y > hiY) * kFacePosY | uint32_t(f.camera.y < loY) * kFaceNegY |
                              uint32_t(f.camera.z > hiZ) * kFacePosZ | uint32_t(f.camera.z < loZ) * kFaceNegZ;
        sides[i] = uint8_t(bits);
    }
}

void projectVoxelCornersOnTarget(const VoxelCornerFrame& f, VoxelCornerLanes& l) {
    const int n = l.count;
    alignas(64) double bx[N], by[N], bz[N], bw[N];
    alignas(64) int32_t crosses[N];
    constexpr double kInfinity = __builtin_inf();
    for (int i = 0; i < n; ++i) {
        // The scalar code's origin + step x * px + step y * py + step z * pz, left to right.
        const double px = double(l.x[i]), py = double(l.y[i]), pz = double(l.z[i]);
        bx[i] = ((f.origin.x + f.step[0].x * px) + f.step[1].x * py) + f.step[2].x * pz;
        by[i] = ((f.origin.y + f.step[0].y * px) + f.step[1].y * py) + f.step[2].y * pz;
        bz[i] = ((f.origin.z + f.step[0].z * px) + f.step[1].z * py) + f.step[2].z * pz;
        bw[i] = ((f.origin.w + f.step[0].w * px) + f.step[1].w * py) + f.step[2].w * pz;
        crosses[i] = 0;
        l.loX[i] = l.loY[i] = kInfinity, l.hiX[i] = l.hiY[i] = -kInfinity;
        l.nearestZ[i] = kInfinity, l.farthestZ[i] = -kInfinity, l.nearestW[i] = kInfinity;
    }
    projectCorner<0>(f, n, bx, by, bz, bw, crosses, l);
    projectCorner<1>(f, n, bx, by, bz, bw, crosses, l);
    projectCorner<2>(f, n, bx, by, bz, bw, crosses, l);
    projectCorner<3>(f, n, bx, by, bz, bw, crosses, l);
    projectCorner<4>(f, n, bx, by, bz, bw, crosses, l);
    projectCorner<5>(f, n, bx, by, bz, bw, crosses, l);
    projectCorner<6>(f, n, bx, by, bz, bw, crosses, l);
    projectCorner<7>(f, n, bx, by, bz, bw, crosses, l);
    const double m = kFootprintMarginPixels;
    const double right = double(f.widthPixels) + m, bottom = double(f.heightPixels) + m;
    for (int i = 0; i < n; ++i) {
        const int32_t outside = int32_t(l.hiX[i] < -m) | int32_t(l.hiY[i] < -m) | int32_t(l.loX[i] > right) |
                                int32_t(l.loY[i] > bottom);
        l.projection[i] = uint8_t(crosses[i] ? kCrossesNearPlane : (outside ? kOutsideViewport : kProjected));
    }
}

void pretestHiddenDepthOnTarget(const HiddenDepthFrame& f, const VoxelCornerLanes& l, uint8_t* pretest) {
    const DepthFootprint& d = *f.depth;
    const int n = l.count;
    const float* farthest = d.farthestKey.data();
    const double keySign = double(d.keySign), m = kFootprintMarginPixels;
    constexpr int kBlock = raster::kBlockSizePixels;  // a constant, so that the divisions are shifts
    // Three loops without branches, so that each vectorises: the bound and the block range, the
    // blocks' keys (gathered), then the verdict.
    alignas(64) int32_t tested[N], x0[N], y0[N], x1[N], y1[N], behind[N], surely[N];
    alignas(64) double bound[N], surelyBound[N];
    for (int i = 0; i < n; ++i) tested[i] = int32_t(l.projection[i] == kProjected);
    for (int i = 0; i < n; ++i) {
        const double loX = l.loX[i], loY = l.loY[i], hiX = l.hiX[i], hiY = l.hiY[i];
        const int32_t small = int32_t(hiX - loX <= kDepthTestedVoxelPixels) & int32_t(hiY - loY <= kDepthTestedVoxelPixels);
        const int32_t t = tested[i] & small;
        tested[i] = t;
        const double nearestZ = l.nearestZ[i], farthestZ = l.farthestZ[i];
        const double error = cornerError(f.clipZError, f.clipWError, nearestZ, farthestZ, l.nearestW[i]);
        const double nearKey = depthKeyOf(nearestZ, keySign), farKey = depthKeyOf(farthestZ, keySign);
        const double nearestKey = farKey < nearKey ? farKey : nearKey;  // std::min
        bound[i] = nearestKey - hiddenDepthMargin(nearestZ, farthestZ, error, 0.0);
        surelyBound[i] = nearestKey - hiddenDepthMargin(nearestZ, farthestZ, error, kLargestPlaneTermRatio);
        // face_expansion.cpp's behindFootprint: blocks by truncation, then clamped to the image.
        // (A lane not tested converts 0, not whatever its box holds.)
        const int32_t bx0 = int32_t((t ? loX : 0.0) - m) / kBlock, by0 = int32_t((t ? loY : 0.0) - m) / kBlock;
        const int32_t bx1 = int32_t((t ? hiX : 0.0) + m) / kBlock, by1 = int32_t((t ? hiY : 0.0) + m) / kBlock;
        x0[i] = bx0 < 0 ? 0 : bx0, y0[i] = by0 < 0 ? 0 : by0;
        x1[i] = bx1 < d.blocksX - 1 ? bx1 : d.blocksX - 1, y1[i] = by1 < d.blocksY - 1 ? by1 : d.blocksY - 1;
    }
    const int32_t blocksX = d.blocksX;
    for (int i = 0; i < n; ++i) behind[i] = 1, surely[i] = 1;
    for (int dy = 0; dy < 3; ++dy)
        for (int dx = 0; dx < 3; ++dx)
        {
            alignas(64) int32_t block[N];
            for (int i = 0; i < n; ++i) {
                // Past the range, the range's last block again (an AND does not mind); an empty
                // range reads block 0, and its answer is not used.
                const int32_t empty = int32_t(x0[i] > x1[i]) | int32_t(y0[i] > y1[i]);
                const int32_t bx = x0[i] + dx < x1[i] ? x0[i] + dx : x1[i], by = y0[i] + dy < y1[i] ? y0[i] + dy : y1[i];
                block[i] = (by * blocksX + bx) * (1 - empty);
            }
            for (int i = 0; i < n; ++i) {
                const double key = double(farthest[block[i]]);
                behind[i] &= int32_t(key <= bound[i]);
                surely[i] &= int32_t(key <= surelyBound[i]);
            }
        }
    for (int i = 0; i < n; ++i) {
        const int32_t empty = int32_t(x0[i] > x1[i]) | int32_t(y0[i] > y1[i]);
        const int32_t wide = int32_t(x1[i] - x0[i] > 2) | int32_t(y1[i] - y0[i] > 2);
        // Not tested: kNotDepthTested; an empty range: kInFront; more than 3 x 3 blocks:
        // kTestDepthOnOwn; else kBehindWithAnyMargin, kMayBeBehind or kInFront.
        const int32_t behindVerdict = surely[i] ? int32_t(kBehindWithAnyMargin) : int32_t(kMayBeBehind);
        const int32_t verdict = empty ? int32_t(kInFront) : (wide ? int32_t(kTestDepthOnOwn) : (behind[i] ? behindVerdict : int32_t(kInFront)));
        pretest[i] = uint8_t(tested[i] ? verdict : int32_t(kNotDepthTested));
    }
}

/// For each sample offset and each lane, the pixels whose sample lies in the lane's box
/// (samplePixels() of face_expansion.cpp on each axis: clamped first, ceil and floor by
/// truncation and one correction), the first W x W of them tested against the four edges; `wide`
/// where the box holds more.
template <int W>
void searchWindow(const glm::dvec2* samples, int sampleCount, int widthPixels, int heightPixels, int n,
                  const double (&a)[4][N], const double (&b)[4][N], const double (&c)[4][N], const double* loX,
                  const double* loY, const double* hiX, const double* hiY, int32_t* holds, int32_t* wide) {
    const double width = double(widthPixels), height = double(heightPixels);
    for (int s = 0; s < sampleCount; ++s) {
        const double offsetX = samples[s].x, offsetY = samples[s].y;
        for (int i = 0; i < n; ++i) {
            auto clamp = [](double v, double lo, double hi) { return v < lo ? lo : (hi < v ? hi : v); };
            const double fromX = clamp(loX[i] - offsetX, -1.0, width), toX = clamp(hiX[i] - offsetX, -1.0, width);
            const double fromY = clamp(loY[i] - offsetY, -1.0, height), toY = clamp(hiY[i] - offsetY, -1.0, height);
            int32_t x0 = int32_t(fromX), x1 = int32_t(toX), y0 = int32_t(fromY), y1 = int32_t(toY);
            x0 += int32_t(double(x0) < fromX), x1 -= int32_t(double(x1) > toX);
            y0 += int32_t(double(y0) < fromY), y1 -= int32_t(double(y1) > toY);
            x0 = x0 < 0 ? 0 : x0, y0 = y0 < 0 ? 0 : y0;
            x1 = x1 < widthPixels - 1 ? x1 : widthPixels - 1, y1 = y1 < heightPixels - 1 ? y1 : heightPixels - 1;
            wide[i] |= int32_t(x1 - x0 > W - 1) | int32_t(y1 - y0 > W - 1);
            int32_t found = 0;
            for (int dy = 0; dy < W; ++dy)
                for (int dx = 0; dx < W; ++dx) {
                    const double sx = double(x0 + dx) + offsetX, sy = double(y0 + dy) + offsetY;
                    int32_t inside = int32_t(x0 + dx <= x1) & int32_t(y0 + dy <= y1);
                    for (int e = 0; e < 4; ++e) inside &= int32_t(a[e][i] * sx + b[e][i] * sy + c[e][i] >= 0.0);
                    found |= inside;
                }
            holds[i] |= found;
        }
    }
}

void searchFaceSamplesOnTarget(const glm::dvec2* samples, int sampleCount, int widthPixels, int heightPixels,
                               double margin, double searched, FaceQuadLanes& l) {
    const int n = l.count;
    // Each quad's edges, inside where a x + b y + c >= 0 (face_expansion.cpp's visitSamplesInQuad,
    // its operations in its order), and its box.
    alignas(64) double a[4][N], b[4][N], c[4][N];
    alignas(64) double loX[N], loY[N], hiX[N], hiY[N];
    alignas(64) int32_t big[N], holds[N], wide[N];
    const double widening = margin > 0.0 ? margin : 0.0;  // std::max(margin, 0.0)
    for (int i = 0; i < n; ++i) {
        double area2 = 0.0;
        area2 = area2 + (l.x[0][i] * l.y[1][i] - l.x[1][i] * l.y[0][i]);
        area2 = area2 + (l.x[1][i] * l.y[2][i] - l.x[2][i] * l.y[1][i]);
        area2 = area2 + (l.x[2][i] * l.y[3][i] - l.x[3][i] * l.y[2][i]);
        area2 = area2 + (l.x[3][i] * l.y[0][i] - l.x[0][i] * l.y[3][i]);
        const double orientation = area2 >= 0.0 ? 1.0 : -1.0;
        for (int e = 0; e < 4; ++e) {
            const int next = (e + 1) & 3;
            const double dx = l.x[next][i] - l.x[e][i], dy = l.y[next][i] - l.y[e][i];
            a[e][i] = -dy * orientation, b[e][i] = dx * orientation;
            const double adx = dx < 0.0 ? -dx : dx, ady = dy < 0.0 ? -dy : dy;  // std::abs
            c[e][i] = -(a[e][i] * l.x[e][i] + b[e][i] * l.y[e][i]) + margin * (adx + ady);
        }
        const double faceLoX = minOf(minOf(l.x[0][i], l.x[1][i]), minOf(l.x[2][i], l.x[3][i]));
        const double faceLoY = minOf(minOf(l.y[0][i], l.y[1][i]), minOf(l.y[2][i], l.y[3][i]));
        const double faceHiX = maxOf(maxOf(l.x[0][i], l.x[1][i]), maxOf(l.x[2][i], l.x[3][i]));
        const double faceHiY = maxOf(maxOf(l.y[0][i], l.y[1][i]), maxOf(l.y[2][i], l.y[3][i]));
        big[i] = int32_t(faceHiX - faceLoX > searched) | int32_t(faceHiY - faceLoY > searched);
        loX[i] = faceLoX - widening, loY[i] = faceLoY - widening;
        hiX[i] = faceHiX + widening, hiY[i] = faceHiY + widening;
        holds[i] = 0, wide[i] = 0;
    }
    // A searched face's box is at most `searched` plus the widening on each side, so it holds at
    // most floor(that) + 1 samples of one offset a row: three at one sample (2 + 1/8 pixels), two
    // at more (at most 1 + 1/8). The window of pixels looked at a sample is that wide.
    const double widest = searched + 2.0 * widening;
    if (widest < 2.0)
        searchWindow<2>(samples, sampleCount, widthPixels, heightPixels, n, a, b, c, loX, loY, hiX, hiY, holds, wide);
    else
        searchWindow<3>(samples, sampleCount, widthPixels, heightPixels, n, a, b, c, loX, loY, hiX, hiY, holds, wide);
    for (int i = 0; i < n; ++i)
        l.found[i] = uint8_t(big[i] ? kMayCover : (wide[i] ? kSearchOnOwn : (holds[i] ? kMayCover : kNoSample)));
}

}  // namespace HWY_NAMESPACE
}  // namespace cuberille::voxel
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace cuberille::voxel {

HWY_EXPORT(cameraFacingSidesOnTarget);
HWY_EXPORT(projectVoxelCornersOnTarget);

void cameraFacingSides(const VoxelFacingFrame& frame, const uint32_t* packed, int count, uint8_t* sides) {
    if (count > 0) HWY_DYNAMIC_DISPATCH(cameraFacingSidesOnTarget)(frame, packed, count, sides);
}

HWY_EXPORT(searchFaceSamplesOnTarget);
HWY_EXPORT(pretestHiddenDepthOnTarget);

void pretestHiddenDepth(const HiddenDepthFrame& frame, const VoxelCornerLanes& lanes, uint8_t* pretest) {
    if (lanes.count <= 0) return;
    const DepthFootprint& d = *frame.depth;
    if (d.blockSizePixels != raster::kBlockSizePixels || d.blocksX <= 0 || d.blocksY <= 0 ||
        d.farthestKey.size() < size_t(d.blocksX) * size_t(d.blocksY)) {
        // Not the rasterizer's blocks, or no blocks: the one-voxel test decides every voxel.
        for (int i = 0; i < lanes.count; ++i) pretest[i] = kTestDepthOnOwn;
        return;
    }
    HWY_DYNAMIC_DISPATCH(pretestHiddenDepthOnTarget)(frame, lanes, pretest);
}

void projectVoxelCorners(const VoxelCornerFrame& frame, VoxelCornerLanes& lanes) {
    if (lanes.count > 0) HWY_DYNAMIC_DISPATCH(projectVoxelCornersOnTarget)(frame, lanes);
}

void searchFaceSamples(const SampleFootprint& footprint, double marginPixels, double searchedFacePixels,
                       FaceQuadLanes& lanes) {
    if (lanes.count <= 0) return;
    HWY_DYNAMIC_DISPATCH(searchFaceSamplesOnTarget)(footprint.samples.data(), int(footprint.samples.size()),
                                                    footprint.widthPixels, footprint.heightPixels, marginPixels,
                                                    searchedFacePixels, lanes);
}

}  // namespace cuberille::voxel
#endif  // HWY_ONCE
