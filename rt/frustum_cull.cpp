#include "rt/frustum_cull.h"

#include <algorithm>

namespace cuberille::rt {
namespace {

enum class BoxSide { Outside, Inside, Straddling };

/// The box's corners farthest along and against each plane's normal decide it (the p- and
/// n-vertex test): outside if the farthest-along corner is behind a plane, inside if the
/// farthest-against corner is in front of all.
BoxSide classify(const Aabb& box, const FrustumPlanes& planes) {
    bool inside = true;
    for (const glm::vec4& p : planes) {
        const glm::vec3 n(p);
        const glm::vec3 along(n.x >= 0 ? box.hi.x : box.lo.x, n.y >= 0 ? box.hi.y : box.lo.y, n.z >= 0 ? box.hi.z : box.lo.z);
        const glm::vec3 against(n.x >= 0 ? box.lo.x : box.hi.x, n.y >= 0 ? box.lo.y : box.hi.y, n.z >= 0 ? box.lo.z : box.hi.z);
        if (glm::dot(n, along) + p.w < 0.0f) return BoxSide::Outside;
        if (glm::dot(n, against) + p.w < 0.0f) inside = false;
    }
    return inside ? BoxSide::Inside : BoxSide::Straddling;
}

}  // namespace

FrustumPlanes frustumPlanes(const glm::mat4& m) {
    // Rows of the matrix (glm is column-major: m[column][row]).
    auto row = [&](int r) { return glm::vec4(m[0][r], m[1][r], m[2][r], m[3][r]); };
    const glm::vec4 x = row(0), y = row(1), z = row(2), w = row(3);
    return {w + x, w - x, w + y, w - y, z, w - z};
}

std::vector<uint32_t> trianglesInFrustum(const Bvh& bvh, const TriangleMeshView& mesh, const FrustumPlanes& planes,
                                         FrustumCullCounters* counters) {
    std::vector<uint32_t> visible;
    if (bvh.empty()) return visible;
    FrustumCullCounters local;
    uint32_t stack[kMaxBvhDepth + 1];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const uint32_t index = stack[--top];
        const BvhNode& node = bvh.nodes[index];
        ++local.nodesVisited;
        const BoxSide side = classify(node.box(), planes);
        if (side == BoxSide::Outside) {
            ++local.subtreesRejected;
            continue;
        }
        if (side == BoxSide::Inside) {
            ++local.subtreesAccepted;
            const uint32_t first = bvh.subtreeFirst[index];
            visible.insert(visible.end(), bvh.primitiveIndices.begin() + first,
                           bvh.primitiveIndices.begin() + first + bvh.subtreeCount[index]);
            continue;
        }
        if (node.isLeaf()) {
            for (uint32_t i = node.first; i < node.first + node.primitiveCount; ++i) {
                const uint32_t triangle = bvh.primitiveIndices[i];
                if (classify(mesh.triangleBounds(triangle), planes) != BoxSide::Outside) visible.push_back(triangle);
            }
            continue;
        }
        stack[top++] = node.first + 1;
        stack[top++] = node.first;
    }
    std::sort(visible.begin(), visible.end());
    if (counters) *counters = local;
    return visible;
}

std::vector<uint32_t> trianglesInFrustumBruteForce(const TriangleMeshView& mesh, const FrustumPlanes& planes) {
    std::vector<uint32_t> visible;
    for (uint32_t t = 0; t < mesh.triangleCount(); ++t)
        if (classify(mesh.triangleBounds(t), planes) != BoxSide::Outside) visible.push_back(t);
    return visible;
}

}  // namespace cuberille::rt
