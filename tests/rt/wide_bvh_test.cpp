// The wide BVH: its structure is the binary tree's leaves under wide nodes, and its queries
// give brute force's answers bit for bit (triangle, t, barycentrics; occlusion) on random scenes
// and on the cases that break naive traversal. The suite runs once per instruction set
// (tests/CMakeLists.txt), so every compiled slab test is held to the same answers.

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "rt/bvh_build.h"
#include "rt/bvh_refit.h"
#include "rt/wide_bvh.h"
#include "tests/rt/rt_test_support.h"
#include "tests/thread_counts.h"

namespace cuberille::rt {
namespace {

using testing::OwnedMesh;

void expectSameAsBruteForce(const WideBvh& bvh, const TriangleMeshView& mesh, const Ray& ray) {
    const RayHit expected = closestHitBruteForce(mesh, ray);
    const RayHit got = closestHit(bvh, ray);
    ASSERT_EQ(got.triangle, expected.triangle)
        << "origin " << ray.origin.x << " " << ray.origin.y << " " << ray.origin.z << " direction " << ray.direction.x
        << " " << ray.direction.y << " " << ray.direction.z << " tMin " << ray.tMin << " tMax " << ray.tMax;
    EXPECT_EQ(got.t, expected.t);
    EXPECT_EQ(got.u, expected.u);
    EXPECT_EQ(got.v, expected.v);
    ASSERT_EQ(anyHit(bvh, ray), anyHitBruteForce(mesh, ray));
}

/// Every triangle appears once in the leaves' groups, with its vertices; every child box is tight
/// over what lies under it; every node is reached once, from a parent laid out before it.
void expectWellFormed(const WideBvh& wide, const Bvh& binary, const TriangleMeshView& mesh) {
    ASSERT_FALSE(wide.empty());
    std::vector<int> triangleSeen(mesh.triangleCount(), 0), groupSeen(wide.triangleGroups.size(), 0);
    std::vector<int> nodeSeen(wide.nodes.size(), 0);
    nodeSeen[0] = 1;
    auto childBox = [](const WideBvhNode& node, int c) {
        return Aabb{{node.lo[0][c], node.lo[1][c], node.lo[2][c]}, {node.hi[0][c], node.hi[1][c], node.hi[2][c]}};
    };
    for (uint32_t n = 0; n < wide.nodes.size(); ++n) {
        const WideBvhNode& node = wide.nodes[n];
        const int children = node.childCount();
        ASSERT_GE(children, 1);
        if (n > 0) {
            EXPECT_GE(children, 2) << "only a root over a single leaf has one child";
        }
        for (int c = children; c < kWideBvhWidth; ++c) EXPECT_EQ(node.child[c], WideBvhNode::kNoChild) << "children fill the first slots";
        for (int c = 0; c < children; ++c) {
            if (node.leafGroups[c] != 0) {
                Aabb tight;
                for (uint32_t g = node.child[c]; g < node.child[c] + node.leafGroups[c]; ++g) {
                    ASSERT_LT(g, wide.triangleGroups.size());
                    ++groupSeen[g];
                    const WideBvhTriangles& group = wide.triangleGroups[g];
                    for (int lane = 0; lane < kTriangleGroupWidth; ++lane) {
                        const uint32_t id = group.triangle[lane];
                        if (id == WideBvhTriangles::kNoTriangle) {
                            EXPECT_EQ(g + 1, node.child[c] + node.leafGroups[c]) << "only a leaf's last group has unused lanes";
                            EXPECT_TRUE(std::isnan(group.a[0][lane]));
                            continue;
                        }
                        ASSERT_LT(id, triangleSeen.size());
                        ++triangleSeen[id];
                        for (int axis = 0; axis < 3; ++axis) {
                            EXPECT_EQ(group.a[axis][lane], mesh.vertex(id, 0)[axis]);
                            EXPECT_EQ(group.b[axis][lane], mesh.vertex(id, 1)[axis]);
                            EXPECT_EQ(group.c[axis][lane], mesh.vertex(id, 2)[axis]);
                        }
                        tight.grow(mesh.triangleBounds(id));
                    }
                }
                EXPECT_EQ(childBox(node, c), tight) << "node " << n << " child " << c;
                continue;
            }
            ASSERT_GT(node.child[c], n) << "children are laid out after their parent";
            ASSERT_LT(node.child[c], wide.nodes.size());
            ++nodeSeen[node.child[c]];
            const WideBvhNode& below = wide.nodes[node.child[c]];
            Aabb under;
            for (int k = 0; k < below.childCount(); ++k) under.grow(childBox(below, k));
            EXPECT_EQ(childBox(node, c), under) << "node " << n << " child " << c << " is its children's box";
        }
    }
    for (size_t t = 0; t < triangleSeen.size(); ++t) EXPECT_EQ(triangleSeen[t], 1) << "triangle " << t;
    for (size_t g = 0; g < groupSeen.size(); ++g) EXPECT_EQ(groupSeen[g], 1) << "group " << g;
    for (size_t n = 0; n < nodeSeen.size(); ++n) EXPECT_EQ(nodeSeen[n], 1) << "node " << n;
    EXPECT_LE(wide.height, binary.height);
}

TEST(WideBvh, CollapsedTreeHoldsEveryBinaryLeafOnceUnderTightBoxes) {
    for (const BvhBuildMethod method : {BvhBuildMethod::BinnedSah, BvhBuildMethod::SpatialMedian}) {
        const OwnedMesh soup = testing::randomSoup(5000, 7, 0.2f);
        const Bvh binary = buildBvh(soup.view(), {.method = method});
        const WideBvh wide = collapseToWideBvh(binary);
        expectWellFormed(wide, binary, soup.view());
        // The greedy collapse opens inner children until a node is full: a node with a free slot
        // holds only leaves (nothing was left to open). A collapse that stopped early fails this.
        for (size_t n = 0; n < wide.nodes.size(); ++n) {
            const WideBvhNode& node = wide.nodes[n];
            if (node.childCount() == kWideBvhWidth) continue;
            for (int c = 0; c < node.childCount(); ++c) EXPECT_NE(node.leafGroups[c], 0u) << "node " << n << " child " << c;
        }
    }
    // A mesh of one leaf: a root with that leaf as its only child.
    const OwnedMesh one = testing::randomSoup(1, 1);
    const Bvh binary = buildBvh(one.view());
    ASSERT_TRUE(binary.nodes[0].isLeaf());
    const WideBvh wide = collapseToWideBvh(binary);
    expectWellFormed(wide, binary, one.view());
    EXPECT_EQ(wide.nodes.size(), 1u);
    EXPECT_TRUE(collapseToWideBvh(buildBvh(OwnedMesh{}.view())).empty());
}

TEST(WideBvh, ClosestAndAnyHitEqualBruteForceOnRandomScenes) {
    for (const uint32_t seed : {1u, 2u, 3u}) {
        const OwnedMesh soup = testing::randomSoup(3000, seed, 0.3f);
        for (const BvhBuildMethod method : {BvhBuildMethod::BinnedSah, BvhBuildMethod::SpatialMedian}) {
            const WideBvh bvh = collapseToWideBvh(buildBvh(soup.view(), {.method = method}));
            testing::forEachRandomRay(seed + 100, 2000, [&](const Ray& ray) { expectSameAsBruteForce(bvh, soup.view(), ray); });
        }
    }
}

TEST(WideBvh, RaysInBoxFacesThroughEdgesAndVerticesEqualBruteForce) {
    // Every lattice coordinate is an integer: boxes, faces, edges and vertices lie on the planes
    // these rays start in, run along or pass through, with +0 and -0 direction components.
    const OwnedMesh lattice = testing::cubeLattice(4);
    for (const BvhBuildMethod method : {BvhBuildMethod::BinnedSah, BvhBuildMethod::SpatialMedian}) {
        const WideBvh bvh = collapseToWideBvh(buildBvh(lattice.view(), {.method = method}));
        testing::forEachLatticeRay([&](const Ray& ray) { expectSameAsBruteForce(bvh, lattice.view(), ray); });
    }
}

TEST(WideBvh, OriginsOnSurfacesEqualBruteForce) {
    const OwnedMesh sphere = testing::uvSphere(16, 32);
    const WideBvh bvh = collapseToWideBvh(buildBvh(sphere.view()));
    testing::forEachRayFromSurface(sphere.view(), 9, 3000, [&](const Ray& ray) { expectSameAsBruteForce(bvh, sphere.view(), ray); });
}

TEST(WideBvh, RaysLeavingFromUlpsOffASurfaceEqualBruteForce) {
    for (const OwnedMesh& mesh : {testing::cubeLattice(4), testing::uvSphere(24, 48, glm::vec3(37.0f, -11.0f, 5.0f), 3.0f)}) {
        const WideBvh bvh = collapseToWideBvh(buildBvh(mesh.view()));
        testing::forEachRayLeavingNearASurface(mesh.view(), 17, 20000, 3,
                                               [&](const Ray& ray) { expectSameAsBruteForce(bvh, mesh.view(), ray); });
    }
}

TEST(WideBvh, RaysAtTheEdgesAndVerticesOfAClosedMeshEqualBruteForce) {
    // Aimed at shared vertices and edge midpoints with coordinates that are not integers: edge
    // weights round to exactly zero in float where they are not zero, and the lanes must then
    // take the scalar test's double-precision answer (Woop et al. §3.3), or the hit changes.
    const OwnedMesh sphere = testing::uvSphere(20, 40);
    const TriangleMeshView m = sphere.view();
    const WideBvh bvh = collapseToWideBvh(buildBvh(m, {.maxLeafPrimitives = 8}));
    for (const glm::vec3 origin : {glm::vec3(0.0f), glm::vec3(0.3f, -0.2f, 0.1f), glm::vec3(-0.5f, 0.25f, 0.6f)}) {
        for (const glm::vec3& v : sphere.positions) expectSameAsBruteForce(bvh, m, Ray{origin, v - origin});
        for (size_t t = 0; t < m.triangleCount(); ++t)
            for (int e = 0; e < 3; ++e) {
                const glm::vec3 mid = 0.5f * (m.vertex(t, e) + m.vertex(t, (e + 1) % 3));
                expectSameAsBruteForce(bvh, m, Ray{origin, mid - origin});
                expectSameAsBruteForce(bvh, m, Ray{origin + 3.0f * (mid - origin), origin - mid});  // from outside
            }
    }
}

TEST(WideBvh, EqualTsGoToTheLowerTriangleIdWhateverTheVisitOrder) {
    // Fifty copies of one triangle, one to a leaf: every hit is a tie across many wide children.
    OwnedMesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    for (int i = 0; i < 50; ++i) m.indices.insert(m.indices.end(), {0u, 1u, 2u});
    const WideBvh bvh = collapseToWideBvh(buildBvh(m.view(), {.maxLeafPrimitives = 1}));
    for (const float dz : {1.0f, -1.0f}) {
        const RayHit hit = closestHit(bvh, Ray{{0.2f, 0.2f, -dz}, {0, 0, dz}});
        ASSERT_TRUE(hit.hit());
        EXPECT_EQ(hit.triangle, 0u);
        EXPECT_EQ(hit.t, 1.0f);
    }
}

TEST(WideBvh, RefreshAfterARefitKeepsTheTreeWithCurrentBoxesAndVertices) {
    OwnedMesh soup = testing::randomSoup(4000, 11, 0.1f);
    Bvh binary = buildBvh(soup.view());
    WideBvh wide = collapseToWideBvh(binary);
    const size_t nodes = wide.nodes.size(), groups = wide.triangleGroups.size();
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> unit(-0.3f, 0.3f);
    for (glm::vec3& p : soup.positions) p += glm::vec3(unit(rng), unit(rng), unit(rng));
    refitBvh(binary, soup.view());
    refreshWideBvh(wide, binary);
    // The same nodes and groups (a fresh collapse could open other children: the areas that choose
    // them have changed), every box tight over the moved triangles, every vertex the moved one.
    EXPECT_EQ(wide.nodes.size(), nodes);
    EXPECT_EQ(wide.triangleGroups.size(), groups);
    expectWellFormed(wide, binary, soup.view());
    testing::forEachRandomRay(12, 2000, [&](const Ray& ray) { expectSameAsBruteForce(wide, soup.view(), ray); });
}

TEST(WideBvh, TheSameTreeAtAnyThreadCount) {
    // The collapse is serial and the refresh writes each node and group from its own sources, so
    // the bytes are the same whatever the threads (a refresh large enough for several chunks).
    OwnedMesh soup = testing::randomSoup(40000, 13, 0.05f);
    Bvh binary = buildBvh(soup.view());
    const WideBvh collapsed = collapseToWideBvh(binary);
    std::mt19937 rng(13);
    std::uniform_real_distribution<float> unit(-0.1f, 0.1f);
    for (glm::vec3& p : soup.positions) p += glm::vec3(unit(rng), unit(rng), unit(rng));
    refitBvh(binary, soup.view());
    std::vector<WideBvh> refreshed;
    for (const cuberille::testing::ThreadCount count : cuberille::testing::kThreadCounts) {
        const cuberille::testing::ThreadCountScope scope(count);
        WideBvh wide = collapsed;
        refreshWideBvh(wide, binary);
        if (count.exact) {
            EXPECT_GT(scope.ran(), 1) << "the refresh ran on one of " << count.threads << " threads";  // TBB may use one
        }
        refreshed.push_back(std::move(wide));
    }
    for (size_t k = 1; k < refreshed.size(); ++k) {
        ASSERT_EQ(refreshed[k].nodes.size(), refreshed[0].nodes.size());
        EXPECT_EQ(std::memcmp(refreshed[k].nodes.data(), refreshed[0].nodes.data(), refreshed[0].nodes.size() * sizeof(WideBvhNode)), 0);
        EXPECT_EQ(std::memcmp(refreshed[k].triangleGroups.data(), refreshed[0].triangleGroups.data(),
                              refreshed[0].triangleGroups.size() * sizeof(WideBvhTriangles)),
                  0);
    }
}

TEST(WideBvh, TraversalVisitsFewerNodesThanTheBinaryTree) {
    const OwnedMesh soup = testing::randomSoup(20000, 4, 0.05f);
    const Bvh binary = buildBvh(soup.view());
    const WideBvh wide = collapseToWideBvh(binary);
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    TraversalCounters binaryCounters, wideCounters;
    const int rays = 1000;
    for (int i = 0; i < rays; ++i) {
        const Ray ray{{unit(rng), unit(rng), -3.0f}, {0.1f * unit(rng), 0.1f * unit(rng), 1.0f}};
        closestHit(binary, soup.view(), ray, binaryCounters);
        closestHit(wide, ray, wideCounters);
    }
    // Each wide node stands for up to seven binary inner nodes; measured 0.25 of the binary
    // tree's visits here, so half is a bound with room that a traversal opening every child fails.
    EXPECT_LT(wideCounters.nodesVisited * 2, binaryCounters.nodesVisited);
    EXPECT_LT(wideCounters.trianglesTested / rays, 200u);
}

}  // namespace
}  // namespace cuberille::rt

