#pragma once
// The voxel grid a model is voxelized into (Chajdas 2015, section 3.1.1): a cube of
// `resolution`³ voxels whose corner is the model bounds' minimum and whose edge is their
// largest extent, so the model fits with a uniform scale. The voxelizer works in the grid's
// unit cube, where the root octree node is [0, 1]³; tests compute the same transform.

#include <algorithm>
#include <cstdint>

#include <glm/glm.hpp>

namespace cuberille::voxel {

/// Voxelization resolutions are powers of two, so every octree level halves exactly.
constexpr uint32_t kMinResolution = 2;
constexpr uint32_t kMaxResolution = 65536;

inline bool isValidResolution(uint32_t r) {
    return r >= kMinResolution && r <= kMaxResolution && (r & (r - 1)) == 0;
}

inline int log2OfPowerOfTwo(uint32_t r) {
    int d = 0;
    while ((1u << d) < r) ++d;
    return d;
}

struct VoxelGrid {
    uint32_t resolution = 0;
    glm::dvec3 origin{0.0};  // model units
    double extent = 1.0;     // model units along each axis

    /// The grid around an axis-aligned box: origin at its minimum, edge its largest extent (1 for
    /// a box of no extent, so a single point still voxelizes).
    static VoxelGrid fitting(const glm::dvec3& min, const glm::dvec3& max, uint32_t resolution) {
        const glm::dvec3 size = max - min;
        double e = std::max({size.x, size.y, size.z});
        if (!(e > 0.0)) e = 1.0;
        return {resolution, min, e};
    }

    double voxelSize() const { return extent / double(resolution); }

    /// Model point to the grid's unit cube [0, 1]³ (in double, the voxelizer's only rounding
    /// of input coordinates).
    glm::dvec3 toUnitCube(const glm::vec3& p) const { return (glm::dvec3(p) - origin) / extent; }
};

}  // namespace cuberille::voxel
