// Frustum culling through the BVH keeps exactly the triangles a per-triangle test keeps, and
// opens few nodes to do it.

#include <gtest/gtest.h>

#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "rt/bvh_build.h"
#include "rt/frustum_cull.h"
#include "tests/rt/rt_test_support.h"

namespace cuberille::rt {
namespace {

TEST(FrustumCull, KeepsExactlyWhatTheBruteForceTestKeeps) {
    const testing::OwnedMesh soup = testing::randomSoup(30000, 8, 0.05f);
    const Bvh bvh = buildBvh(soup.view());
    std::mt19937 rng(8);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    uint64_t accepted = 0, rejected = 0;
    for (int i = 0; i < 40; ++i) {
        const glm::vec3 eye(3.0f * unit(rng), 3.0f * unit(rng), 3.0f * unit(rng));
        const glm::vec3 target(0.5f * unit(rng), 0.5f * unit(rng), 0.5f * unit(rng));
        const float fov = glm::radians(20.0f + 30.0f * (unit(rng) + 1.0f));
        const glm::mat4 viewProjection =
            glm::perspectiveRH_ZO(fov, 1.5f, 0.1f, 2.0f + 3.0f * (unit(rng) + 1.0f)) * glm::lookAtRH(eye, target, glm::vec3(0, 1, 0));
        const FrustumPlanes planes = frustumPlanes(viewProjection);
        FrustumCullCounters counters;
        const std::vector<uint32_t> kept = trianglesInFrustum(bvh, soup.view(), planes, &counters);
        EXPECT_EQ(kept, trianglesInFrustumBruteForce(soup.view(), planes)) << "camera " << i;
        EXPECT_LT(counters.nodesVisited, bvh.nodes.size());
        accepted += counters.subtreesAccepted;
        rejected += counters.subtreesRejected;
    }
    EXPECT_GT(accepted, 0u);
    EXPECT_GT(rejected, 0u);
}

TEST(FrustumCull, PlanesMatchTheClipVolume) {
    // A point is inside all six planes exactly when its clip coordinates are inside the volume.
    const glm::mat4 viewProjection = glm::perspectiveRH_ZO(glm::radians(60.0f), 1.0f, 0.5f, 10.0f) *
                                     glm::lookAtRH(glm::vec3(0, 0, 5), glm::vec3(0), glm::vec3(0, 1, 0));
    const FrustumPlanes planes = frustumPlanes(viewProjection);
    std::mt19937 rng(2);
    std::uniform_real_distribution<float> unit(-8.0f, 8.0f);
    for (int i = 0; i < 5000; ++i) {
        const glm::vec3 p(unit(rng), unit(rng), unit(rng));
        const glm::vec4 c = viewProjection * glm::vec4(p, 1.0f);
        const bool inClip = c.w > 0 && std::abs(c.x) <= c.w && std::abs(c.y) <= c.w && c.z >= 0 && c.z <= c.w;
        bool inPlanes = true;
        for (const glm::vec4& plane : planes) inPlanes = inPlanes && glm::dot(glm::vec3(plane), p) + plane.w >= 0.0f;
        // Points within rounding of a plane may disagree; skip them.
        const float margin = 1e-4f * std::abs(c.w);
        const bool nearBoundary = std::abs(std::abs(c.x) - c.w) < margin || std::abs(std::abs(c.y) - c.w) < margin ||
                                  std::abs(c.z) < margin || std::abs(c.z - c.w) < margin;
        if (!nearBoundary) { EXPECT_EQ(inClip, inPlanes); }
    }
}

}  // namespace
}  // namespace cuberille::rt
