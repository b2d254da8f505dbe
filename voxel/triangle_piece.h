#pragma once
// The clipped piece of a triangle inside one octree node (Chajdas 2015, section 3.1.1), in that
// node's own unit cube. Splitting a node clips the piece at the mid-plane 0.5 of each axis in
// turn and rescales each half to its child's unit cube (x -> 2x or 2x - 1, both exact in
// binary floating point), so every test at every depth compares against the same constants and
// no error accumulates from subdividing the domain.
//
// Pieces are closed convex polygons (a triangle clipped by a box has at most 9 vertices), and
// may be degenerate: a triangle that only touches a plane leaves a segment or a single point on
// the far side, which still touches the voxel there (conservative voxelization counts contact).
//
// Exactness: a clipped vertex lies exactly on the plane (its axis coordinate is set, not
// computed), and the other coordinates are computed as a + ((b - a)(m - a_axis)) / (b_axis -
// a_axis) from the edge's lower endpoint: the product and differences of grid-aligned inputs are
// exact, and a correctly rounded quotient is exact whenever the true crossing is representable,
// so triangles through voxel edges and corners clip without error and both halves of a split
// share bit-identical vertices.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include <glm/glm.hpp>

namespace cuberille::voxel {

struct PieceVertex {
    glm::dvec3 position;  // in the node's unit cube
    glm::dvec2 bary;      // weights of the triangle's vertices 1 and 2 (vertex 0: 1 - u - v)
};

struct TrianglePiece {
    static constexpr int kCapacity = 16;  // 9 in exact arithmetic; room for rounding's extras
    std::array<PieceVertex, kCapacity> v;
    int count = 0;

