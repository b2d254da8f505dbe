#pragma once
// Frustum culling through a BVH, node by node: a box outside one plane drops its whole subtree,
// a box inside all six takes its whole subtree without another test, and only boxes that
// straddle a plane are opened. In leaves each triangle's own box is tested, so the result is
// exactly what testing every triangle's box would give (trianglesInFrustumBruteForce).

#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "rt/bvh.h"
#include "rt/triangle_mesh.h"

namespace cuberille::rt {

/// Six planes (a, b, c, d), inside where a x + b y + c z + d >= 0.
using FrustumPlanes = std::array<glm::vec4, 6>;

/// The planes of a clip-space volume -w <= x, y <= w, 0 <= z <= w (Direct3D/Vulkan depth,
/// DESIGN.md) from its view-projection matrix (Gribb and Hartmann's extraction).
FrustumPlanes frustumPlanes(const glm::mat4& viewProjection);

struct FrustumCullCounters {
    uint64_t nodesVisited = 0;
    uint64_t subtreesAccepted = 0;  // wholly inside: taken without opening
    uint64_t subtreesRejected = 0;  // wholly outside one plane
};

/// Ids of the triangles whose boxes are not outside any plane, ascending (submission order, so
/// a draw of the survivors gives the same image as a draw of all).
std::vector<uint32_t> trianglesInFrustum(const Bvh& bvh, const TriangleMeshView& mesh, const FrustumPlanes& planes,
                                         FrustumCullCounters* counters = nullptr);

std::vector<uint32_t> trianglesInFrustumBruteForce(const TriangleMeshView& mesh, const FrustumPlanes& planes);

}  // namespace cuberille::rt
