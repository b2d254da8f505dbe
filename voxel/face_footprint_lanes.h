#pragma once
// The footprint tests of voxel-face expansion in vector lanes (voxel/face_expansion.h,
// SampleFootprint): a run of voxels' eight corners projected to the window at once, then a run
// of their faces' quads searched for a sample position at once.
//
// Why: one voxel at a time, these tests were most of a voxel frame. On the 4096^3 dragon's zoom
// at 1280x720 and one sample, expansion was 62% of the process's samples (perf record), the
// corner projection (eight divides and their bounds in scalar double) a fifth of that and the
// faces' sample searches a third; a frame looks at about four faces for each one it draws.
// Here each step is a loop over the run's lanes, one element type each, which GCC vectorises for
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

/// Voxels, and faces, per run: the corner lanes (about 160 bytes a voxel) stay in the
/// first-level cache.
inline constexpr int kFootprintLanes = 128;

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

/// What a face's search found.
enum FaceSearch : uint8_t {
    kNoSample = 0,     // no sample position lies in the widened quad
    kMayCover = 1,     // one does, or the face is too large to search (kept without looking)
    kSearchOnOwn = 2,  // the lanes look at up to 3 x 3 pixels a sample: this face's box holds more
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
