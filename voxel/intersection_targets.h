#pragma once
// Intersection targets (Laine 2013, as used in Chajdas 2015, section 3.1.2): the voxels of a
// conservative voxelization are pruned to a thinner set that still separates inside from
// outside, by keeping only voxels whose piece of surface meets a target inside the voxel.
//
//  - 6-separating: the three axis lines through the voxel centre (the "crosshair"). A 6-connected
//    path of voxels is covered by centre-to-face-centre-to-centre segments, each half inside one
//    voxel's crosshair, so a surface it crosses marks one of those voxels.
//  - 26-separating: the four cube diagonals. Any two 26-neighbours share a corner, and the
//    half-diagonals centre-corner-centre join them, so the same argument covers 26-paths.
//
// Each test is a point-in-convex-polygon test after projecting the piece along the target line:
// the piece lies inside the voxel, so meeting the line means meeting the target segment.

#include "voxel/triangle_piece.h"

namespace cuberille::voxel {

/// Whether the closed convex polygon of the projected points contains q. Projections may be
/// degenerate (a segment or a point when the piece is parallel to the line): then every edge
/// orientation is zero exactly when q is on the segment's line, and the bounding box decides.
template <class Project>
bool projectionContains(const TrianglePiece& p, const glm::dvec2& q, Project&& project) {
    glm::dvec2 pts[TrianglePiece::kCapacity];
    glm::dvec2 lo(1e300), hi(-1e300);
    for (int i = 0; i < p.count; ++i) {
        pts[i] = project(p.v[i].position);
        lo = glm::min(lo, pts[i]);
        hi = glm::max(hi, pts[i]);
    }
    if (q.x < lo.x || q.x > hi.x || q.y < lo.y || q.y > hi.y) return false;
    bool positive = false, negative = false;
    for (int i = 0; i < p.count; ++i) {
        const glm::dvec2 e = pts[(i + 1) % p.count] - pts[i];
        const glm::dvec2 d = q - pts[i];
        const double side = e.x * d.y - e.y * d.x;
        positive |= side > 0;
        negative |= side < 0;
    }
    return !(positive && negative);
}

/// The piece (in the voxel's unit cube) meets an axis line through the centre.
inline bool pieceMeetsCrosshair(const TrianglePiece& p) {
    const glm::dvec2 c(0.5, 0.5);
    return projectionContains(p, c, [](const glm::dvec3& v) { return glm::dvec2(v.y, v.z); }) ||  // x line
           projectionContains(p, c, [](const glm::dvec3& v) { return glm::dvec2(v.x, v.z); }) ||  // y line
           projectionContains(p, c, [](const glm::dvec3& v) { return glm::dvec2(v.x, v.y); });   // z line
}

/// The piece meets one of the four diagonals. Each projection is a linear map whose kernel is the
/// diagonal's direction, so the whole diagonal lands on the centre's image.
inline bool pieceMeetsDiagonals(const TrianglePiece& p) {
    return projectionContains(p, {0.0, 0.0}, [](const glm::dvec3& v) { return glm::dvec2(v.x - v.y, v.y - v.z); }) ||  // (1,1,1)
           projectionContains(p, {0.0, 1.0}, [](const glm::dvec3& v) { return glm::dvec2(v.x - v.y, v.y + v.z); }) ||  // (1,1,-1)
           projectionContains(p, {1.0, 1.0}, [](const glm::dvec3& v) { return glm::dvec2(v.x + v.y, v.y + v.z); }) ||  // (1,-1,1)
           projectionContains(p, {1.0, 0.0}, [](const glm::dvec3& v) { return glm::dvec2(v.x + v.y, v.y - v.z); });   // (-1,1,1)
}

}  // namespace cuberille::voxel
