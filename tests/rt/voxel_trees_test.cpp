// The voxel acceleration structures of Chajdas's chapter 5 (rt/voxel_trees.h) give brute force's
// hit bit for bit — voxel, t, entry face — with every short-stack size, restarts included, on
// random voxel sets and on the rays that break naive traversals (axis-parallel rays in the planes
// between voxels, rays along edges, origins on faces and corners, -0 components); the hit rule
// needs no offset for rays leaving a face; the builds keep their rules; the lane simulation counts
// what it says. The wide BVH (rt/wide_voxel_bvh.h) is held to the same hits; its suite runs once
// per instruction set (tests/CMakeLists.txt), so every compiled slab test is.

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <optional>
#include <random>
#include <set>

#include <tbb/global_control.h>

#include "rt/voxel_traversal.h"
#include "rt/voxel_trees.h"
#include "rt/wide_voxel_bvh.h"

namespace cuberille::rt {
namespace {

/// Distinct voxels: a thick spherical shell (a scan's surface, with its holes), a random scatter,
/// and a solid slab, the three inside a 64-voxel cube placed away from the grid origin.
std::vector<VoxelCoord> voxelScene(uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> coord(0, 63), coin(0, 9);
    std::set<uint64_t> seen;
    std::vector<VoxelCoord> voxels;
    auto add = [&](int x, int y, int z) {
        const VoxelCoord v{uint16_t(x + 100), uint16_t(y + 7), uint16_t(z + 300)};
        if (seen.insert(voxelKey(v)).second) voxels.push_back(v);
    };
    for (int z = 0; z < 64; ++z)
        for (int y = 0; y < 64; ++y)
            for (int x = 0; x < 64; ++x) {
                const double r = std::sqrt(double((x - 31) * (x - 31) + (y - 29) * (y - 29) + (z - 33) * (z - 33)));
                if (r > 20.0 && r < 22.0 && coin(rng) != 0) add(x, y, z);
                if (z == 50 && x > 10 && x < 40 && y > 5 && y < 58) add(x, y, z);
            }
    for (int i = 0; i < 600; ++i) add(coord(rng), coord(rng), coord(rng));
    std::shuffle(voxels.begin(), voxels.end(), rng);
    return voxels;
}

/// Random rays and the degenerate ones: origins on the lattice of voxel corners, directions with
/// zero (and -0) components, so rays run along faces, edges and the planes between voxels.
std::vector<Ray> testRays(uint32_t seed, int n) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> position(80.0f, 190.0f), unit(-1.0f, 1.0f);
    std::uniform_int_distribution<int> lattice(95, 170), pick(0, 5);
    const glm::vec3 offset(0.0f, -93.0f, 200.0f);  // the scene sits at (100, 7, 300)
    const glm::vec3 axisDirections[] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -0.0f, -1}, {1, 1, 0}, {1, -1, 1},
                                        {0, 1, -1}, {-0.0f, -0.0f, 1}, {0.5f, 0.25f, 0}, {-1, 0.5f, 0.25f}};
    std::vector<Ray> rays;
    for (int i = 0; i < n; ++i) {
        Ray r;
        const int kind = pick(rng);
        r.origin = kind < 3 ? glm::vec3(position(rng), position(rng), position(rng)) + offset
                            : glm::vec3(float(lattice(rng)), float(lattice(rng) - 93), float(lattice(rng) + 200));
        if (kind == 4) r.origin.x += 0.5f;  // on a face's plane, off its edges
        r.direction = kind % 2 == 0 ? glm::vec3(unit(rng), unit(rng), unit(rng)) : axisDirections[i % 10];
        // Aim some random rays at the scene so most hit something.
        if (kind == 0) r.direction = glm::vec3(131.0f, 36.0f, 333.0f) + 20.0f * glm::vec3(unit(rng), unit(rng), unit(rng)) - r.origin;
        if (i % 7 == 0) r.tMin = 3.0f;
        if (i % 11 == 0) r.tMax = 40.0f;
        rays.push_back(r);
    }
    return rays;
}

