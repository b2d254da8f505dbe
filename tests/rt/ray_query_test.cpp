// Ray queries through the BVH give exactly the brute-force answer (same triangle, same t bits),
// on random scenes and on the cases that break naive traversal: rays lying in box faces, through
// shared edges and vertices, with +0 and -0 direction components, starting on surfaces.

#include <gtest/gtest.h>

#include <random>

#include "rt/bvh_build.h"
#include "rt/ray_query.h"
#include "tests/rt/rt_test_support.h"

namespace cuberille::rt {
namespace {

using testing::OwnedMesh;

const BvhBuildMethod kMethods[] = {BvhBuildMethod::BinnedSah, BvhBuildMethod::SpatialMedian};

void expectSameAsBruteForce(const Bvh& bvh, const TriangleMeshView& mesh, const Ray& ray) {
    const RayHit expected = closestHitBruteForce(mesh, ray);
    const RayHit got = closestHit(bvh, mesh, ray);
    ASSERT_EQ(got.triangle, expected.triangle)
        << "origin " << ray.origin.x << " " << ray.origin.y << " " << ray.origin.z << " direction " << ray.direction.x
        << " " << ray.direction.y << " " << ray.direction.z;
    if (expected.hit()) {
        EXPECT_EQ(got.t, expected.t);
        EXPECT_EQ(got.u, expected.u);
        EXPECT_EQ(got.v, expected.v);
    }
    ASSERT_EQ(anyHit(bvh, mesh, ray), anyHitBruteForce(mesh, ray));
}

TEST(RayQuery, ClosestAndAnyHitEqualBruteForceOnRandomScenes) {
    for (const uint32_t seed : {1u, 2u, 3u}) {
        const OwnedMesh soup = testing::randomSoup(3000, seed, 0.3f);
        for (const BvhBuildMethod method : kMethods) {
            const Bvh bvh = buildBvh(soup.view(), {.method = method});
            testing::forEachRandomRay(seed + 100, 2000, [&](const Ray& ray) { expectSameAsBruteForce(bvh, soup.view(), ray); });
        }
    }
}

TEST(RayQuery, RaysInBoxFacesThroughEdgesAndVerticesEqualBruteForce) {
    // Every lattice coordinate is an integer, so boxes, faces, edges and vertices all lie on the
    // planes these rays start in, run along or pass through.
    const OwnedMesh lattice = testing::cubeLattice(4);
    for (const BvhBuildMethod method : kMethods) {
        const Bvh bvh = buildBvh(lattice.view(), {.method = method});
        testing::forEachLatticeRay([&](const Ray& ray) { expectSameAsBruteForce(bvh, lattice.view(), ray); });
    }
}

TEST(RayQuery, OriginsOnSurfacesEqualBruteForce) {
    // Shadow rays start on the surface they leave: at t = 0 they may hit it, and both must agree.
    const OwnedMesh sphere = testing::uvSphere(16, 32);
    const Bvh bvh = buildBvh(sphere.view());
    testing::forEachRayFromSurface(sphere.view(), 9, 3000, [&](const Ray& ray) { expectSameAsBruteForce(bvh, sphere.view(), ray); });
}

TEST(RayQuery, RaysLeavingFromUlpsOffASurfaceEqualBruteForce) {
    // The lattice's faces are axis-aligned, so a triangle's box is flat across its plane and a
    // ray leaving from a few ulps outside it exits the box before t = 0.
    for (const OwnedMesh& mesh : {testing::cubeLattice(4), testing::uvSphere(24, 48, glm::vec3(37.0f, -11.0f, 5.0f), 3.0f)})
        for (const BvhBuildMethod method : kMethods) {
            const Bvh bvh = buildBvh(mesh.view(), {.method = method});
            testing::forEachRayLeavingNearASurface(mesh.view(), 17, 20000, 3,
                                                   [&](const Ray& ray) { expectSameAsBruteForce(bvh, mesh.view(), ray); });
        }
}

TEST(RayQuery, NoRayEscapesAClosedMeshThroughAnEdgeOrVertex) {
    // From points inside a closed sphere, rays aimed exactly at vertices and edge midpoints must
    // hit: a non-watertight test lets some through the cracks between neighbouring triangles.
    const OwnedMesh sphere = testing::uvSphere(20, 40);
    const TriangleMeshView m = sphere.view();
    const Bvh bvh = buildBvh(m);
    int escaped = 0;
    for (const glm::vec3 origin : {glm::vec3(0.0f), glm::vec3(0.3f, -0.2f, 0.1f), glm::vec3(-0.5f, 0.25f, 0.6f)}) {
        for (const glm::vec3& v : sphere.positions) escaped += !closestHit(bvh, m, Ray{origin, v - origin}).hit();
        for (size_t t = 0; t < m.triangleCount(); ++t)
            for (int e = 0; e < 3; ++e) {
                const glm::vec3 mid = 0.5f * (m.vertex(t, e) + m.vertex(t, (e + 1) % 3));
                escaped += !closestHit(bvh, m, Ray{origin, mid - origin}).hit();
            }
    }
    EXPECT_EQ(escaped, 0);
}

TEST(RayQuery, EqualTsGoToTheLowerTriangleId) {
    // Two copies of one triangle: every hit is a tie, and the lower id must win in any tree.
    OwnedMesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    for (int i = 0; i < 50; ++i) m.indices.insert(m.indices.end(), {0u, 1u, 2u});
    const Bvh bvh = buildBvh(m.view(), {.maxLeafPrimitives = 1});
    const RayHit hit = closestHit(bvh, m.view(), Ray{{0.2f, 0.2f, -1.0f}, {0, 0, 1}});
    ASSERT_TRUE(hit.hit());
    EXPECT_EQ(hit.triangle, 0u);
    EXPECT_EQ(hit.t, 1.0f);
}

TEST(RayQuery, TraversalTestsFewTriangles) {
    const OwnedMesh soup = testing::randomSoup(20000, 4, 0.05f);
    const Bvh bvh = buildBvh(soup.view());
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    TraversalCounters counters;
    const int rays = 1000;
    for (int i = 0; i < rays; ++i) closestHit(bvh, soup.view(), Ray{{unit(rng), unit(rng), -3.0f}, {0.1f * unit(rng), 0.1f * unit(rng), 1.0f}}, counters);
    EXPECT_LT(counters.trianglesTested / rays, 200u) << "a BVH should test a small fraction of 20000 triangles";
}

}  // namespace
}  // namespace cuberille::rt
