#pragma once
// Voxel-face expansion (Chajdas 2015, section 4.3): the software version of the vertex/geometry
// shader pair that turns a block's packed voxels into quads. Each voxel's position is unpacked
// from its block; of its active faces, only those facing the camera are emitted (at most three
// per voxel: the camera sees +x only from beyond the voxel's +x side, and so on), each as two
// triangles whose four corners all carry the voxel's normal and colour, so nothing varies
// across a face (flat attributes, as the paper's geometry shader emits them).

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "raster/uninitialized_allocator.h"
#include "voxel/voxel_model.h"

namespace cuberille::voxel {

struct FaceMesh {
    // Sized without writing their new elements (raster/uninitialized_allocator.h): expansion
    // makes room for a run's faces and then writes every element of it.
    raster::UninitializedVector<glm::vec3> positions, normals, colors;  // model units; linear colours
    raster::UninitializedVector<uint32_t> indices;
    uint64_t voxels = 0, faces = 0;
    uint64_t facesBetweenSamples = 0;  // camera-facing active faces left out: they cover no sample
    uint64_t facesBehindDepth = 0;     // ... left out: their voxel lies behind what is drawn (DepthFootprint)

    void clear() {
        positions.clear(), normals.clear(), colors.clear(), indices.clear();
        voxels = faces = facesBetweenSamples = facesBehindDepth = 0;
    }
};

/// Where the frame's samples are, so expansion can leave out faces that cover none of them: the
/// small-primitive culling a GPU does before set-up, done here before a face costs four vertices.
/// At pixel error 1 a voxel is smaller than a pixel, and many camera-facing faces fall between
/// sample positions (on the dragon at 1280x720, one sample: 409k of 700k): the rasterizer would
/// transform, set up and drop every one of them. A face is left out only when no sample lies in
/// its projected quad widened by kFootprintMarginPixels on every side, so the image is the same
/// bits as drawing it (VoxelFootprint.LeavingOutFacesBetweenSamplesLeavesTheImageBitForBit).
struct SampleFootprint {
    glm::dmat4 clipFromModel{1.0};  // the draw's matrix (Direct3D clip space: 0 <= z <= w)
    int widthPixels = 0, heightPixels = 0;
    std::vector<glm::dvec2> samples;  // the pattern's positions, pixels from a pixel's top-left corner
};

/// How far a face's projected quad is widened before asking whether it holds a sample. The
/// rasterizer projects the face's float corners with the float matrix and snaps them to 1/256
/// pixel; this test projects the exact corners in double. The two differ by float rounding
/// (relative 2^-24 of the clip coordinates: a thousandth of a pixel at 4K for any camera this
/// renderer frames) plus half a subpixel (1/512 pixel); 1/16 pixel covers both many times over.
constexpr double kFootprintMarginPixels = 1.0 / 16.0;

/// What the frame's depth buffer already holds, coarsely, so expansion can leave out voxels behind
/// it: the same-frame half of hierarchical-Z occlusion culling (Chajdas 2015, section 4.5, does
/// it per block from the last frame; this is per voxel, from the blocks drawn before in this
/// frame). Voxel faces are drawn with the depth test alone deciding what shows: the dragon at
/// pixel error 1 drew 2.88 faces per covered pixel, behind nearer surfaces of the model, where one
/// shows (2.35 with this; docs/performance.md). Blocks are drawn front to back in chunks; after
/// each chunk the rasterizer's hierarchical Z is made exact
/// (raster::Pipeline::flushAndTightenHierarchicalDepth) and copied here, and a later voxel whose
/// nearest depth lies behind the farthest depth of every 8x8 block under it cannot pass a LESS
/// test anywhere, so leaving it out leaves the image the same bits (VoxelHiddenDepth.*).
struct DepthFootprint {
    int blockSizePixels = 8;  // raster::kBlockSizePixels
    int blocksX = 0, blocksY = 0;
    float keySign = 1.0f;  // the stored key is keySign times the window depth (raster/depth.h)
    std::vector<float> farthestKey;  // per block of the image, row-major: no sample holds a key above it
};

/// Voxels whose projected box is wider or taller than this many pixels are not tested against a
/// DepthFootprint. Bounding the faces' size bounds the float error of the rasterizer's depth
/// plane (hiddenDepthMargin in the source): their triangles' sides are then under 16 pixels
/// (2^12 subpixels), and a plane evaluated anywhere in a snapped triangle of any area is off by at
/// most a few times the triangle's own depth range. At pixel error 1 a voxel is about a pixel;
/// voxels seen larger are near the camera, where little lies in front of them.
constexpr double kDepthTestedVoxelPixels = 8.0;

/// The world box of one voxel of a block (at the block's level).
struct VoxelBoxes {
    glm::dvec3 blockOrigin;  // model units
    double voxelSize;        // model units, at the block's level

    VoxelBoxes(const VoxelModel& m, uint32_t level, const glm::uvec3& coord)
        : voxelSize(m.grid.voxelSize() * double(1u << level)) {
        blockOrigin = m.grid.origin + glm::dvec3(coord) * double(m.blockSize) * voxelSize;
    }
    VoxelBoxes(const VoxelModel& m, const VoxelBlock& b) : VoxelBoxes(m, b.level, b.coord) {}
    glm::dvec3 lowCorner(const glm::uvec3& local) const { return blockOrigin + glm::dvec3(local) * voxelSize; }
};

/// A block's voxel arrays wherever they live: in a VoxelBlock, or in a streaming pool (lod/).
struct BlockVoxels {
    uint32_t level = 0;
    glm::uvec3 coord{0};
    std::span<const uint32_t> voxels, normals, colors;

    static BlockVoxels of(const VoxelBlock& b) { return {b.level, b.coord, b.voxels, b.normals, b.colors}; }
};

/// Voxel positions [lo, hi) inside a block. When streaming, a resident ancestor stands in for a
/// missing block by drawing only the voxels over that block's cell; the faces on the cell's sides
/// are drawn whether active or not (a skirt, as at block boundaries), so the stand-in closes
/// against the finer blocks around it.
struct VoxelRegion {
    glm::uvec3 lo{0}, hi{0};
};

/// The four corners of the face on `axis` at the high (positive) or low side of the box [lo, hi],
/// counter-clockwise seen from outside: a face's quad is triangles (0, 1, 2) and (0, 2, 3).
void faceCorners(const glm::dvec3& lo, const glm::dvec3& hi, int axis, bool positive, glm::dvec3 (&c)[4]);

/// Appends the camera-facing active faces of every voxel of the block (or of the region); with a
/// footprint, only those that may cover one of its samples, and with a depth footprint as well,
/// only those of voxels not behind it, nor, with testWithinBlock, behind the block's own nearer
/// voxels (only for faces the caller draws writing depth: a voxel is left out because nearer
/// faces of its block will be in the depth buffer). overrideColor, when given, replaces the
/// voxels' colours (debug views).
void expandVoxelFaces(const VoxelModel& model, const BlockVoxels& block, const glm::dvec3& cameraPosition,
                      FaceMesh& out, const glm::vec3* overrideColor = nullptr, const VoxelRegion* region = nullptr,
                      const SampleFootprint* footprint = nullptr, const DepthFootprint* depth = nullptr,
                      bool testWithinBlock = false);
inline void expandVoxelFaces(const VoxelModel& model, const VoxelBlock& block, const glm::dvec3& cameraPosition,
                             FaceMesh& out, const glm::vec3* overrideColor = nullptr) {
    expandVoxelFaces(model, BlockVoxels::of(block), cameraPosition, out, overrideColor);
}

}  // namespace cuberille::voxel