template <class Tree>
void expectBruteForcesHits(const Tree& tree, std::span<const VoxelHit> bruteForce, std::span<const Ray> rays, const char* name) {
    for (int entries : {0, 1, 2, 4, 8, VoxelTraversal::kFullStack}) {
        size_t hits = 0;
        for (size_t i = 0; i < rays.size(); ++i) {
            const Ray& r = rays[i];
            const VoxelRay ray(r);
            const VoxelHit& expected = bruteForce[i];
            const VoxelHit got = tree.trace(ray, {.stackEntries = entries});
            const auto where = [&] {
                return ::testing::Message() << name << ", " << entries << " stack entries: origin " << r.origin.x << " "
                                            << r.origin.y << " " << r.origin.z << " direction " << r.direction.x << " "
                                            << r.direction.y << " " << r.direction.z << " t [" << r.tMin << ", " << r.tMax << "]";
            };
            ASSERT_EQ(got.voxel, expected.voxel) << where();
            ASSERT_EQ(std::bit_cast<uint32_t>(got.t), std::bit_cast<uint32_t>(expected.t)) << where();
            ASSERT_EQ(got.axis, expected.axis) << where();
            const VoxelHit any = tree.trace(ray, {.stackEntries = entries, .anyHit = true});
            ASSERT_EQ(any.hit(), expected.hit()) << where();
            hits += expected.hit() ? 1 : 0;
        }
        // The rays are aimed to hit often and miss often: both cases are exercised.
        EXPECT_GT(hits, rays.size() / 5);
        EXPECT_LT(hits, rays.size() * 9 / 10);
    }
}

/// The three test scenes, each with 3,000 rays and brute force's hits for them:
/// check(voxels, bruteForce, rays).
template <class Check>
void onTestScenes(Check&& check) {
    for (uint32_t seed : {1u, 2u, 3u}) {
        const std::vector<VoxelCoord> voxels = voxelScene(seed);
        const std::vector<Ray> rays = testRays(seed + 10, 3000);
        std::vector<VoxelHit> bruteForce;
        for (const Ray& r : rays) bruteForce.push_back(closestVoxelBruteForce(voxels, VoxelRay(r)));
        check(voxels, bruteForce, rays);
    }
}

TEST(VoxelTrees, EveryStructureAndStackSizeGivesBruteForcesHit) {
    onTestScenes([](const std::vector<VoxelCoord>& voxels, const std::vector<VoxelHit>& bruteForce, const std::vector<Ray>& rays) {
        expectBruteForcesHits(VoxelBvh(voxels), bruteForce, rays, "bvh");
        expectBruteForcesHits(VoxelKdTree(voxels), bruteForce, rays, "kdtree");
        expectBruteForcesHits(VoxelOctree(voxels), bruteForce, rays, "octree");
    });
}

TEST(VoxelTrees, TinyAndEmptySetsAnswerLikeBruteForce) {
    const std::vector<Ray> rays = testRays(5, 300);
    for (size_t n : {0, 1, 2, 8, 9}) {
        std::vector<VoxelCoord> voxels;
        for (size_t i = 0; i < n; ++i) voxels.push_back({uint16_t(130 + i), uint16_t(36 + (i % 3)), uint16_t(330 + i / 2)});
        for (const Ray& r : rays) {
            const VoxelRay ray(r);
            const VoxelHit expected = closestVoxelBruteForce(voxels, ray);
            EXPECT_EQ(VoxelBvh(voxels).trace(ray, {}).voxel, expected.voxel);
            EXPECT_EQ(VoxelKdTree(voxels).trace(ray, {}).voxel, expected.voxel);
            EXPECT_EQ(VoxelOctree(voxels).trace(ray, {}).voxel, expected.voxel);
            EXPECT_EQ(WideVoxelBvh(voxels).trace(ray, {}).voxel, expected.voxel);
        }
    }
}