    void push(const PieceVertex& p) {
        if (count < kCapacity) v[count++] = p;
    }
    double minAlong(int axis) const {
        double m = v[0].position[axis];
        for (int i = 1; i < count; ++i) m = std::min(m, v[i].position[axis]);
        return m;
    }
    double maxAlong(int axis) const {
        double m = v[0].position[axis];
        for (int i = 1; i < count; ++i) m = std::max(m, v[i].position[axis]);
        return m;
    }
    /// Both corners of the bounding box in one pass over the vertices.
    void bounds(glm::dvec3& lo, glm::dvec3& hi) const {
        lo = hi = v[0].position;
        for (int i = 1; i < count; ++i) {
            lo = glm::min(lo, v[i].position);
            hi = glm::max(hi, v[i].position);
        }
    }
};

/// The crossing of edge a-b with the plane position[axis] = m, where a and b are strictly on
/// opposite sides. Computed from the endpoint lower on the axis, so the same edge gives the same
/// point whichever side is being kept.
inline PieceVertex crossingOf(PieceVertex a, PieceVertex b, int axis, double m) {
    if (a.position[axis] > b.position[axis]) std::swap(a, b);
    const double num = m - a.position[axis];
    const double den = b.position[axis] - a.position[axis];
    PieceVertex c;
    for (int k = 0; k < 3; ++k)
        c.position[k] = k == axis ? m : a.position[k] + ((b.position[k] - a.position[k]) * num) / den;
    c.bary = a.bary + ((b.bary - a.bary) * num) / den;
    return c;
}

/// Sutherland-Hodgman against one closed half-space: position[axis] <= m (keepAbove false) or
/// >= m (keepAbove true). Vertices on the plane are kept; crossings are added only for edges that
/// pass strictly through it.
inline void clipPiece(const TrianglePiece& in, int axis, double m, bool keepAbove, TrianglePiece& out) {
    out.count = 0;
    auto inside = [&](const PieceVertex& p) { return keepAbove ? p.position[axis] >= m : p.position[axis] <= m; };
    for (int i = 0; i < in.count; ++i) {
        const PieceVertex& a = in.v[i];
        const PieceVertex& b = in.v[(i + 1) % in.count];
        if (inside(a)) out.push(a);
        const double da = a.position[axis] - m, db = b.position[axis] - m;
        if ((da < 0 && db > 0) || (da > 0 && db < 0)) out.push(crossingOf(a, b, axis, m));
    }
}

/// How far (in the node's unit cube) a piece may be from a plane and still be treated as
/// touching it. Rounding in the crossings grows by 2 per level in local units and stays below
/// 1e-10 at depth 16; a piece this close to a boundary is sent to both sides, and the leaf decides
/// exactly (exact_overlap.h) whether the triangle really touches its voxel.
constexpr double kTouchEpsilon = 1.0 / double(1ull << 30);

/// The closed half of a piece on one side of the plane position[axis] = m: the whole piece, its
/// clipped part, or, when rounding leaves it within kTouchEpsilon of the plane without reaching
/// it, its vertices near the plane moved onto it (a point or segment of contact).
inline void halfOfPiece(const TrianglePiece& in, int axis, double m, bool keepAbove, double lo, double hi,
                        TrianglePiece& out) {
    out.count = 0;
    if (keepAbove ? lo >= m : hi <= m) {
        out = in;
        return;
    }
    if (keepAbove ? hi >= m : lo <= m) {
        clipPiece(in, axis, m, keepAbove, out);
        return;
    }
    for (int i = 0; i < in.count; ++i)
        if (std::abs(in.v[i].position[axis] - m) <= kTouchEpsilon) {
            PieceVertex v = in.v[i];
            v.position[axis] = m;
            out.push(v);
        }
}

/// Splits a piece at the mid-plane of one axis into the closed lower and upper halves, each
/// rescaled to its child's unit cube. A half the piece does not reach (within kTouchEpsilon) is
/// left with count 0.
inline void splitPieceAtMidPlane(const TrianglePiece& in, int axis, TrianglePiece& lower, TrianglePiece& upper) {
    const double lo = in.minAlong(axis), hi = in.maxAlong(axis);
    lower.count = upper.count = 0;
    if (lo <= 0.5 + kTouchEpsilon) {
        halfOfPiece(in, axis, 0.5, false, lo, hi, lower);
        for (int i = 0; i < lower.count; ++i) lower.v[i].position[axis] *= 2.0;
    }
    if (hi >= 0.5 - kTouchEpsilon) {
        halfOfPiece(in, axis, 0.5, true, lo, hi, upper);
        for (int i = 0; i < upper.count; ++i) upper.v[i].position[axis] = upper.v[i].position[axis] * 2.0 - 1.0;
    }
}

/// Whether rounding could decide if the piece's triangle touches the voxel: the piece lies within
/// kTouchEpsilon of one face plane. Otherwise it reaches into the voxel further than any rounding
/// error and the triangle certainly touches it.
inline bool pieceOnlyGrazesCube(const TrianglePiece& p) {
    glm::dvec3 lo, hi;
    p.bounds(lo, hi);
    return glm::any(glm::lessThanEqual(hi, glm::dvec3(kTouchEpsilon))) ||
           glm::any(glm::greaterThanEqual(lo, glm::dvec3(1.0 - kTouchEpsilon)));
}

/// The piece's area (in its cube's units squared) and the barycentric weights at its area
/// centroid (the vertex average when it has no area), where its attributes are evaluated:
/// attributes are linear, so their value there times the area is their exact integral over the
/// piece. One pass over the fan.
inline double pieceAreaAndCentroid(const TrianglePiece& p, glm::dvec2& centroidBary) {
    glm::dvec3 normalSum(0.0);
    glm::dvec2 weighted(0.0);
    double fanArea = 0.0;
    for (int i = 1; i + 1 < p.count; ++i) {
        const glm::dvec3 c = glm::cross(p.v[i].position - p.v[0].position, p.v[i + 1].position - p.v[0].position);
        const double a = glm::length(c);
        normalSum += c;
        weighted += a * (p.v[0].bary + p.v[i].bary + p.v[i + 1].bary);
        fanArea += a;
    }
    if (fanArea > 0.0) {
        centroidBary = weighted / (3.0 * fanArea);
    } else {
        glm::dvec2 avg(0.0);
        for (int i = 0; i < p.count; ++i) avg += p.v[i].bary;
        centroidBary = avg / double(p.count);
    }
    return 0.5 * glm::length(normalSum);
}

/// Round to nearest, halves away from zero, without a libm call (std::llround is one per use in
/// the leaf loop). Exact for the magnitudes of leaf sums (below 2^52).
inline int64_t roundToInt64(double x) { return int64_t(x < 0.0 ? x - 0.5 : x + 0.5); }

}  // namespace cuberille::voxel
