// Deforming meshes: refitted boxes are tight, Lauterbach's criterion stays quiet under rigid
// motion and fires when a mesh explodes, and Larsson's lazy update answers every ray exactly as a
// full refit does, on any number of threads.

#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <random>

#include "raster/parallel.h"
#include "rt/bvh_build.h"
#include "rt/bvh_refit.h"
#include "rt/deforming_bvh.h"
#include "rt/lazy_refit.h"
#include "rt/ray_query.h"
#include "tests/rt/rt_test_support.h"
#include "tests/thread_counts.h"

namespace cuberille::rt {
namespace {

using testing::expectWellFormed;
using testing::OwnedMesh;

/// A wave through the sphere: every vertex moves, neighbours together (coherent deformation).
void wave(const OwnedMesh& rest, OwnedMesh& out, float time) {
    out.indices = rest.indices;
    out.positions.resize(rest.positions.size());
    for (size_t i = 0; i < rest.positions.size(); ++i) {
        const glm::vec3 p = rest.positions[i];
        out.positions[i] = p * (1.0f + 0.25f * std::sin(4.0f * p.z + time));
    }
}

/// The mesh as a soup of unshared vertices, each triangle with its own random velocity: triangles
/// that fly apart, so neighbours part and parents balloon (an exploding mesh).
struct ExplodingSoup {
    OwnedMesh mesh;
    std::vector<glm::vec3> velocity;  // per vertex, the same for a triangle's three
};

ExplodingSoup explodingSoup(const OwnedMesh& rest, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    ExplodingSoup s;
    for (size_t t = 0; t < rest.indices.size() / 3; ++t) {
        const glm::vec3 v(unit(rng), unit(rng), unit(rng));
        for (int c = 0; c < 3; ++c) {
            s.mesh.positions.push_back(rest.positions[rest.indices[3 * t + c]]);
            s.mesh.indices.push_back(uint32_t(s.mesh.positions.size() - 1));
            s.velocity.push_back(v);
        }
    }
    return s;
}

std::vector<Ray> randomRays(int count, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(-1.5f, 1.5f);
    std::vector<Ray> rays;
    for (int i = 0; i < count; ++i) rays.push_back(Ray{{unit(rng), unit(rng), unit(rng)}, {unit(rng), unit(rng), unit(rng)}});
    return rays;
}

TEST(BvhRefit, BoxesAreTightAfterEveryRefit) {
    const OwnedMesh rest = testing::uvSphere(32, 64);
    OwnedMesh moved;
    Bvh bvh = buildBvh(rest.view());
    for (int frame = 1; frame <= 5; ++frame) {
        wave(rest, moved, 0.7f * float(frame));
        refitBvh(bvh, moved.view());
        expectWellFormed(bvh, moved.view());
        for (const Ray& ray : randomRays(200, uint32_t(frame))) {
            EXPECT_EQ(closestHit(bvh, moved.view(), ray).triangle, closestHitBruteForce(moved.view(), ray).triangle);
            EXPECT_EQ(anyHit(bvh, moved.view(), ray), anyHitBruteForce(moved.view(), ray));
        }
    }
}

TEST(BvhRefit, RigidMotionNeverTriggersARebuild) {
    const OwnedMesh rest = testing::uvSphere(32, 64, glm::vec3(2.0f, 0.0f, 0.0f));
    Bvh bvh = buildBvh(rest.view());
    OwnedMesh moved = rest;
    for (int frame = 1; frame <= 60; ++frame) {
        // Translate, then turn about z: a rigid motion changes no triangle's neighbours.
        const float angle = 0.1f * float(frame);
        const glm::vec3 shift(0.5f * float(frame), -0.25f * float(frame), 1.0f);
        for (size_t i = 0; i < rest.positions.size(); ++i) {
            const glm::vec3 p = rest.positions[i];
            moved.positions[i] = glm::vec3(p.x * std::cos(angle) - p.y * std::sin(angle), p.x * std::sin(angle) + p.y * std::cos(angle), p.z) + shift;
        }
        const double degradation = refitBvh(bvh, moved.view());
        EXPECT_LT(degradation, 0.4) << "frame " << frame;
        EXPECT_LT(std::abs(degradation), 0.1) << "frame " << frame;
    }
}

TEST(BvhRefit, AnExplodingMeshTriggersARebuild) {
    // Every triangle flies off in its own direction: neighbours part, parents balloon.
    const auto [soup, velocity] = explodingSoup(testing::uvSphere(32, 64), 5);
    Bvh bvh = buildBvh(soup.view());
    OwnedMesh moved = soup;
    double degradation = 0.0;
    int firstFrameOverThreshold = -1;
    for (int frame = 1; frame <= 20 && firstFrameOverThreshold < 0; ++frame) {
        for (size_t i = 0; i < soup.positions.size(); ++i) moved.positions[i] = soup.positions[i] + 0.1f * float(frame) * velocity[i];
        degradation = refitBvh(bvh, moved.view());
        if (degradation > 0.4) firstFrameOverThreshold = frame;
    }
    EXPECT_GT(firstFrameOverThreshold, 1) << "not at once: the first small steps are fine";
    EXPECT_GT(degradation, 0.4);
    // A rebuild restores the quality: a fresh tree measures 0 against its own build ratios.
    const Bvh rebuilt = buildBvh(moved.view());
    EXPECT_EQ(bvhDegradation(rebuilt), 0.0);
}

TEST(BvhRefit, SameBoxesAndDegradationForAnyThreadCount) {
    const OwnedMesh rest = testing::randomSoup(100000, 21, 0.02f);
    OwnedMesh moved = rest;
    for (size_t i = 0; i < moved.positions.size(); ++i) moved.positions[i] += 0.1f * glm::sin(7.0f * glm::vec3(rest.positions[i].y, rest.positions[i].z, rest.positions[i].x));
    Bvh reference;
    double referenceDegradation = 0.0;
    for (const cuberille::testing::ThreadCount count : cuberille::testing::kThreadCounts) {
        const int threads = count.threads;
        const cuberille::testing::ThreadCountScope scope(count);
        Bvh bvh = buildBvh(rest.view());
        const double degradation = refitBvh(bvh, moved.view());
        if (count.exact) { EXPECT_EQ(scope.ran(), threads) << "threads that ran"; }
        if (threads == 1) {
            reference = bvh;
            referenceDegradation = degradation;
            continue;
        }
        EXPECT_EQ(degradation, referenceDegradation);
        EXPECT_EQ(0, std::memcmp(bvh.nodes.data(), reference.nodes.data(), bvh.nodes.size() * sizeof(BvhNode)));
    }
}

TEST(LazyRefit, GivesTheSameHitsAsAFullRefitEveryFrame) {
    const OwnedMesh rest = testing::uvSphere(40, 80);
    OwnedMesh moved;
    Bvh full = buildBvh(rest.view());
    Bvh lazyTree = full;
    LazyRefit lazy(lazyTree);
    EXPECT_GT(lazy.middleDepth(), 2);
    for (int frame = 1; frame <= 6; ++frame) {
        wave(rest, moved, 0.9f * float(frame));
        refitBvh(full, moved.view());
        lazy.update(moved.view());
        for (const Ray& ray : randomRays(500, uint32_t(frame))) {
            const RayHit a = closestHit(full, moved.view(), ray), b = lazy.closestHit(ray);
            ASSERT_EQ(a.triangle, b.triangle);
            if (a.hit()) { ASSERT_EQ(a.t, b.t); }
            ASSERT_EQ(anyHit(full, moved.view(), ray), lazy.anyHit(ray));
        }
        // Every box a query refreshed is the full refit's; refreshing the rest gives the full tree.
        lazy.refreshAll();
        ASSERT_EQ(0, std::memcmp(full.nodes.data(), lazyTree.nodes.data(), full.nodes.size() * sizeof(BvhNode)));
    }
}

TEST(LazyRefit, RaysThatMissRefreshNothingBelowTheMiddle) {
    const OwnedMesh rest = testing::uvSphere(40, 80);
    OwnedMesh moved;
    Bvh bvh = buildBvh(rest.view());
    LazyRefit lazy(bvh);
    wave(rest, moved, 1.0f);
    lazy.update(moved.view());
    for (int i = 0; i < 100; ++i) EXPECT_FALSE(lazy.closestHit(Ray{{5.0f, float(i) * 0.01f, 0.0f}, {0, 1, 0}}).hit());
    EXPECT_EQ(lazy.refreshedThisFrame(), 0u);
    // One ray into the mesh refreshes one path's worth of boxes and their siblings, not the tree.
    EXPECT_TRUE(lazy.closestHit(Ray{{0.0f, 0.0f, -5.0f}, {0, 0, 1}}).hit());
    EXPECT_GT(lazy.refreshedThisFrame(), 0u);
    EXPECT_LT(lazy.refreshedThisFrame(), bvh.nodes.size() / 10);
}

TEST(LazyRefit, ConcurrentQueriesGiveTheSameHitsAsSerialOnes) {
    const OwnedMesh rest = testing::uvSphere(64, 128);
    OwnedMesh moved;
    wave(rest, moved, 2.0f);
    const std::vector<Ray> rays = randomRays(20000, 77);
    std::vector<uint32_t> serial(rays.size()), parallel(rays.size());
    {
        Bvh bvh = buildBvh(rest.view());
        LazyRefit lazy(bvh);
        lazy.update(moved.view());
        for (size_t i = 0; i < rays.size(); ++i) serial[i] = lazy.closestHit(rays[i]).triangle;
    }
    Bvh bvh = buildBvh(rest.view());
    LazyRefit lazy(bvh);
    lazy.update(moved.view());
    raster::ThreadLimit limit(4);
    raster::parallelFor(rays.size(), [&](size_t i) { parallel[i] = lazy.closestHit(rays[i]).triangle; });
    EXPECT_EQ(serial, parallel);
}


TEST(DeformingBvh, RebuildsWhenTheCriterionFiresAndAnswersLikeBruteForceThroughout) {
    // An exploding soup under each update method, its rays answered by the wide tree (refreshed or
    // collapsed again after each update) or by the binary one: refit and lazy rebuild once the
    // degradation passes their threshold (and not before), and every ray is answered as brute
    // force answers it.
    const auto [soup, velocity] = explodingSoup(testing::uvSphere(16, 32), 3);
    for (const RayQueryTree queries : {RayQueryTree::Wide, RayQueryTree::Binary}) {
    for (const BvhUpdateMethod method : {BvhUpdateMethod::Refit, BvhUpdateMethod::Lazy, BvhUpdateMethod::Rebuild}) {
        SCOPED_TRACE(int(method) + 10 * int(queries));
        OwnedMesh moved = soup;
        DeformingBvh bvh(moved.view(), method, {}, 0.4, queries);
        for (const Ray& ray : randomRays(100, 99)) {  // the first pose, before any update
            ASSERT_EQ(bvh.closestHit(ray).triangle, closestHitBruteForce(moved.view(), ray).triangle);
            ASSERT_EQ(bvh.anyHit(ray), anyHitBruteForce(moved.view(), ray));
        }
        int rebuilt = 0;
        for (int frame = 1; frame <= 16; ++frame) {
            for (size_t i = 0; i < soup.positions.size(); ++i) moved.positions[i] = soup.positions[i] + 0.15f * float(frame) * velocity[i];
            const BvhUpdateReport report = bvh.update(moved.view());
            rebuilt += report.rebuilt;
            if (method != BvhUpdateMethod::Rebuild) {
                EXPECT_EQ(report.rebuilt, report.measured && report.degradation > 0.4) << "frame " << frame;
            }
            for (const Ray& ray : randomRays(100, uint32_t(frame))) {
                ASSERT_EQ(bvh.closestHit(ray).triangle, closestHitBruteForce(moved.view(), ray).triangle);
                ASSERT_EQ(bvh.anyHit(ray), anyHitBruteForce(moved.view(), ray));
            }
        }
        if (method == BvhUpdateMethod::Rebuild) EXPECT_EQ(rebuilt, 16);
        else EXPECT_GT(rebuilt, 0) << "an exploding mesh must trigger a rebuild";
        EXPECT_EQ(rebuilt, bvh.rebuilds());
        expectWellFormed(bvh.bvh(), moved.view());
    }
    }
}

}  // namespace
}  // namespace cuberille::rt
