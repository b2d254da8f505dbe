#pragma once
// The footprint tests of voxel-face expansion in vector lanes (voxel/face_expansion.h,
// SampleFootprint): a run of voxels' eight corners projected to the window at once, then a run
// of their faces' quads searched for a sample position at once.
//
// Why: one voxel at a time, these tests were most of a voxel frame. On the 4096^3 dragon's zoom
// at 1280x720 and one sample, expansion was 62% of the process's samples (perf record), the
// corner projection (eight divides and their bounds in scalar double) a fifth of that and the
// faces' sample searches a third; a frame looks at about four faces for each one it draws.
// Before either, which sides of each voxel face the camera, likewise. Here each step is a loop
// over the run's lanes, one element type each, which GCC vectorises for
// each instruction set (compiled once per set like the rasterizer's lanes, raster/instruction_set.h).
//
// The same decisions as the one-at-a-time tests, bit for bit: every value is computed in double
// with the scalar code's operations in its order (no contraction: -ffp-contract=off), minima and
// maxima as std::min and std::max choose, truncations as int() truncates
// (FaceFootprintLanes.* against references written one voxel and one sample at a time, per
// instruction set; the voxel renderer's image tests against drawing every face).

#include <cstdint>

#include <glm/glm.hpp>

namespace cuberille::voxel {

struct SampleFootprint;
struct DepthFootprint;

/// Voxels, and faces, per run: the corner lanes (about 160 bytes a voxel) stay in the
/// first-level cache.
inline constexpr int kFootprintLanes = 128;

/// What the facing test reads: the block's first voxel corner and a voxel's size at the block's
/// level (voxel/face_expansion.h, VoxelBoxes), and the camera, model units.
struct VoxelFacingFrame {
    glm::dvec3 blockOrigin{0.0}, camera{0.0};
    double voxelSize = 0.0;
};

/// For each of `count` packed voxels (voxel_model.h): the sides of its box the camera lies
/// beyond, as face bits (kFacePosX where the camera is beyond the high x side, and so on; at
/// most one per axis), whether or not those faces are active. The box is the scalar code's,
/// low corner origin + position x size and high corner that plus the size.
void cameraFacingSides(const VoxelFacingFrame& frame, const uint32_t* packed, int count, uint8_t* sides);

/// What the corner projection reads of a block and the frame: the clip position of the block's
/// first voxel corner and what one voxel step along each axis adds to it, and the viewport.
struct VoxelCornerFrame {
    glm::dvec4 origin{0.0}, step[3]{glm::dvec4(0.0), glm::dvec4(0.0), glm::dvec4(0.0)};
    double halfWidth = 0.0, halfHeight = 0.0;
    int widthPixels = 0, heightPixels = 0;
};

/// What became of a voxel's projection.
enum CornerProjection : uint8_t {
    kProjected = 0,         // every corner in front of the near plane: the window values hold
    kCrossesNearPlane = 1,  // some corner is not (w <= 0 or z < 0): the rasterizer clips its faces
    kOutsideViewport = 2,   // projected, and its box lies wholly outside the viewport (widened
                            // by kFootprintMarginPixels): it covers no sample
};

/// A run of voxels (positions inside their block, in voxels) and, after projectVoxelCorners,
/// their corners in window pixels: corner k at p + (k & 1, k >> 1 & 1, k >> 2 & 1), their box,
/// and the range of their window depths z / w and the least w.
struct VoxelCornerLanes {
    int count = 0;
    int32_t x[kFootprintLanes], y[kFootprintLanes], z[kFootprintLanes];
    double windowX[8][kFootprintLanes], windowY[8][kFootprintLanes];
    double loX[kFootprintLanes], loY[kFootprintLanes], hiX[kFootprintLanes], hiY[kFootprintLanes];
    double nearestZ[kFootprintLanes], farthestZ[kFootprintLanes], nearestW[kFootprintLanes];
    uint8_t projection[kFootprintLanes];  // CornerProjection
};

/// Projects the run's voxels (count of them). The values of a lane that crosses the near plane
/// are meaningless; every other lane's are those of the scalar projection.
void projectVoxelCorners(const VoxelCornerFrame& frame, VoxelCornerLanes& lanes);

/// Sixteen roundings of 2^-24: what bounds the error of the rasterizer's float clip z and w of a
/// corner, relative to the sum of |matrix entry x coordinate| of the row (cornerError).
inline constexpr double kTransformRounding = 0x1p-20;
/// The float depth plane's sum's roundings of terms up to 1 (hiddenDepthMargin).
inline constexpr double kPlaneRounding = 0x1p-21;

/// How far the rasterizer's float window depth of a corner can lie from the exact z / w found
/// here: the position rounded to float, the float matrix product (four products, three sums)
/// and the division are seven or eight roundings of 2^-24 relative to the terms' magnitudes;
/// 2^-20 of them (sixteen roundings, kTransformRounding) bounds the error of clip z and w, so of
/// z / w at most (Ez + |z / w| Ew) / w, with E = 2^-20 the sum of |matrix entry x coordinate|
/// of that row (clipZError, clipWError: over the block's largest coordinates).
inline double cornerError(double clipZError, double clipWError, double nearestZ, double farthestZ, double nearestW) {
    const double absNearest = nearestZ < 0.0 ? -nearestZ : nearestZ, absFarthest = farthestZ < 0.0 ? -farthestZ : farthestZ;
    const double zMagnitude = absNearest < absFarthest ? absFarthest : absNearest;  // std::max
    return (clipZError + zMagnitude * clipWError) / nearestW;
}

/// How far outside [nearestZ, farthestZ] the rasterizer's depth at a sample one of the voxel's
/// faces covers can lie, in window depth. Three sources, each bounded with room to spare:
/// - Each face corner's float window depth against the exact one: cornerError.
/// - Exactly evaluated, the depth plane at a covered sample is a convex combination of its
///   triangle's three vertex depths (the sample lies in the snapped triangle the plane was fit
///   to), so not outside the corners' range.
/// - The plane is stored and evaluated in float: z0 + gx X + gy Y, X and Y within the
///   triangle's sides L of the first vertex (raster/depth.h, setDepthPlane). The gradient is at
///   most 2 dz L / area2 (dz the vertices' depth range, area2 the snapped doubled area), so each
///   term is at most 2 dz R with R = L² / area2 (planeTermRatio). The gradients' float rounding,
///   the two products' and the two sums' are each at most 2^-24 of terms up to 2 dz R (or 1,
///   the depth at the origin), so together at most 2^-20 R dz + 2^-21. R is at most 2^24 for
///   any triangle of the tested size (L <= 2^12 subpixels: kDepthTestedVoxelPixels times sqrt 2,
///   under 16 pixels; area2 >= 1 subpixel², snapped vertices being integers): 16 dz, the bound
///   for a sliver; a face seen square on, of about a pixel, has R near 2, and its margin is then
///   about the corners' error alone.
inline double hiddenDepthMargin(double nearestZ, double farthestZ, double cornerError, double planeTermRatio) {
    const double depthRange = farthestZ - nearestZ + 2.0 * cornerError;
    return cornerError + 0x1p-20 * planeTermRatio * depthRange + kPlaneRounding;
}

/// The largest plane-term ratio R = L² / area2 the margin allows for (hiddenDepthMargin): the
/// bound for any triangle of the tested size, a sliver's.
inline constexpr double kLargestPlaneTermRatio = 0x1p24;

/// The depth key (raster/depth.h) of window depth z: clamped to [0, 1] as std::clamp does, signed.
inline double depthKeyOf(double z, double keySign) { return keySign * (z < 0.0 ? 0.0 : (1.0 < z ? 1.0 : z)); }

/// What the hidden-depth pre-test reads: the frame's depth footprint (its blocks must be the
/// rasterizer's 8x8) and the block's bounds on the corners' float error (cornerError).
struct HiddenDepthFrame {
    const DepthFootprint* depth = nullptr;
    double clipZError = 0.0, clipWError = 0.0;
};

/// What the pre-test found of a voxel.
enum DepthPretest : uint8_t {
    kNotDepthTested = 0,  // not projected, or wider or taller than kDepthTestedVoxelPixels
    kInFront = 1,         // not behind the footprint even with the least margin (plane-term ratio 0)
    kMayBeBehind = 2,     // behind it with the least margin: the voxel's own margin decides
    kTestDepthOnOwn = 3,  // its box meets more than 3 x 3 of the footprint's blocks
    kBehindWithAnyMargin = 4,  // behind it even with the largest margin (kLargestPlaneTermRatio)
};

/// The cheap part of the hidden-depth test of face_expansion.cpp for each projected voxel of the
/// run: is its nearest key, less the least margin (and less the largest), at or behind the
/// farthest key of every footprint block under its box widened by kFootprintMarginPixels?
void pretestHiddenDepth(const HiddenDepthFrame& frame, const VoxelCornerLanes& lanes, uint8_t* pretest);

/// What a face's search found.
enum FaceSearch : uint8_t {
    kNoSample = 0,     // no sample position lies in the widened quad
    kMayCover = 1,     // one does, or the face is too large to search (kept without looking)
    kSearchOnOwn = 2,  // the lanes look at up to 3 x 3 pixels a sample (2 x 2 where a searched
                       // face's box cannot hold more): this face's box holds more
};

/// A run of face quads (window pixels, corners in order around the face, either winding) and,
/// after searchFaceSamples, what was found for each.
struct FaceQuadLanes {
    int count = 0;
    double x[4][kFootprintLanes], y[4][kFootprintLanes];
    uint8_t found[kFootprintLanes];  // FaceSearch
};

/// For each quad of the run: kMayCover when its box is wider or taller than searchedFacePixels
/// or a sample of `footprint` lies in it with each edge moved outwards by marginPixels (as the
/// one-quad search of face_expansion.cpp decides), kNoSample when none does, kSearchOnOwn when
/// the lanes cannot tell (a box over three pixels wide, at any sample, which a quad under
/// searchedFacePixels + 2 marginPixels <= 2.125 pixels does not have).
void searchFaceSamples(const SampleFootprint& footprint, double marginPixels, double searchedFacePixels,
                       FaceQuadLanes& lanes);

}  // namespace cuberille::voxel
