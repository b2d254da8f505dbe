#pragma once
// Morton (Z-order) codes of 3D grid positions: x in bit 0, y in bit 1, z in bit 2, then the next
// bit of each. Octant order at every octree level (x in bit 0 of the octant) is Morton order, so
// walking an octree child by child, sorting voxels by code and ordering blocks all agree: the
// voxelizer, iso-surfaces, simplification and the block octree share this one order.

#include <cstdint>

#include <glm/glm.hpp>

namespace cuberille::voxel {

/// The bits of v (up to 21) spread to every third bit.
inline uint64_t spreadBits3(uint32_t v) {
    uint64_t x = v & 0x1FFFFF;
    x = (x | x << 32) & 0x1F00000000FFFFull;
    x = (x | x << 16) & 0x1F0000FF0000FFull;
    x = (x | x << 8) & 0x100F00F00F00F00Full;
    x = (x | x << 4) & 0x10C30C30C30C30C3ull;
    x = (x | x << 2) & 0x1249249249249249ull;
    return x;
}

/// Up to 21 bits per axis.
inline uint64_t mortonOf(const glm::uvec3& p) { return spreadBits3(p.x) | spreadBits3(p.y) << 1 | spreadBits3(p.z) << 2; }

/// spreadBits3 undone: every third bit of v, from bit 0, gathered.
inline uint32_t compactBits3(uint64_t v) {
    uint64_t x = v & 0x1249249249249249ull;
    x = (x | x >> 2) & 0x10C30C30C30C30C3ull;
    x = (x | x >> 4) & 0x100F00F00F00F00Full;
    x = (x | x >> 8) & 0x1F0000FF0000FFull;
    x = (x | x >> 16) & 0x1F00000000FFFFull;
    x = (x | x >> 32) & 0x1FFFFFull;
    return uint32_t(x);
}

/// mortonOf undone.
inline glm::uvec3 positionOfMorton(uint64_t code) { return {compactBits3(code), compactBits3(code >> 1), compactBits3(code >> 2)}; }

}  // namespace cuberille::voxel