TEST(VoxelTrees, ARayLeavingAFaceMissesItsOwnVoxelAndOneEnteringItHits) {
    // Voxels (10,10,10) and its neighbour across +y, (10,11,10). A ray from the middle of the
    // first's +x face: outward it misses both; back inward it hits the first at t = 0; along the
    // face (direction +y, in the plane x = 11) it is in neither, since the plane belongs to x >= 11.
    const std::vector<VoxelCoord> voxels{{10, 10, 10}, {10, 11, 10}};
    const VoxelKdTree tree(voxels);
    auto trace = [&](glm::vec3 origin, glm::vec3 direction) {
        const VoxelRay ray(Ray{origin, direction, 0.0f, 100.0f});
        const VoxelHit h = tree.trace(ray, {});
        EXPECT_EQ(h.voxel, closestVoxelBruteForce(voxels, ray).voxel);
        return h;
    };
    EXPECT_FALSE(trace({11.0f, 10.5f, 10.5f}, {1.0f, 0.3f, 0.2f}).hit());
    const VoxelHit inward = trace({11.0f, 10.5f, 10.5f}, {-1.0f, 0.3f, 0.2f});
    EXPECT_EQ(inward.voxel, 0u);
    EXPECT_EQ(inward.t, 0.0f);
    EXPECT_FALSE(trace({11.0f, 10.5f, 10.5f}, {0.0f, 1.0f, 0.0f}).hit());
    // The same ray one plane lower, x = 10, runs inside both: it starts in the first.
    const VoxelHit inside = trace({10.0f, 10.5f, 10.5f}, {0.0f, 1.0f, 0.0f});
    EXPECT_EQ(inside.voxel, 0u);
    EXPECT_EQ(inside.axis, -1);
    // A ray through the edge the two share, from outside: it touches the first only along the
    // edge's line at a point, and enters the second through that edge.
    const VoxelHit edge = trace({12.0f, 10.0f, 10.5f}, {-1.0f, 1.0f, 0.0f});
    EXPECT_EQ(edge.voxel, 1u);
}

/// Every voxel in exactly one leaf, no leaf over kVoxelLeafSize (at the depth guard aside), and
/// the sizes Table 11 reports add up.
template <class Tree>
void expectWellFormed(const Tree& tree, size_t voxelCount, bool mayHaveNullLeaves) {
    const VoxelTreeSize s = tree.size();
    EXPECT_EQ(s.leafBytes, s.leaves * sizeof(VoxelLeaf));
    EXPECT_GT(s.interiorNodes, 0u);
    EXPECT_GE(s.leaves, voxelCount / kVoxelLeafSize);
    EXPECT_GT(s.meanLeafDepth, 1.0);
    EXPECT_LE(s.meanLeafDepth, double(s.depth));
    if (!mayHaveNullLeaves) {
        EXPECT_EQ(s.nullLeaves, 0u);
    }
}

TEST(VoxelTrees, BuildsKeepTheirRules) {
    const std::vector<VoxelCoord> voxels = voxelScene(4);
    const VoxelBvh bvh(voxels);
    const VoxelKdTree kd(voxels);
    const VoxelOctree octree(voxels);
    expectWellFormed(bvh, voxels.size(), false);
    expectWellFormed(kd, voxels.size(), true);
    expectWellFormed(octree, voxels.size(), true);
    // The octree's leaves sit no deeper than its cube allows (the scene spans coordinates < 512,
    // so nine levels), and its shallow fan-out keeps it shallower than the binary trees (§5.5.2).
    EXPECT_LE(octree.size().depth, 9);
    EXPECT_LT(octree.size().meanLeafDepth, bvh.size().meanLeafDepth);
    EXPECT_LT(octree.size().meanLeafDepth, kd.size().meanLeafDepth);
    // A BVH over n voxels in leaves has one interior node fewer than leaves.
    EXPECT_EQ(bvh.size().interiorNodes + 1, bvh.size().leaves);
}

