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

#include "voxel/voxel_model.h"

namespace cuberille::voxel {

struct FaceMesh {
    std::vector<glm::vec3> positions, normals, colors;  // model units; linear colours
    std::vector<uint32_t> indices;
    uint64_t voxels = 0, faces = 0;
    uint64_t facesBetweenSamples = 0;  // camera-facing active faces left out: they cover no sample

    void clear() {
        positions.clear(), normals.clear(), colors.clear(), indices.clear();
        voxels = faces = facesBetweenSamples = 0;
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

/// Appends the camera-facing active faces of every voxel of the block (or of the region); with a
/// footprint, only those that may cover one of its samples. overrideColor, when given, replaces
/// the voxels' colours (debug views).
void expandVoxelFaces(const VoxelModel& model, const BlockVoxels& block, const glm::dvec3& cameraPosition,
                      FaceMesh& out, const glm::vec3* overrideColor = nullptr, const VoxelRegion* region = nullptr,
                      const SampleFootprint* footprint = nullptr);
inline void expandVoxelFaces(const VoxelModel& model, const VoxelBlock& block, const glm::dvec3& cameraPosition,
                             FaceMesh& out, const glm::vec3* overrideColor = nullptr) {
    expandVoxelFaces(model, BlockVoxels::of(block), cameraPosition, out, overrideColor);
}

}  // namespace cuberille::voxel
