// Ambient occlusion by rays (rt/ambient_occlusion.h): the mask is exactly what testing every
// triangle gives, the estimator follows the cosine law it claims, surfaces do not occlude
// themselves, and the mask does not depend on the thread count.

#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include "raster/pipeline.h"
#include "rt/ambient_occlusion.h"
#include "rt/bvh_build.h"
#include "rt/ray_query.h"
#include "rt/screen_surfaces.h"
#include "rt/shadows.h"
#include "tests/rt/rt_test_support.h"
#include "tests/thread_counts.h"

namespace cuberille::rt {
namespace {

using testing::OwnedMesh;

/// A ground with a box standing on it, a box floating just above it and a sphere resting in the
/// corner they make: contact, a narrow gap and curved concavities, where occlusion varies.
OwnedMesh occludedScene() {
    OwnedMesh m;
    testing::addBox(m, {-4.0f, -0.1f, -4.0f}, {4.0f, 0.0f, 4.0f});
    testing::addBox(m, {-1.5f, 0.0f, -0.5f}, {-0.5f, 1.0f, 0.5f});
    testing::addBox(m, {0.2f, 0.15f, -1.5f}, {1.6f, 0.6f, -0.4f});
    testing::append(m, testing::uvSphere(16, 32, glm::vec3(-0.1f, 0.4f, 0.3f), 0.4f));
    return m;
}

struct Occlusion {
    ScreenSurfaces surfaces;
    std::vector<float> mask;
    AmbientOcclusionStats stats;
};

Occlusion occlusionOf(const OwnedMesh& scene, const CasterRays& casters, const AmbientOcclusionOptions& options, float distance) {
    const TriangleMeshView mesh = scene.view();
    const glm::mat4 clipFromWorld = glm::perspectiveRH_ZO(glm::radians(50.0f), 160.0f / 120.0f, 0.1f, 50.0f) *
                                    glm::lookAtRH(glm::vec3(2.5f, 3.0f, 4.5f), glm::vec3(-0.3f, 0.3f, 0.0f), glm::vec3(0, 1, 0));
    const CasterRange all{0, uint32_t(mesh.triangleCount()), 0, uint32_t(mesh.positions.size()), raster::CullMode::None, {}};
    raster::Pipeline gpu;
    Occlusion o;
    o.surfaces = findScreenSurfaces(mesh, std::span(&all, 1), clipFromWorld, 160, 120, gpu);
    computeAmbientOcclusion(o.surfaces, casters, distance, surfaceRayOffset(meshBounds(mesh)), options, o.mask, o.stats);
    return o;
}

TEST(AmbientOcclusion, MatchesBruteForceRaysBitForBit) {
    const OwnedMesh scene = occludedScene();
    const TriangleMeshView mesh = scene.view();
    const DeformingBvh bvh(mesh, BvhUpdateMethod::Refit);
    const AmbientOcclusionOptions options{.raysPerPixel = 12};
    const float distance = 0.6f, offset = surfaceRayOffset(meshBounds(mesh));
    const Occlusion o = occlusionOf(scene, {.bvh = &bvh}, options, distance);
    const std::vector<glm::vec3> directions = occlusionDirections(options.raysPerPixel);
    int compared = 0, partlyOpen = 0, open = 0;
    for (int y = 0; y < o.surfaces.height; ++y)
        for (int x = 0; x < o.surfaces.width; ++x) {
            const size_t i = size_t(y) * o.surfaces.width + x;
            Surface surface;
            if (!o.surfaces.covered(i) || !o.surfaces.surfaceAt(x, y, surface)) {
                EXPECT_EQ(o.mask[i], 1.0f) << "no surface at " << x << ", " << y;
                continue;
            }
            const float expected = openShare(surface, directions, occlusionTurnRadians(x, y), distance, offset,
                                             [&](const Ray& ray) { return anyHitBruteForce(mesh, ray); });
            ASSERT_EQ(o.mask[i], expected) << "pixel " << x << ", " << y;
            ++compared;
            partlyOpen += expected > 0.0f && expected < 1.0f;
            open += expected == 1.0f;
        }
    EXPECT_EQ(uint64_t(compared), o.stats.pixels);
    EXPECT_EQ(o.stats.rays, o.stats.pixels * uint64_t(options.raysPerPixel));
    // The comparison is only as strong as the scene: both occluded and open pixels must occur.
    EXPECT_GT(partlyOpen, 500) << "of " << compared;
    EXPECT_GT(open, 500) << "of " << compared;
}

/// A point on a floor under a ceiling at height h: a cosine-distributed ray at angle theta meets
/// the ceiling at h / cos(theta), so within d it is blocked exactly when cos(theta) > h / d, whose
/// cosine-weighted share is 1 - (h/d)^2. The open share is then (h/d)^2, and the directions'
/// stratification (sin^2(theta) at (i + 1/2) / N) puts the estimate within 1/N of it: the strata
/// on either side of the boundary are counted exactly, and the one it cuts is off by at most one
/// ray.
TEST(AmbientOcclusion, UnderACeilingTheOpenShareFollowsTheCosineLaw) {
    constexpr float kHalfSize = 1000.0f;  // far beyond any ray's reach below: an infinite plane
    for (const float height : {0.3f, 0.5f, 0.8f}) {
        OwnedMesh scene;
        testing::addBox(scene, {-kHalfSize, -0.1f, -kHalfSize}, {kHalfSize, 0.0f, kHalfSize});
        testing::addBox(scene, {-kHalfSize, height, -kHalfSize}, {kHalfSize, height + 0.1f, kHalfSize});
        const TriangleMeshView mesh = scene.view();
        const DeformingBvh bvh(mesh, BvhUpdateMethod::Refit);
        const Surface floor{.position = glm::vec3(0.3f, 0.0f, -0.2f), .normal = glm::vec3(0.0f, 1.0f, 0.0f)};
        const float offset = 1e-4f;
        for (const int rays : {64, 256}) {
            const std::vector<glm::vec3> directions = occlusionDirections(rays);
            for (const float distance : {0.6f, 1.0f, 2.0f}) {
                const float share = openShare(floor, directions, 0.7f, distance, offset,
                                              [&](const Ray& ray) { return bvh.anyHit(ray); });
                if (distance < height - offset) {
                    EXPECT_EQ(share, 1.0f) << "the ceiling is out of reach: h " << height << ", d " << distance;
                    continue;
                }
                const float c = (height - offset) / distance;
                EXPECT_NEAR(share, c * c, 1.0f / float(rays)) << "h " << height << ", d " << distance << ", " << rays << " rays";
            }
        }
    }
}

/// Rays leave the surface's own plane: a floor alone, and the faces of a convex box, see an open
/// sky from every pixel, whatever the reach (a ray meeting its own triangle would darken them).
TEST(AmbientOcclusion, OpenConvexSurfacesDoNotOccludeThemselves) {
    OwnedMesh scene;
    testing::addBox(scene, {-1.0f, -0.2f, -1.0f}, {1.0f, 0.0f, 1.0f});
    testing::append(scene, testing::uvSphere(24, 48, glm::vec3(0.0f, 2.0f, 0.0f), 0.3f));  // far off the slab
    const DeformingBvh bvh(scene.view(), BvhUpdateMethod::Refit);
    const Occlusion o = occlusionOf(scene, {.bvh = &bvh}, {.raysPerPixel = 16}, 1.0f);
    ASSERT_GT(o.stats.pixels, 1000u);
    for (size_t i = 0; i < o.mask.size(); ++i) ASSERT_EQ(o.mask[i], 1.0f) << "pixel " << i;
}

TEST(AmbientOcclusion, TheSameMaskAtAnyThreadCount) {
    const OwnedMesh scene = occludedScene();
    const DeformingBvh bvh(scene.view(), BvhUpdateMethod::Refit);
    std::vector<float> reference;
    for (const cuberille::testing::ThreadCount count : cuberille::testing::kThreadCounts) {
        const cuberille::testing::ThreadCountScope scope(count);
        const Occlusion o = occlusionOf(scene, {.bvh = &bvh}, {.raysPerPixel = 8}, 0.8f);
        if (count.exact) { EXPECT_EQ(scope.ran(), count.threads) << "threads that ran"; }
        if (count.threads == 1) reference = o.mask;
        else EXPECT_EQ(o.mask, reference) << count.threads << " threads";
    }
}

// The two seeds' structures (rt/caster_rays.h) answer every ray alike, so the mask is the same
// bits through a grid built for the pose as through the BVH.
TEST(AmbientOcclusion, TheGridGivesTheBvhsMaskBitForBit) {
    const OwnedMesh scene = occludedScene();
    const DeformingBvh bvh(scene.view(), BvhUpdateMethod::Refit);
    const UniformGrid grid = buildUniformGrid(scene.view());
    const Occlusion throughBvh = occlusionOf(scene, {.bvh = &bvh}, {.raysPerPixel = 16}, 0.8f);
    const Occlusion throughGrid = occlusionOf(scene, {.grid = &grid, .mesh = scene.view()}, {.raysPerPixel = 16}, 0.8f);
    ASSERT_GT(throughBvh.stats.rays, 0u);
    EXPECT_LT(*std::min_element(throughBvh.mask.begin(), throughBvh.mask.end()), 1.0f) << "some pixel is occluded";
    EXPECT_EQ(throughGrid.mask, throughBvh.mask);
}

TEST(AmbientOcclusion, DirectionsAreUnitAndInTheUpperHemisphere) {
    for (const int n : {1, 7, 64}) {
        const std::vector<glm::vec3> d = occlusionDirections(n);
        ASSERT_EQ(d.size(), size_t(n));
        for (const glm::vec3& v : d) {
            EXPECT_NEAR(glm::length(v), 1.0f, 1e-6f);
            EXPECT_GT(v.z, 0.0f);
        }
    }
    EXPECT_TRUE(occlusionDirections(0).empty());
}

}  // namespace
}  // namespace cuberille::rt