TEST(VoxelTrees, ShortStacksRestartAndFullStacksNever) {
    const std::vector<VoxelCoord> voxels = voxelScene(6);
    const std::vector<Ray> rays = testRays(7, 400);
    const VoxelOctree octree(voxels);
    const VoxelKdTree kd(voxels);
    VoxelTraversalCounters full, none, fullKd, noneKd;
    for (const Ray& r : rays) {
        const VoxelRay ray(r);
        octree.trace(ray, {.stackEntries = VoxelTraversal::kFullStack}, &full);
        octree.trace(ray, {.stackEntries = 0}, &none);
        kd.trace(ray, {.stackEntries = VoxelTraversal::kFullStack}, &fullKd);
        kd.trace(ray, {.stackEntries = 0}, &noneKd);
    }
    EXPECT_EQ(full.restarts, 0u);
    EXPECT_EQ(fullKd.restarts, 0u);
    EXPECT_GT(none.restarts, 0u);
    EXPECT_GT(noneKd.restarts, 0u);
    // Restarting from the root costs interior steps, never leaf tests.
    EXPECT_GT(none.interiorSteps, full.interiorSteps);
    EXPECT_EQ(none.voxelTests, full.voxelTests);
    EXPECT_EQ(none.hits, full.hits);
}

/// The tree's arrays byte for byte: nodes, leaves, voxels and their source indices.
template <class Tree>
void expectSameLayout(const Tree& a, const Tree& b) {
    ASSERT_EQ(a.nodes().size(), b.nodes().size());
    EXPECT_EQ(std::memcmp(a.nodes().data(), b.nodes().data(), a.nodes().size_bytes()), 0);
    ASSERT_EQ(a.leafData().leaves.size(), b.leafData().leaves.size());
    for (size_t i = 0; i < a.leafData().leaves.size(); ++i) {
        EXPECT_EQ(a.leafData().leaves[i].first, b.leafData().leaves[i].first);
        EXPECT_EQ(a.leafData().leaves[i].count, b.leafData().leaves[i].count);
    }
    EXPECT_EQ(a.leafData().voxels, b.leafData().voxels);
    EXPECT_EQ(a.leafData().sourceIndex, b.leafData().sourceIndex);
}

TEST(VoxelTrees, BuildsAreTheSameBitsAtEveryThreadCount) {
    // A shell big enough that the top levels build their children in parallel.
    std::vector<VoxelCoord> voxels;
    for (int z = 0; z < 160; ++z)
        for (int y = 0; y < 160; ++y)
            for (int x = 0; x < 160; ++x) {
                const int r2 = (x - 80) * (x - 80) + (y - 75) * (y - 75) + (z - 82) * (z - 82);
                if (r2 >= 70 * 70 && r2 < 72 * 72) voxels.push_back({uint16_t(x), uint16_t(y), uint16_t(z)});
            }
    ASSERT_GT(voxels.size(), 2 * size_t(kParallelBuildVoxels));
    std::optional<VoxelBvh> bvh;
    std::optional<VoxelKdTree> kd;
    std::optional<VoxelOctree> octree;
    {
        const tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        bvh.emplace(voxels), kd.emplace(voxels), octree.emplace(voxels);
    }
    for (int threads : {2, 7}) {
        const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
        expectSameLayout(*bvh, VoxelBvh(voxels));
        expectSameLayout(*kd, VoxelKdTree(voxels));
        expectSameLayout(*octree, VoxelOctree(voxels));
    }
}

TEST(WideVoxelBvh, GivesBruteForcesHitOnRandomAndDegenerateRays) {
    onTestScenes([](const std::vector<VoxelCoord>& voxels, const std::vector<VoxelHit>& bruteForce, const std::vector<Ray>& rays) {
        expectBruteForcesHits(WideVoxelBvh(voxels), bruteForce, rays, "bvh8");
    });
}

TEST(WideVoxelBvh, TinyAndEmptySetsAnswerLikeBruteForce) {
    const std::vector<Ray> rays = testRays(5, 300);
    for (size_t n : {0, 1, 2, 8, 9, 64, 65}) {
        std::vector<VoxelCoord> voxels;
        for (size_t i = 0; i < n; ++i) voxels.push_back({uint16_t(130 + i % 9), uint16_t(36 + (i % 3)), uint16_t(330 + i / 2)});
        const WideVoxelBvh tree(voxels);
        for (const Ray& r : rays) {
            const VoxelRay ray(r);
            const VoxelHit expected = closestVoxelBruteForce(voxels, ray);
            const VoxelHit got = tree.trace(ray, {});
            EXPECT_EQ(got.voxel, expected.voxel);
            EXPECT_EQ(std::bit_cast<uint32_t>(got.t), std::bit_cast<uint32_t>(expected.t));
            EXPECT_EQ(tree.trace(ray, {.anyHit = true}).hit(), expected.hit());
        }
    }
}

