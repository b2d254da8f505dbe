#pragma once
// Which triangles of a mesh share an edge: what a silhouette needs (the edge between a triangle
// that faces a viewpoint and one that faces away). The shadow stage uses it to keep conservative
// thin-caster marking to the triangles at a silhouette from the light, as Lauterbach (section
// 6.3) suggests: a thin triangle inside a sheet the light sees whole is not missed by the map,
// whose texels sample its neighbours.
//
// Vertices are matched by position, not index: meshes split vertices along UV and normal seams,
// and a seam is no silhouette. An edge is shared when exactly two triangles use it, in opposite
// directions (consistent winding); every other edge (a boundary, a non-manifold fan, flipped
// winding, a collapsed edge) is open, and its ends are always treated as on a silhouette.
//
// Determinism: ids and edges come from sorts and prefix sums over indices alone.

#include <cstdint>
#include <vector>

#include "rt/triangle_mesh.h"

namespace cuberille::rt {

struct MeshAdjacency {
    struct SharedEdge {
        uint32_t first, second;  // the two triangles
        uint32_t from, to;       // the edge's ends, as position ids
    };
    std::vector<uint32_t> positionId;  // per vertex index: its position's id
    uint32_t positionCount = 0;
    std::vector<SharedEdge> shared;
    std::vector<uint32_t> openPositions;  // position ids at an end of some open edge, ascending

    /// A mesh whose adjacency was never built: every vertex is open.
    bool empty() const { return positionId.empty(); }
};

MeshAdjacency buildMeshAdjacency(const TriangleMeshView& mesh);

}  // namespace cuberille::rt
