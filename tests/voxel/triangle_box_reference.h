#pragma once
// Slow but sure: does a closed triangle touch a closed axis-aligned box? The separating axis
// theorem in exact integer arithmetic (coordinates on a fixed-point lattice, products in 128
// bits), so touching at a single point counts and no rounding decides anything. Degenerate
// triangles (segments, points) are handled by the same axes: a zero axis separates nothing and is
// skipped, and the box normals and edge cross products are enough for segments and points.

#include <algorithm>
#include <cstdint>

namespace cuberille::testing {

struct LatticePoint {
    int64_t x, y, z;
};

inline bool triangleTouchesBox(const LatticePoint (&v)[3], const LatticePoint& lo, const LatticePoint& hi) {
    using I = __int128;
    auto separatedOn = [&](I ax, I ay, I az) {
        if (ax == 0 && ay == 0 && az == 0) return false;
        I tmin = 0, tmax = 0;
        for (int i = 0; i < 3; ++i) {
            const I p = ax * v[i].x + ay * v[i].y + az * v[i].z;
            tmin = i == 0 ? p : std::min(tmin, p);
            tmax = i == 0 ? p : std::max(tmax, p);
        }
        // The box's extreme corners along the axis.
        const I bmin = (ax >= 0 ? ax * lo.x : ax * hi.x) + (ay >= 0 ? ay * lo.y : ay * hi.y) + (az >= 0 ? az * lo.z : az * hi.z);
        const I bmax = (ax >= 0 ? ax * hi.x : ax * lo.x) + (ay >= 0 ? ay * hi.y : ay * lo.y) + (az >= 0 ? az * hi.z : az * lo.z);
        return tmax < bmin || tmin > bmax;
    };
    if (separatedOn(1, 0, 0) || separatedOn(0, 1, 0) || separatedOn(0, 0, 1)) return false;
    const I e[3][3] = {{I(v[1].x) - v[0].x, I(v[1].y) - v[0].y, I(v[1].z) - v[0].z},
                       {I(v[2].x) - v[1].x, I(v[2].y) - v[1].y, I(v[2].z) - v[1].z},
                       {I(v[0].x) - v[2].x, I(v[0].y) - v[2].y, I(v[0].z) - v[2].z}};
    const I n[3] = {e[0][1] * e[1][2] - e[0][2] * e[1][1], e[0][2] * e[1][0] - e[0][0] * e[1][2],
                    e[0][0] * e[1][1] - e[0][1] * e[1][0]};
    if (separatedOn(n[0], n[1], n[2])) return false;
    for (const auto& d : e) {
        if (separatedOn(0, d[2], -d[1])) return false;  // d × x
        if (separatedOn(-d[2], 0, d[0])) return false;  // d × y
        if (separatedOn(d[1], -d[0], 0)) return false;  // d × z
    }
    return true;
}

}  // namespace cuberille::testing