TEST(WideVoxelBvh, HoldsEveryBinaryLeafOnceUnderFewerLevels) {
    const std::vector<VoxelCoord> voxels = voxelScene(4);
    const VoxelBvh binary(voxels);
    const WideVoxelBvh wide(binary);
    // Every leaf of the binary tree is a child of exactly one wide node; unused slots are null
    // with an inverted box, and every used box holds its subtree's voxels.
    std::vector<int> seen(binary.leafData().leaves.size(), 0);
    size_t usedSlots = 0;
    for (const WideVoxelBvhNode& n : wide.nodes())
        for (int c = 0; c < kWideVoxelBvhWidth; ++c) {
            if (n.child[c] == VoxelNodeRef::kNull) {
                EXPECT_GT(n.lo[0][c], n.hi[0][c]);
                continue;
            }
            ++usedSlots;
            if (!VoxelNodeRef::isLeaf(n.child[c])) continue;
            ++seen[VoxelNodeRef::index(n.child[c])];
            const VoxelLeaf& leaf = wide.leafData().leaves[VoxelNodeRef::index(n.child[c])];
            for (uint32_t i = leaf.first; i < leaf.first + leaf.count; ++i) {
                const VoxelCoord& v = wide.leafData().voxels[i];
                EXPECT_TRUE(v.x >= n.lo[0][c] && v.x <= n.hi[0][c] && v.y >= n.lo[1][c] && v.y <= n.hi[1][c] &&
                            v.z >= n.lo[2][c] && v.z <= n.hi[2][c]);
            }
        }
    for (int count : seen) EXPECT_EQ(count, 1);
    // A wide node of k children absorbs the k - 1 binary nodes it opened, each binary node once.
    EXPECT_EQ(usedSlots - wide.nodes().size(), binary.nodes().size());
    EXPECT_LT(wide.nodes().size() * 2, binary.nodes().size());
    EXPECT_LT(wide.height() * 2, binary.size().depth);
    // The same leaves, the same voxels in the same order: hits name the same source voxels.
    EXPECT_EQ(wide.leafData().voxels, binary.leafData().voxels);
    EXPECT_EQ(wide.leafData().sourceIndex, binary.leafData().sourceIndex);
    // A ray visits fewer interior nodes than through the binary tree, and no more leaves.
    VoxelTraversalCounters wideCounts, binaryCounts;
    for (const Ray& r : testRays(8, 500)) {
        wide.trace(VoxelRay(r), {}, &wideCounts);
        binary.trace(VoxelRay(r), {}, &binaryCounts);
    }
    EXPECT_EQ(wideCounts.hits, binaryCounts.hits);
    EXPECT_LT(wideCounts.interiorSteps * 2, binaryCounts.interiorSteps);
    EXPECT_LE(wideCounts.leafSteps, binaryCounts.leafSteps);
}

TEST(VoxelLaneOccupancy, CountsUsefulLaneSlotsOfLockstepIterations) {
    // Two lanes: interior, interior, leaf against interior, leaf. Iteration 0: both at an interior
    // step (one issue, two useful); 1: one interior, one leaf (two issues, two useful); 2: one
    // lane left (one issue, one useful). 5 useful of (1 + 2 + 1) x 2 slots.
    const std::vector<VoxelStepTrace> traces{{kInteriorStep, kInteriorStep, kLeafStep}, {kInteriorStep, kLeafStep}};
    const LaneOccupancy o = voxelLaneOccupancy(traces, 2);
    EXPECT_EQ(o.usefulSlots, 5u);
    EXPECT_EQ(o.laneSlots, 8u);
    // One lane wide, nothing is ever wasted.
    EXPECT_EQ(voxelLaneOccupancy(traces, 1).share(), 1.0);
}

}  // namespace
}  // namespace cuberille::rt
