// The structure of built hierarchies: every triangle in exactly one leaf and inside its box,
// every box inside its parent's, subtree runs that match the leaves, bounded depth, and a tree
// that does not depend on the thread count.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>

#include "raster/parallel.h"
#include "rt/bvh_build.h"
#include "tests/rt/rt_test_support.h"
#include "tests/thread_counts.h"

namespace cuberille::rt {
namespace {

using testing::expectWellFormed;
using testing::OwnedMesh;

const BvhBuildMethod kMethods[] = {BvhBuildMethod::BinnedSah, BvhBuildMethod::SpatialMedian};

TEST(BvhBuild, EveryTriangleInExactlyOneLeafInsideEveryBoxAboveIt) {
    const OwnedMesh soup = testing::randomSoup(20000, 7);
    const OwnedMesh lattice = testing::cubeLattice(6);
    const OwnedMesh sphere = testing::uvSphere(24, 48);
    for (const OwnedMesh* mesh : {&soup, &lattice, &sphere})
        for (const BvhBuildMethod method : kMethods) {
            SCOPED_TRACE(int(method));
            expectWellFormed(buildBvh(mesh->view(), {.method = method}), mesh->view());
        }
}

TEST(BvhBuild, LeavesRespectTheSizeLimits) {
    const OwnedMesh soup = testing::randomSoup(5000, 3);
    for (const BvhBuildMethod method : kMethods) {
        const BvhBuildOptions options{.method = method};
        const Bvh bvh = buildBvh(soup.view(), options);
        const uint32_t limit = method == BvhBuildMethod::SpatialMedian ? options.medianLeafPrimitives : options.maxLeafPrimitives;
        for (const BvhNode& node : bvh.nodes)
            if (node.isLeaf()) { EXPECT_LE(node.primitiveCount, limit); }
    }
}

TEST(BvhBuild, CoincidentTrianglesStillMakeSmallLeaves) {
    // 1000 copies of one triangle: no plane separates their centroids.
    OwnedMesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    for (int i = 0; i < 1000; ++i) m.indices.insert(m.indices.end(), {0u, 1u, 2u});
    for (const BvhBuildMethod method : kMethods) {
        const Bvh bvh = buildBvh(m.view(), {.method = method});
        expectWellFormed(bvh, m.view());
        for (const BvhNode& node : bvh.nodes)
            if (node.isLeaf()) { EXPECT_LE(node.primitiveCount, 8u); }
    }
}

TEST(BvhBuild, ExponentiallySpacedTrianglesStayWithinTheDepthLimit) {
    // Each triangle twice as far as the last: the SAH peels one off per level. The build must
    // switch to count splits before the traversal stack's bound.
    OwnedMesh m;
    for (int i = 0; i < 120; ++i) {
        const float x = std::ldexp(1.0f, i - 60);
        for (const glm::vec3 p : {glm::vec3(x, 0, 0), glm::vec3(x, 1, 0), glm::vec3(x, 0, 1)}) {
            m.positions.push_back(p);
            m.indices.push_back(uint32_t(m.positions.size() - 1));
        }
    }
    for (const BvhBuildMethod method : kMethods) {
        const Bvh bvh = buildBvh(m.view(), {.method = method, .maxLeafPrimitives = 1});
        expectWellFormed(bvh, m.view());
        EXPECT_LE(bvh.height, kMaxBvhDepth);
    }
}

TEST(BvhBuild, EmptyAndSingleTriangleMeshes) {
    const OwnedMesh empty;
    EXPECT_TRUE(buildBvh(empty.view()).empty());
    OwnedMesh one;
    one.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    one.indices = {0, 1, 2};
    const Bvh bvh = buildBvh(one.view());
    ASSERT_EQ(bvh.nodes.size(), 1u);
    EXPECT_TRUE(bvh.nodes[0].isLeaf());
    EXPECT_EQ(bvh.height, 0);
}

TEST(BvhBuild, SameTreeForAnyThreadCount) {
    const OwnedMesh soup = testing::randomSoup(200000, 11, 0.02f);  // past the parallel thresholds
    for (const BvhBuildMethod method : kMethods) {
        Bvh reference;
        for (const cuberille::testing::ThreadCount count : cuberille::testing::kThreadCounts) {
            const int threads = count.threads;
            const cuberille::testing::ThreadCountScope scope(count);
            const Bvh bvh = buildBvh(soup.view(), {.method = method});
            if (count.exact) { EXPECT_EQ(scope.ran(), threads) << "threads that ran"; }
            if (threads == 1) {
                reference = bvh;
                continue;
            }
            ASSERT_EQ(bvh.nodes.size(), reference.nodes.size());
            EXPECT_EQ(0, std::memcmp(bvh.nodes.data(), reference.nodes.data(), bvh.nodes.size() * sizeof(BvhNode)));
            EXPECT_EQ(bvh.primitiveIndices, reference.primitiveIndices);
        }
    }
}

TEST(BvhBuild, SahTreeIsCheaperThanTheMedianTree) {
    // The SAH minimises expected traversal cost; measured by the SAH cost of the finished trees.
    const OwnedMesh soup = testing::randomSoup(20000, 5, 0.05f);
    auto cost = [](const Bvh& bvh) {
        double c = 0.0;
        const double root = bvh.nodes[0].box().surfaceArea();
        for (const BvhNode& n : bvh.nodes)
            c += n.box().surfaceArea() / root * (n.isLeaf() ? double(n.primitiveCount) : 1.0);
        return c;
    };
    EXPECT_LT(cost(buildBvh(soup.view(), {.method = BvhBuildMethod::BinnedSah})),
              cost(buildBvh(soup.view(), {.method = BvhBuildMethod::SpatialMedian})));
}

}  // namespace
}  // namespace cuberille::rt
