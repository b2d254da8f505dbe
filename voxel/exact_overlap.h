#pragma once
// The exact triangle/voxel touch test that settles the cases floating-point clipping cannot
// (Chajdas 2015 leaves these to rounding; here "conservative" means exactly the voxels whose
// closed box the closed triangle touches). The voxelizer snaps each triangle's unit-cube
// coordinates to a lattice of 2^-40 (far finer than float input, and every voxel boundary of a
// grid up to 2^16 lies on it), so the separating axis test runs on integers: coordinates fit in
// 41 bits, cross products in 83, projections in 125, inside a signed 128-bit integer.

#include <algorithm>
#include <cstdint>

#include <glm/glm.hpp>

namespace cuberille::voxel {

constexpr int kLatticeBits = 40;
constexpr double kLatticeScale = double(1ull << kLatticeBits);

struct LatticeTriangle {
    int64_t v[3][3];  // vertex, axis: unit-cube coordinate × 2^40
};

/// Separating axes: the three box normals, the triangle normal, and the nine cross products of
/// triangle edges with box axes. Closed sets: touching at a point is overlap. A zero axis (from a
/// degenerate triangle) separates nothing and is skipped; the remaining axes still decide segments
/// and points.
inline bool latticeTriangleTouchesBox(const LatticeTriangle& t, const int64_t lo[3], const int64_t hi[3]) {
    using I = __int128;
    auto separatedOn = [&](I ax, I ay, I az) {
        if (ax == 0 && ay == 0 && az == 0) return false;
        I tmin = 0, tmax = 0;
        for (int i = 0; i < 3; ++i) {
            const I p = ax * t.v[i][0] + ay * t.v[i][1] + az * t.v[i][2];
            tmin = i == 0 ? p : std::min(tmin, p);
            tmax = i == 0 ? p : std::max(tmax, p);
        }
        const I bmin = (ax >= 0 ? ax * lo[0] : ax * hi[0]) + (ay >= 0 ? ay * lo[1] : ay * hi[1]) +
                       (az >= 0 ? az * lo[2] : az * hi[2]);
        const I bmax = (ax >= 0 ? ax * hi[0] : ax * lo[0]) + (ay >= 0 ? ay * hi[1] : ay * lo[1]) +
                       (az >= 0 ? az * hi[2] : az * lo[2]);
        return tmax < bmin || tmin > bmax;
    };
    if (separatedOn(1, 0, 0) || separatedOn(0, 1, 0) || separatedOn(0, 0, 1)) return false;
    I e[3][3];
    for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k) e[i][k] = I(t.v[(i + 1) % 3][k]) - t.v[i][k];
    if (separatedOn(e[0][1] * e[1][2] - e[0][2] * e[1][1], e[0][2] * e[1][0] - e[0][0] * e[1][2],
                    e[0][0] * e[1][1] - e[0][1] * e[1][0]))
        return false;
    for (const auto& d : e)
        if (separatedOn(0, d[2], -d[1]) || separatedOn(-d[2], 0, d[0]) || separatedOn(d[1], -d[0], 0)) return false;
    return true;
}

/// Whether the triangle touches voxel `cell` of a grid of 2^leafDepth voxels per axis.
inline bool latticeTriangleTouchesVoxel(const LatticeTriangle& t, const glm::uvec3& cell, int leafDepth) {
    const int shift = kLatticeBits - leafDepth;
    const int64_t lo[3] = {int64_t(cell.x) << shift, int64_t(cell.y) << shift, int64_t(cell.z) << shift};
    const int64_t hi[3] = {int64_t(cell.x + 1) << shift, int64_t(cell.y + 1) << shift, int64_t(cell.z + 1) << shift};
    return latticeTriangleTouchesBox(t, lo, hi);
}

}  // namespace cuberille::voxel
