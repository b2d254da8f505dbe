// The shadow modes against the ray-traced reference on scenes made in code: hybrid equals it on
// every pixel (its documented limits do not arise in these scenes; a wire thinner than a texel,
// which the map misses, exercises the thin-caster marking), the map differs from it only where
// the hybrid method marks pixels, and every mode is deterministic across thread counts.

#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include "raster/parallel.h"
#include "rt/bvh_build.h"
#include "rt/ray.h"
#include "rt/screen_surfaces.h"
#include "rt/shadow_map.h"
#include "rt/shadows.h"
#include "tests/rt/rt_test_support.h"
#include "tests/thread_counts.h"

namespace cuberille::rt {
namespace {

using testing::addBox;
using testing::append;
using testing::OwnedMesh;

/// A ground plane with a floating box, a thin pole and a sphere: hard edges, a thin caster and a
/// curved receiver and caster.
OwnedMesh testScene() {
    OwnedMesh m;
    addBox(m, {-4.0f, -0.1f, -4.0f}, {4.0f, 0.0f, 4.0f});  // the ground
    addBox(m, {-1.5f, 1.0f, -0.5f}, {-0.5f, 1.6f, 0.5f});  // a floating box
    addBox(m, {1.0f, 0.0f, -1.0f}, {1.03f, 2.0f, -0.97f});  // a thin pole
    append(m, testing::uvSphere(24, 48, glm::vec3(0.8f, 0.6f, 1.2f), 0.5f));
    return m;
}

struct Rendered {
    ShadowMasks masks;
    ScreenSurfaces surfaces;
};

/// The stage as the renderer runs it (hybrid with the casters' edge adjacency), or with every
/// thin triangle marked (`silhouettesOnly` false).
Rendered shadowsOf(const OwnedMesh& scene, const raster::Lighting& lighting, const ShadowOptions& options, int width = 320,
                   int height = 240, bool silhouettesOnly = true, CasterAccel accel = CasterAccel::Bvh) {
    const TriangleMeshView mesh = scene.view();
    const DeformingBvh bvh(mesh, BvhUpdateMethod::Refit);  // a static scene's: never updated
    const UniformGrid grid = accel == CasterAccel::Grid ? buildUniformGrid(mesh) : UniformGrid{};
    const CasterRays rays = accel == CasterAccel::Grid ? CasterRays{.grid = &grid, .mesh = mesh} : CasterRays{.bvh = &bvh};
    const MeshAdjacency adjacency = buildMeshAdjacency(mesh);
    const glm::mat4 clipFromWorld = glm::perspectiveRH_ZO(glm::radians(50.0f), float(width) / float(height), 0.1f, 50.0f) *
                                    glm::lookAtRH(glm::vec3(3.0f, 4.0f, 6.0f), glm::vec3(0.0f, 0.5f, 0.0f), glm::vec3(0, 1, 0));
    const CasterRange all{0, uint32_t(mesh.triangleCount()), 0, uint32_t(mesh.positions.size()), raster::CullMode::None, {}};
    Rendered r;
    raster::Pipeline gpu;
    r.surfaces = findScreenSurfaces(mesh, std::span(&all, 1), clipFromWorld, width, height, gpu);
    r.masks = computeShadows(r.surfaces, lighting,
                             {.mesh = mesh, .rays = rays, .bounds = meshBounds(mesh),
                              .adjacency = silhouettesOnly ? &adjacency : nullptr, .adjacencyOnDemand = {}},
                             options, gpu);
    return r;
}

raster::Lighting sun() { return raster::Lighting::directional(glm::normalize(glm::vec3(0.4f, 1.0f, 0.3f)), glm::vec3(1.0f), glm::vec3(0.1f)); }

/// A point light above the scene and a spot light from the side, lighting it whole between them.
raster::Lighting pointAndSpotLights() {
    raster::Lighting lights;
    lights.ambient = glm::vec3(0.1f);
    lights.lightCount = 2;
    lights.lights[0].type = raster::LightType::Point;
    lights.lights[0].position = {0.5f, 4.0f, 0.8f};
    lights.lights[0].intensity = glm::vec3(5.0f);
    lights.lights[1].type = raster::LightType::Spot;
    lights.lights[1].position = {-2.0f, 3.5f, 2.0f};
    lights.lights[1].direction = glm::normalize(glm::vec3(0.5f, -1.0f, -0.5f));
    lights.lights[1].intensity = glm::vec3(5.0f);
    lights.lights[1].cosOuterCone = 0.8f;
    return lights;
}

TEST(Shadows, HybridEqualsRayTracedOnEveryPixel) {
    const OwnedMesh scene = testScene();
    for (const int mapSize : {256, 1024}) {
        ShadowOptions options;
        options.mapSizeTexels = mapSize;
        options.mode = ShadowMode::RayTraced;
        const Rendered reference = shadowsOf(scene, sun(), options);
        options.mode = ShadowMode::Hybrid;
        const Rendered hybrid = shadowsOf(scene, sun(), options);
        const std::vector<float>& a = reference.masks.visibility[0];
        const std::vector<float>& b = hybrid.masks.visibility[0];
        size_t differ = 0;
        for (size_t i = 0; i < a.size(); ++i) differ += a[i] != b[i];
        const ShadowStats& st = hybrid.masks.stats;
        std::printf("map %d: %zu of %llu receivers differ, %llu marked\n", mapSize, differ,
                    (unsigned long long)st.receiverPixels, (unsigned long long)st.markedPixels);
        EXPECT_EQ(differ, 0u) << "map " << mapSize;
        EXPECT_LT(st.markedPixels, st.receiverPixels / 4) << "hybrid should trace a minority of pixels";
    }
}

size_t countDifferent(const std::vector<float>& a, const std::vector<float>& b) {
    size_t n = 0;
    for (size_t i = 0; i < a.size(); ++i) n += a[i] != b[i];
    return n;
}

TEST(Shadows, AWireThinnerThanATexelShadowsInHybridWhereTheMapMissesIt) {
    // A wire 0.008 wide across the ground, a quarter of a texel of a 256-texel map over the
    // 8-unit ground: the map holds it in few texels or none, so its shadow is found by the
    // thin-caster marking (Lauterbach 2009, section 6.3) or not at all. Seen at 640x480 so that
    // its thin shadow holds enough pixel centres.
    OwnedMesh scene;
    addBox(scene, {-4.0f, -0.1f, -4.0f}, {4.0f, 0.0f, 4.0f});
    addBox(scene, {-2.0f, 0.8f, -0.004f}, {2.0f, 0.808f, 0.004f});
    ShadowOptions options;
    options.mapSizeTexels = 256;
    options.mode = ShadowMode::RayTraced;
    const Rendered reference = shadowsOf(scene, sun(), options, 640, 480);
    options.mode = ShadowMode::Map;
    const Rendered map = shadowsOf(scene, sun(), options, 640, 480);
    options.mode = ShadowMode::Hybrid;
    const Rendered hybrid = shadowsOf(scene, sun(), options, 640, 480);
    size_t shadowed = 0;
    for (size_t i = 0; i < reference.masks.visibility[0].size(); ++i)
        shadowed += reference.surfaces.covered(i) && reference.masks.visibility[0][i] == 0.0f;
    EXPECT_GT(shadowed, 10u) << "the wire's shadow reaches pixel centres";
    EXPECT_GT(countDifferent(reference.masks.visibility[0], map.masks.visibility[0]), shadowed / 2)
        << "the map alone misses most of the wire's shadow";
    EXPECT_EQ(countDifferent(reference.masks.visibility[0], hybrid.masks.visibility[0]), 0u);
}

TEST(Shadows, TheReferenceHasShadowsAndLight) {
    ShadowOptions options;
    options.mode = ShadowMode::RayTraced;
    const Rendered r = shadowsOf(testScene(), sun(), options);
    size_t shadowed = 0, lit = 0;
    for (size_t i = 0; i < r.masks.visibility[0].size(); ++i) {
        if (!r.surfaces.covered(i)) continue;
        shadowed += r.masks.visibility[0][i] == 0.0f;
        lit += r.masks.visibility[0][i] == 1.0f;
    }
    EXPECT_GT(shadowed, 500u);
    EXPECT_GT(lit, 20000u);
}

/// The reference itself against brute force: each receiver's ray to the light, from the same
/// offset origin, tested against every triangle in the direction it leaves the receiver (the
/// stage traces the segment from the light's end back, through the BVH). They may part only on
/// rays that graze a triangle's edge at the segment's very end, where rounding decides.
TEST(Shadows, TheReferenceEqualsBruteForceRaysForEveryLightType) {
    const OwnedMesh scene = testScene();
    const TriangleMeshView mesh = scene.view();
    raster::Lighting lights = pointAndSpotLights();
    lights.lights[2] = sun().lights[0];
    lights.lightCount = 3;
    ShadowOptions options;
    options.mode = ShadowMode::RayTraced;
    const Rendered r = shadowsOf(scene, lights, options, 160, 120);
    const float rayOffset = 1e-4f * std::max(0.5f * glm::length(meshBounds(mesh).extent()), 1e-3f);  // as the stage offsets
    for (int l = 0; l < 3; ++l) {
        const raster::Light& light = lights.lights[l];
        size_t tested = 0, shadowed = 0, differ = 0;
        for (size_t i = 0; i < r.surfaces.triangle.size(); ++i) {
            Surface s;
            const int x = int(i % size_t(r.surfaces.width)), y = int(i / size_t(r.surfaces.width));
            if (!r.surfaces.covered(i) || !r.surfaces.surfaceAt(x, y, s)) continue;
            const float v = r.masks.visibility[size_t(l)][i];
            const bool directional = light.type == raster::LightType::Directional;
            const glm::vec3 toLight = directional ? -glm::normalize(light.direction) : glm::normalize(light.position - s.position);
            const bool inCone = light.type != raster::LightType::Spot || glm::dot(light.direction, -toLight) > light.cosOuterCone;
            if (!(glm::dot(s.normal, toLight) > 0.0f) || !inCone) {
                EXPECT_EQ(v, 0.0f) << "light " << l << " pixel " << i << ": facing away or outside the cone";
                continue;
            }
            const Ray ray{s.position + s.normal * rayOffset, toLight, 0.0f,
                          directional ? std::numeric_limits<float>::infinity() : glm::distance(light.position, s.position) * (1.0f - 1e-4f)};
            const WatertightRay test(ray);
            bool blocked = false;
            for (size_t t = 0; t < mesh.triangleCount() && !blocked; ++t) {
                RayHit hit;
                blocked = test.intersect(mesh.vertex(t, 0), mesh.vertex(t, 1), mesh.vertex(t, 2), ray.tMin, ray.tMax, &hit);
            }
            ++tested;
            shadowed += blocked;
            differ += (v == 0.0f) != blocked;
        }
        EXPECT_GT(tested, 5000u) << "light " << l;
        EXPECT_GT(shadowed, 100u) << "light " << l << ": the scene should cast shadows";
        EXPECT_LE(double(differ), 1e-3 * double(tested)) << "light " << l << ": " << differ << " of " << tested << " differ";
    }
}

TEST(Shadows, MapDiffersFromRayTracedOnlyWhereHybridMarks) {
    const OwnedMesh scene = testScene();
    ShadowOptions options;
    options.mapSizeTexels = 256;  // coarse enough for the map to be visibly wrong
    options.mode = ShadowMode::RayTraced;
    const Rendered reference = shadowsOf(scene, sun(), options);
    options.mode = ShadowMode::Map;
    const Rendered map = shadowsOf(scene, sun(), options);
    options.mode = ShadowMode::Hybrid;
    const Rendered hybrid = shadowsOf(scene, sun(), options);
    const std::vector<float>&ref = reference.masks.visibility[0], &m = map.masks.visibility[0], &h = hybrid.masks.visibility[0];
    size_t mapWrong = 0, unmarkedWrong = 0;
    for (size_t i = 0; i < ref.size(); ++i) {
        if (m[i] == ref[i]) continue;
        ++mapWrong;
        unmarkedWrong += !hybrid.masks.marked[i];
    }
    EXPECT_GT(mapWrong, 20u) << "a 256-texel map should get shadow edges wrong";
    EXPECT_EQ(unmarkedWrong, 0u) << "every pixel the map gets wrong is one the hybrid method traces";
    EXPECT_EQ(countDifferent(ref, h), 0u);
}

TEST(Shadows, PointAndSpotLightsHybridEqualsRayTracedOnEveryPixel) {
    const OwnedMesh scene = testScene();
    const raster::Lighting lights = pointAndSpotLights();
    ShadowOptions options;
    options.mapSizeTexels = 1024;
    options.mode = ShadowMode::RayTraced;
    const Rendered reference = shadowsOf(scene, lights, options);
    options.mode = ShadowMode::Hybrid;
    const Rendered hybrid = shadowsOf(scene, lights, options);
    for (int l = 0; l < 2; ++l) {
        const size_t differ = countDifferent(reference.masks.visibility[l], hybrid.masks.visibility[l]);
        EXPECT_EQ(differ, 0u) << "light " << l;
    }
    EXPECT_EQ(hybrid.masks.stats.lightsShadowed, 2);
    EXPECT_LT(hybrid.masks.stats.markedPixels, hybrid.masks.stats.receiverPixels / 4);
}

/// Soft shadows from the sun (3 x 3 rays, a 1024-texel map): the ray-traced reference, then hybrid.
std::pair<Rendered, Rendered> softReferenceAndHybrid(const OwnedMesh& scene, float lightRadius) {
    ShadowOptions options;
    options.soft = true;
    options.lightRadius = lightRadius;
    options.softSamplesPerSide = 3;
    options.mapSizeTexels = 1024;
    options.mode = ShadowMode::RayTraced;
    Rendered reference = shadowsOf(scene, sun(), options);
    options.mode = ShadowMode::Hybrid;
    return {std::move(reference), shadowsOf(scene, sun(), options)};
}

/// Pixels in partial shadow: visibility strictly between 0 and 1.
size_t partialShadowCount(const Rendered& r) {
    size_t n = 0;
    for (const float v : r.masks.visibility[0]) n += v > 0.0f && v < 1.0f;
    return n;
}

TEST(Shadows, SoftHybridEqualsSoftRayTracedOnEveryPixel) {
    // Outside the penumbra the search finds the hybrid takes the map's hard answer; where the
    // true penumbra reached farther (it should not: each edge is asked at its own depth) pixels
    // would differ.
    const auto [reference, hybrid] = softReferenceAndHybrid(testScene(), 0.05f);
    const size_t differ = countDifferent(reference.masks.visibility[0], hybrid.masks.visibility[0]);
    std::printf("soft: %zu differ, %llu of %llu marked\n", differ, (unsigned long long)hybrid.masks.stats.markedPixels,
                (unsigned long long)hybrid.masks.stats.receiverPixels);
    EXPECT_EQ(differ, 0u);
    EXPECT_LT(hybrid.masks.stats.markedPixels, hybrid.masks.stats.receiverPixels / 2);
    EXPECT_GT(partialShadowCount(reference), 200u) << "the penumbra exists";
}

// The two seeds' structures (rt/caster_rays.h) answer every shadow ray alike: the masks through
// a grid built for the pose are the BVH's bit for bit, hard and soft, ray-traced and hybrid.
TEST(Shadows, TheGridGivesTheBvhsMasksBitForBit) {
    const OwnedMesh scene = testScene();
    for (const bool soft : {false, true})
        for (const ShadowMode mode : {ShadowMode::RayTraced, ShadowMode::Hybrid}) {
            ShadowOptions options;
            options.mode = mode;
            options.soft = soft;
            options.lightRadius = 0.05f;
            options.softSamplesPerSide = 3;
            options.mapSizeTexels = 512;
            const Rendered bvh = shadowsOf(scene, sun(), options, 160, 120);
            const Rendered grid = shadowsOf(scene, sun(), options, 160, 120, true, CasterAccel::Grid);
            ASSERT_GT(bvh.masks.stats.raysTraced, 0u);
            EXPECT_EQ(grid.masks.stats.raysTraced, bvh.masks.stats.raysTraced);
            EXPECT_EQ(grid.masks.visibility[0], bvh.masks.visibility[0]) << (soft ? "soft " : "hard ") << int(mode);
        }
}

TEST(Shadows, APointLikeSoftLightMarksWhatHardShadowsMark) {
    // A light too small for its rays to stray a texel from the shadow ray: every ray stays among
    // the receiver's own 3x3 texels, which the hard test has already found in agreement, so
    // the penumbra search adds nothing (a search widened by whole texels marked every receiver
    // near any edge nearer the light, penumbra or not).
    const OwnedMesh scene = testScene();
    ShadowOptions options;
    options.mapSizeTexels = 512;
    options.mode = ShadowMode::Hybrid;
    const Rendered hard = shadowsOf(scene, sun(), options);
    options.soft = true;
    options.lightRadius = 1e-5f;
    options.softSamplesPerSide = 2;
    const Rendered soft = shadowsOf(scene, sun(), options);
    EXPECT_EQ(soft.masks.marked, hard.masks.marked);
    options.mode = ShadowMode::RayTraced;
    const Rendered reference = shadowsOf(scene, sun(), options);
    EXPECT_EQ(countDifferent(reference.masks.visibility[0], soft.masks.visibility[0]), 0u);
}

TEST(Shadows, SoftMarksFollowThePenumbraNotEveryEdge) {
    // The penumbra search asks of each discontinuity whether the receiver's rays reach it at its
    // own depth; a wide light marks a wide band, a narrow one a narrow band, and either way
    // the masks equal the reference.
    const OwnedMesh scene = testScene();
    uint64_t marked[2] = {0, 0};
    for (const int i : {0, 1}) {
        const float radius = i == 0 ? 0.01f : 0.08f;
        const auto [reference, hybrid] = softReferenceAndHybrid(scene, radius);
        EXPECT_EQ(countDifferent(reference.masks.visibility[0], hybrid.masks.visibility[0]), 0u) << radius;
        const size_t partial = partialShadowCount(reference);
        marked[i] = hybrid.masks.stats.markedPixels;
        std::printf("radius %g: %zu receivers in partial shadow, %llu marked\n", radius, partial, (unsigned long long)marked[i]);
        EXPECT_LE(marked[i], 3 * partial + hybrid.masks.stats.receiverPixels / 100) << radius;
    }
    EXPECT_LT(2 * marked[0], marked[1]);
}

/// A renderer keeps one ShadowMasks from frame to frame, and each light's maps and marks are drawn
/// over the last frame's: whatever that frame was (another light type with another face count,
/// another map size, mode, penumbra or view, so another focus), the result is the one fresh
/// storage gives.
TEST(Shadows, MasksDrawnOverAnEarlierFramesEqualFreshOnes) {
    const OwnedMesh scene = testScene();
    const TriangleMeshView mesh = scene.view();
    const DeformingBvh bvh(mesh, BvhUpdateMethod::Refit);
    const MeshAdjacency adjacency = buildMeshAdjacency(mesh);
    const ShadowCasters casters{.mesh = mesh, .rays = {.bvh = &bvh}, .bounds = meshBounds(mesh), .adjacency = &adjacency, .adjacencyOnDemand = {}};
    const CasterRange all{0, uint32_t(mesh.triangleCount()), 0, uint32_t(mesh.positions.size()), raster::CullMode::None, {}};
    raster::Pipeline gpu;
    auto surfacesFrom = [&](glm::vec3 eye) {
        const glm::mat4 clipFromWorld = glm::perspectiveRH_ZO(glm::radians(50.0f), 320.0f / 240.0f, 0.1f, 50.0f) *
                                        glm::lookAtRH(eye, glm::vec3(0.0f, 0.5f, 0.0f), glm::vec3(0, 1, 0));
        return findScreenSurfaces(mesh, std::span(&all, 1), clipFromWorld, 320, 240, gpu);
    };
    const ScreenSurfaces views[2] = {surfacesFrom({3.0f, 4.0f, 6.0f}), surfacesFrom({-2.0f, 2.5f, 2.5f})};

    raster::Lighting point = pointAndSpotLights();
    point.lightCount = 1;  // the point light alone
    struct Frame {
        raster::Lighting lighting;
        ShadowMode mode;
        bool soft;
        int mapSize;
        int view;
    };
    const Frame frames[] = {{point, ShadowMode::Hybrid, true, 512, 0},  {sun(), ShadowMode::Hybrid, false, 1024, 0},
                            {sun(), ShadowMode::Hybrid, false, 1024, 1}, {sun(), ShadowMode::Hybrid, true, 256, 1},
                            {point, ShadowMode::Map, false, 256, 0},    {sun(), ShadowMode::Map, true, 512, 1},
                            {point, ShadowMode::Hybrid, false, 1024, 0}};
    ShadowMasks kept;
    int thinFrames = 0;
    for (const Frame& f : frames) {
        ShadowOptions options;
        options.mode = f.mode;
        options.soft = f.soft;
        options.softSamplesPerSide = 2;
        options.mapSizeTexels = f.mapSize;
        const ScreenSurfaces& surfaces = views[f.view];
        computeShadows(surfaces, f.lighting, casters, options, gpu, kept);
        raster::Pipeline freshGpu;
        const ShadowMasks fresh = computeShadows(surfaces, f.lighting, casters, options, freshGpu);
        const std::string frame = std::string(f.soft ? "soft " : "hard ") + (f.mode == ShadowMode::Map ? "map " : "hybrid ") +
                                  std::to_string(f.mapSize) + (f.lighting.lights[0].type == raster::LightType::Point ? " point" : " sun") +
                                  " view " + std::to_string(f.view);
        EXPECT_EQ(kept.visibility[0], fresh.visibility[0]) << frame;
        EXPECT_EQ(kept.marked, fresh.marked) << frame;
        EXPECT_EQ(kept.stats.markedPixels, fresh.stats.markedPixels) << frame;
        EXPECT_EQ(kept.stats.thinTriangles, fresh.stats.thinTriangles) << frame;
        thinFrames += fresh.stats.thinTriangles > 0;
    }
    EXPECT_GE(thinFrames, 3) << "the thin pole should be marked in most hybrid frames, or stale marks go unseen";
}

TEST(Shadows, SameMasksForAnyThreadCount) {
    const OwnedMesh scene = testScene();
    ShadowOptions options;
    options.mode = ShadowMode::Hybrid;
    options.soft = true;
    options.softSamplesPerSide = 2;
    options.mapSizeTexels = 512;
    std::vector<float> reference;
    for (const cuberille::testing::ThreadCount count : cuberille::testing::kThreadCounts) {
        const int threads = count.threads;
        const cuberille::testing::ThreadCountScope scope(count);
        const Rendered r = shadowsOf(scene, sun(), options);
        if (count.exact) { EXPECT_EQ(scope.ran(), threads) << "threads that ran"; }
        if (threads == 1) reference = r.masks.visibility[0];
        else EXPECT_EQ(r.masks.visibility[0], reference) << threads << " threads";
    }
}

/// Hard shadows from the sun with a map of `mapSize` texels: the ray-traced reference, then hybrid.
std::pair<Rendered, Rendered> referenceAndHybrid(const OwnedMesh& scene, int mapSize) {
    ShadowOptions options;
    options.mapSizeTexels = mapSize;
    options.mode = ShadowMode::RayTraced;
    Rendered reference = shadowsOf(scene, sun(), options);
    options.mode = ShadowMode::Hybrid;
    return {std::move(reference), shadowsOf(scene, sun(), options)};
}

/// A ground of long slivers, each far narrower than a 256-texel map's texel: every triangle is
/// thin in light space and in the world, as on a finely tessellated scan.
OwnedMesh sliverGround() {
    OwnedMesh m;
    constexpr int kStrips = 800;
    for (int i = 0; i < kStrips; ++i) {
        const float x0 = -4.0f + 8.0f * float(i) / kStrips, x1 = -4.0f + 8.0f * float(i + 1) / kStrips;
        const uint32_t b = uint32_t(m.positions.size());
        m.positions.insert(m.positions.end(), {{x0, 0.0f, -4.0f}, {x1, 0.0f, -4.0f}, {x1, 0.0f, 4.0f}, {x0, 0.0f, 4.0f}});
        m.indices.insert(m.indices.end(), {b, b + 2, b + 1, b, b + 3, b + 2});
    }
    return m;
}

TEST(Shadows, AFinelyTessellatedSurfaceIsNotItsOwnThinCaster) {
    // Marking a thin triangle's texels with its nearest vertex made every receiver on such a
    // surface its own potential occluder, so hybrid traced all of it. Tested as the map tests a
    // texel (depth at its centre against the receiver's plane), the slivers mark nothing under
    // themselves; a real thin caster over them (the pole) still marks its shadow.
    OwnedMesh scene = sliverGround();
    const auto [groundOnly, hybridGround] = referenceAndHybrid(scene, 256);
    EXPECT_EQ(countDifferent(groundOnly.masks.visibility[0], hybridGround.masks.visibility[0]), 0u);
    EXPECT_GT(hybridGround.masks.stats.receiverPixels, 20000u);
    EXPECT_LT(hybridGround.masks.stats.markedPixels, hybridGround.masks.stats.receiverPixels / 100);

    OwnedMesh withPole;
    addBox(withPole, {1.0f, 0.0f, -1.0f}, {1.03f, 2.0f, -0.97f});
    append(withPole, scene);
    const auto [reference, hybrid] = referenceAndHybrid(withPole, 256);
    EXPECT_EQ(countDifferent(reference.masks.visibility[0], hybrid.masks.visibility[0]), 0u);
    size_t poleShadow = 0;
    for (const float v : reference.masks.visibility[0]) poleShadow += v == 0.0f;
    EXPECT_GT(poleShadow, 10u) << "the pole casts a shadow the hybrid method had to find";
    EXPECT_GT(hybrid.masks.stats.markedPixels, hybridGround.masks.stats.markedPixels);
}

/// The sliver ground as one sheet: 800 strips cut into 8 rows, every vertex shared, so only
/// the triangles of the outer rows and strips touch its border.
OwnedMesh sliverSheet() {
    OwnedMesh m;
    constexpr int kStrips = 800, kRows = 8;
    for (int r = 0; r <= kRows; ++r)
        for (int i = 0; i <= kStrips; ++i)
            m.positions.push_back({-4.0f + 8.0f * float(i) / kStrips, 0.0f, -4.0f + 8.0f * float(r) / kRows});
    for (int r = 0; r < kRows; ++r)
        for (int i = 0; i < kStrips; ++i) {
            const uint32_t a = uint32_t(r * (kStrips + 1) + i), b = a + 1, c = a + kStrips + 1, d = c + 1;
            m.indices.insert(m.indices.end(), {a, d, b, a, c, d});
        }
    return m;
}

TEST(Shadows, ThinCastersAreLookedForAtSilhouettesOnly) {
    // A sheet of slivers, each thin in light space and in the world: with the casters'
    // adjacency only those touching its border (an open edge, as a silhouette is) and the
    // pole are candidates (Lauterbach section 6.3's silhouette test); without it, all of them.
    // The masks stay equal to the reference either way.
    OwnedMesh scene;
    addBox(scene, {1.0f, 0.0f, -1.0f}, {1.03f, 2.0f, -0.97f});
    append(scene, sliverSheet());
    const auto [reference, atSilhouettes] = referenceAndHybrid(scene, 256);
    ShadowOptions options;
    options.mapSizeTexels = 256;
    options.mode = ShadowMode::Hybrid;
    const Rendered everywhere = shadowsOf(scene, sun(), options, 320, 240, false);
    EXPECT_GE(everywhere.masks.stats.thinTriangles, 12800u);
    EXPECT_LT(atSilhouettes.masks.stats.thinTriangles, 3300u);
    EXPECT_GT(atSilhouettes.masks.stats.thinTriangles, 0u) << "the pole is thin and all silhouette";
    EXPECT_EQ(countDifferent(reference.masks.visibility[0], atSilhouettes.masks.visibility[0]), 0u);
    EXPECT_EQ(countDifferent(reference.masks.visibility[0], everywhere.masks.visibility[0]), 0u);
    EXPECT_LE(atSilhouettes.masks.stats.markedPixels, everywhere.masks.stats.markedPixels);
}

TEST(Shadows, EverySurfaceSeenLiesInTheHullTheMapIsFocusedOn) {
    const OwnedMesh scene = testScene();
    ShadowOptions options;
    options.mode = ShadowMode::Map;
    const Rendered r = shadowsOf(scene, sun(), options);
    ASSERT_EQ(r.surfaces.seenHull.size(), 8u);
    Aabb hull;
    for (const glm::vec3& p : r.surfaces.seenHull) hull.grow(p);
    size_t seen = 0;
    for (size_t i = 0; i < r.surfaces.triangle.size(); ++i) {
        Surface s;
        if (!r.surfaces.covered(i) || !r.surfaces.surfaceAt(int(i % size_t(r.surfaces.width)), int(i / size_t(r.surfaces.width)), s)) continue;
        ++seen;
        const glm::vec3 slack = 1e-4f * (glm::abs(s.position) + 1.0f);
        ASSERT_TRUE(glm::all(glm::greaterThanEqual(s.position + slack, hull.lo)) &&
                    glm::all(glm::lessThanEqual(s.position - slack, hull.hi)))
            << "pixel " << i;
    }
    EXPECT_GT(seen, 10000u);
}

TEST(Shadows, AFocusedDirectionalMapSpendsItsTexelsOnTheFocus) {
    // A 100-unit ground and a focus of two units across: the focused map's texels are about 50
    // times finer, and a point in the focus lands inside it.
    OwnedMesh ground;
    addBox(ground, {-50.0f, -0.1f, -50.0f}, {50.0f, 0.0f, 50.0f});
    const raster::Lighting light = sun();
    raster::Pipeline gpu;
    const ShadowMap wide = ShadowMap::render(light.lights[0], ground.view(), meshBounds(ground.view()), 512, gpu);
    const std::vector<glm::vec3> focus = {{-1.0f, 0.0f, -1.0f}, {1.0f, 0.0f, 1.0f}, {-1.0f, 0.5f, 1.0f}, {1.0f, 0.5f, -1.0f}};
    const ShadowMap focused = ShadowMap::render(light.lights[0], ground.view(), meshBounds(ground.view()), 512, gpu, focus);
    EXPECT_LT(focused.face(0).halfExtent * 30.0f, wide.face(0).halfExtent);
    for (const glm::vec3& p : focus) {
        const ShadowMapTexel t = focused.locate(p + glm::vec3(0.0f, 1e-3f, 0.0f));
        EXPECT_EQ(t.face, 0);
        EXPECT_LT(focused.depthAt(0, t.x, t.y), ShadowMap::kEmpty) << "the ground is drawn under the focus";
    }
}

TEST(Shadows, NoStageRunsWithoutAModeOrAShadowCastingLight) {
    const OwnedMesh scene = testScene();
    ShadowOptions options;  // mode None
    Rendered r = shadowsOf(scene, sun(), options);
    ASSERT_EQ(r.masks.visibility.size(), 1u);
    EXPECT_TRUE(r.masks.visibility[0].empty());
    EXPECT_EQ(r.masks.stats.lightsShadowed, 0);
    raster::Lighting dark = sun();
    dark.lights[0].intensity = glm::vec3(0.0f);
    options.mode = ShadowMode::Hybrid;
    r = shadowsOf(scene, dark, options);
    EXPECT_TRUE(r.masks.visibility[0].empty());
    EXPECT_EQ(r.masks.stats.raysTraced, 0u);
}

}  // namespace
}  // namespace cuberille::rt
