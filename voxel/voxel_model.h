#pragma once
// Surface voxels as every later stage reads them (Chajdas 2015, section 3.1.1): gathered into
// blocks of at most 64³ voxels, each voxel stored relative to its block, so its position takes
// 8 bits per axis. Per voxel three 32-bit words, kept as separate arrays (the renderer reads
// positions and face masks far more often than attributes):
//   packed:  x (bits 0-7), y (8-15), z (16-23) in the block, active face mask (24-29)
//   normal:  10-10-10 signed normalised (voxel/packing.h)
//   color:   RGBA8, RGB sRGB-encoded
// Each block also keeps the source triangles clipped to it, for hybrid rendering near the
// camera (section 4.7).

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "voxel/voxel_grid.h"

namespace cuberille::voxel {

/// Face bits of the active face mask, in the order +x, -x, +y, -y, +z, -z.
enum FaceBit : uint8_t {
    kFacePosX = 1u << 0,
    kFaceNegX = 1u << 1,
    kFacePosY = 1u << 2,
    kFaceNegY = 1u << 3,
    kFacePosZ = 1u << 4,
    kFaceNegZ = 1u << 5,
};
constexpr uint8_t kAllFaces = 0x3F;

constexpr uint32_t kBlockSize = 64;  // voxels per block edge (at most; a grid smaller than 64 is one block)

enum class Separability : uint32_t { Conservative = 0, TwentySix = 26, Six = 6 };

inline const char* separabilityName(Separability s) {
    switch (s) {
        case Separability::Conservative: return "conservative";
        case Separability::TwentySix: return "26";
        case Separability::Six: return "6";
    }
    return "?";
}

inline uint32_t packVoxel(uint32_t x, uint32_t y, uint32_t z, uint8_t faceMask) {
    return x | (y << 8) | (z << 16) | (uint32_t(faceMask & kAllFaces) << 24);
}
inline glm::uvec3 voxelPositionInBlock(uint32_t packed) {
    return {packed & 0xFFu, (packed >> 8) & 0xFFu, (packed >> 16) & 0xFFu};
}
inline uint8_t voxelFaceMask(uint32_t packed) { return uint8_t((packed >> 24) & kAllFaces); }

/// A source triangle (or a triangle of the fan of a clipped piece) inside one block, in model
/// units, with per-vertex 10-10-10 normals and RGBA8 colours.
struct SourceTriangle {
    glm::vec3 position[3];
    uint32_t normal[3];
    uint32_t color[3];
};

struct VoxelBlock {
    uint32_t level = 0;     // 0: the finest; each level halves the resolution (lod/)
    glm::uvec3 coord{0};    // block position, in blocks, at its level
    std::vector<uint32_t> voxels, normals, colors;
    std::vector<SourceTriangle> triangles;
    glm::uvec3 tightMin{0}, tightMax{0};  // voxel bounds inside the block (inclusive)
    // Block octree (lod/lod_pyramid.h): the children at level - 1 are blocks
    // [firstChild, firstChild + popcount(childMask)) of the model, one per octant bit set.
    uint32_t firstChild = 0;
    uint8_t childMask = 0;
    // A block's counts as its file states them, set in a layout whose data is not loaded
    // (CvoxReader::layout): selection asks hasVoxels()/hasTriangles() of either kind of block.
    uint32_t layoutVoxels = 0, layoutTriangles = 0;

    size_t voxelCount() const { return voxels.size(); }
    /// Counts whether loaded or only stated in the layout.
    uint64_t totalVoxels() const { return voxels.empty() ? layoutVoxels : voxels.size(); }
    uint64_t totalTriangles() const { return triangles.empty() ? layoutTriangles : triangles.size(); }
    bool hasVoxels() const { return !voxels.empty() || layoutVoxels; }
    bool hasTriangles() const { return !triangles.empty() || layoutTriangles; }
};

struct VoxelModel {
    VoxelGrid grid;  // the finest level's grid
    uint32_t blockSize = kBlockSize;
    Separability separability = Separability::Conservative;
    bool hasColors = false;  // colours came from the source (otherwise white)
    std::vector<VoxelBlock> blocks;

    uint64_t voxelCount() const {
        uint64_t n = 0;
        for (const VoxelBlock& b : blocks) n += b.totalVoxels();
        return n;
    }
    uint64_t triangleCount() const {
        uint64_t n = 0;
        for (const VoxelBlock& b : blocks) n += b.totalTriangles();
        return n;
    }
    /// The voxel's grid coordinates at its block's level.
    glm::uvec3 gridPosition(const VoxelBlock& b, size_t voxel) const {
        return b.coord * blockSize + voxelPositionInBlock(b.voxels[voxel]);
    }
};

}  // namespace cuberille::voxel