namespace cuberille::rt {
namespace {

/// closestHits() against closestHit() ray by ray: the same triangle, t and weights for each.
void expectPacketsAsSingleRays(const WideBvh& bvh, const std::vector<Ray>& rays, const HitFilter* filter, const char* what) {
    std::vector<RayHit> packed(rays.size());
    closestHits(bvh, rays, packed, filter);
    int differing = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
        const RayHit single = filter ? closestHit(bvh, rays[i], *filter) : closestHit(bvh, rays[i]);
        const bool same = packed[i].triangle == single.triangle && packed[i].t == single.t && packed[i].u == single.u &&
                          packed[i].v == single.v;
        if (!same && differing++ < 3)
            ADD_FAILURE() << what << ": ray " << i << " hit " << packed[i].triangle << " at " << packed[i].t
                          << " in its packet, " << single.triangle << " at " << single.t << " alone";
    }
    EXPECT_EQ(differing, 0) << what;
}

/// A pinhole camera's rays through a side x side grid of pixels covering the scene, in 8x8 tiles
/// (each tile one packet), from an eye outside [-1.5, 1.5]^3.
std::vector<Ray> cameraTiles(const glm::vec3& eye, int side, float tMax) {
    const glm::vec3 forward = glm::normalize(-eye), right = glm::normalize(glm::cross(forward, glm::vec3(0.1f, 1.0f, 0.05f)));
    const glm::vec3 up = glm::cross(right, forward);
    std::vector<Ray> rays;
    for (int ty = 0; ty < side; ty += 8)
        for (int tx = 0; tx < side; tx += 8)
            for (int y = ty; y < ty + 8; ++y)
                for (int x = tx; x < tx + 8; ++x) {
                    const float sx = (2.0f * (x + 0.5f) / side - 1.0f) * 0.6f, sy = (1.0f - 2.0f * (y + 0.5f) / side) * 0.6f;
                    Ray r{eye, forward + sx * right + sy * up};
                    r.tMax = tMax;
                    rays.push_back(r);
                }
    return rays;
}

bool passesWhereUIsSmall(const void*, uint32_t, const Ray&, float u, float) { return u < 0.4f; }

// Packets of camera rays from eyes on every side (so every direction-sign combination, and packets
// whose rays straddle an axis and go ray by ray), segments ending inside the scene, a lattice whose
// rays meet edges and vertices exactly, and a filter that skips some triangles and alpha-tests
// others: each ray's hit in its packet is its hit alone, bit for bit.
TEST(WideBvh, PacketsGiveEachRayItsOwnClosestHit) {
    const OwnedMesh soup = testing::randomSoup(4000, 7, 0.3f);
    const WideBvh bvh = collapseToWideBvh(buildBvh(soup.view()));
    std::vector<uint8_t> entries(soup.view().triangleCount());
    for (size_t t = 0; t < entries.size(); ++t) entries[t] = t % 7 == 0 ? HitFilter::kSkipped : (t % 5 == 0 ? HitFilter::kAlphaTested : HitFilter::kKept);
    const HitFilter filter{entries, passesWhereUIsSmall, nullptr};
    for (const glm::vec3 eye : {glm::vec3(3.0f, 2.0f, 4.0f), glm::vec3(-4.0f, 1.0f, -2.0f), glm::vec3(0.5f, -4.0f, 0.3f),
                                glm::vec3(0.0f, 0.0f, 5.0f)}) {
        for (const float tMax : {std::numeric_limits<float>::infinity(), 4.5f}) {
            const std::vector<Ray> rays = cameraTiles(eye, 48, tMax);
            expectPacketsAsSingleRays(bvh, rays, nullptr, "camera");
            expectPacketsAsSingleRays(bvh, rays, &filter, "camera, filtered");
            // The packets share their node visits: fewer than the rays make alone.
            TraversalCounters packed, alone;
            std::vector<RayHit> hits(rays.size());
            closestHits(bvh, rays, hits, nullptr, &packed);
            for (const Ray& r : rays) closestHit(bvh, r, alone);
            EXPECT_LT(packed.nodesVisited, alone.nodesVisited);
        }
    }
    std::vector<Ray> scattered;  // mixed signs: ray by ray
    testing::forEachRandomRay(8, 500, [&](const Ray& r) { scattered.push_back(r); });
    expectPacketsAsSingleRays(bvh, scattered, &filter, "scattered");
    const OwnedMesh lattice = testing::cubeLattice(4);
    const WideBvh latticeBvh = collapseToWideBvh(buildBvh(lattice.view()));
    std::vector<Ray> exact;
    testing::forEachLatticeRay([&](const Ray& r) { exact.push_back(r); });
    expectPacketsAsSingleRays(latticeBvh, exact, nullptr, "lattice");
    std::vector<Ray> few(exact.begin(), exact.begin() + 13);  // a packet of fewer than 64
    expectPacketsAsSingleRays(latticeBvh, few, nullptr, "13 rays");
}

/// Each ray's answer through the packets is its own anyHit's.
void expectShadowPacketsAsSingleRays(const WideBvh& bvh, std::span<const Ray> rays, const char* what) {
    std::vector<uint8_t> occluded(rays.size(), 2);
    anyHits(bvh, rays, occluded);
    for (size_t i = 0; i < rays.size(); ++i) ASSERT_EQ(bool(occluded[i]), anyHit(bvh, rays[i])) << what << " ray " << i;
}

TEST(WideBvh, ShadowPacketsGiveEachRayItsOwnAnswer) {
    // Shadow rays from the camera's hits toward one light, a tile's hits a packet, each leaving its
    // surface a little along the normal's side toward the light; and toward a light inside the
    // soup (finite tMax), and from the lattice's faces, edges and vertices.
    const OwnedMesh soup = testing::randomSoup(4000, 11, 0.3f);
    const WideBvh bvh = collapseToWideBvh(buildBvh(soup.view()));
    size_t occludedCount = 0, total = 0;
    for (const glm::vec3 eye : {glm::vec3(3.0f, 2.0f, 4.0f), glm::vec3(-4.0f, 1.0f, -2.0f)})
        for (const glm::vec3 light : {glm::normalize(glm::vec3(0.4f, 1.0f, 0.3f)), glm::normalize(glm::vec3(-1.0f, 0.2f, 0.5f))})
            for (const float reach : {std::numeric_limits<float>::infinity(), 0.6f}) {
                const std::vector<Ray> camera = cameraTiles(eye, 48, std::numeric_limits<float>::infinity());
                std::vector<Ray> shadow;
                for (const Ray& r : camera) {
                    const RayHit h = closestHit(bvh, r);
                    if (!h.hit()) continue;
                    const glm::vec3 a = soup.positions[soup.indices[3 * h.triangle]], b = soup.positions[soup.indices[3 * h.triangle + 1]],
                                    c = soup.positions[soup.indices[3 * h.triangle + 2]];
                    const glm::vec3 n = glm::normalize(glm::cross(b - a, c - a));
                    const glm::vec3 p = r.origin + h.t * r.direction + n * (1e-4f * (glm::dot(n, light) >= 0.0f ? 1.0f : -1.0f));
                    shadow.push_back(Ray{p, light, 0.0f, reach});
                }
                expectShadowPacketsAsSingleRays(bvh, shadow, "shadow");
                std::vector<uint8_t> occluded(shadow.size());
                anyHits(bvh, shadow, occluded);
                for (uint8_t o : occluded) occludedCount += o;
                total += shadow.size();
            }
    EXPECT_GT(occludedCount, total / 10);  // both answers are exercised
    EXPECT_LT(occludedCount, total * 9 / 10);
    const OwnedMesh lattice = testing::cubeLattice(4);
    const WideBvh latticeBvh = collapseToWideBvh(buildBvh(lattice.view()));
    std::vector<Ray> exact;
    testing::forEachLatticeRay([&](const Ray& r) { exact.push_back(r); });
    expectShadowPacketsAsSingleRays(latticeBvh, exact, "lattice");
    std::vector<Ray> scattered;
    testing::forEachRandomRay(9, 300, [&](const Ray& r) { scattered.push_back(r); });
    expectShadowPacketsAsSingleRays(bvh, scattered, "scattered");
}

}  // namespace
}  // namespace cuberille::rt
