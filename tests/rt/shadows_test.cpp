// The shadow modes against the ray-traced reference on scenes made in code: hybrid equals it on
// every pixel (its documented limits do not arise in these scenes; a wire thinner than a texel,
// which the map misses, exercises the thin-caster marking), the map differs from it only where
// the hybrid method marks pixels, and every mode is deterministic across thread counts.

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <string>

#include <glm/gtc/matrix_transform.hpp>

#include "raster/parallel.h"
#include "raster/texture.h"
#include "rt/bvh_build.h"
#include "rt/caster_alpha_test.h"
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
/// `ranges`: the casters' draws, with their alpha tests (empty: one opaque range).
Rendered shadowsOf(const OwnedMesh& scene, const raster::Lighting& lighting, const ShadowOptions& options, int width = 320,
                   int height = 240, bool silhouettesOnly = true, CasterAccel accel = CasterAccel::Bvh,
                   std::span<const CasterRange> ranges = {}) {
    const TriangleMeshView mesh = scene.view();
    const DeformingBvh bvh(mesh, BvhUpdateMethod::Refit);  // a static scene's: never updated
    const UniformGrid grid = accel == CasterAccel::Grid ? buildUniformGrid(mesh) : UniformGrid{};
    const CasterRange all{0, uint32_t(mesh.triangleCount()), 0, uint32_t(mesh.positions.size()), raster::CullMode::None, {}};
    if (ranges.empty()) ranges = std::span(&all, 1);
    CasterAlphaFilter alpha;
    alpha.reset(ranges, mesh.indices);
    const CasterRays rays = accel == CasterAccel::Grid ? CasterRays{.grid = &grid, .mesh = mesh, .filter = alpha.filter()}
                                                       : CasterRays{.bvh = &bvh, .mesh = mesh, .filter = alpha.filter()};
    const MeshAdjacency adjacency = buildMeshAdjacency(mesh);
    const glm::mat4 clipFromWorld = glm::perspectiveRH_ZO(glm::radians(50.0f), float(width) / float(height), 0.1f, 50.0f) *
                                    glm::lookAtRH(glm::vec3(3.0f, 4.0f, 6.0f), glm::vec3(0.0f, 0.5f, 0.0f), glm::vec3(0, 1, 0));
    Rendered r;
    raster::Pipeline gpu;
    r.surfaces = findScreenSurfaces(mesh, ranges, clipFromWorld, width, height, gpu);
    r.masks = computeShadows(r.surfaces, lighting,
                             {.mesh = mesh, .rays = rays, .bounds = meshBounds(mesh),
                              .adjacency = silhouettesOnly ? &adjacency : nullptr, .adjacencyOnDemand = {}, .ranges = ranges},
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

/// The brute-force references' shadow rays: for each receiver pixel of `r`, f(pixel, ray) with the
/// ray from its surface to the light, from the offset origin the stage uses, or a null ray where
/// the light cannot reach it (facing away, outside a spot's cone).
template <class F>
void forEachReferenceShadowRay(const Rendered& r, const TriangleMeshView& mesh, const raster::Light& light, F&& f) {
    const float rayOffset = 1e-4f * std::max(0.5f * glm::length(meshBounds(mesh).extent()), 1e-3f);  // as the stage offsets
    for (size_t i = 0; i < r.surfaces.triangle.size(); ++i) {
        Surface s;
        const int x = int(i % size_t(r.surfaces.width)), y = int(i / size_t(r.surfaces.width));
        if (!r.surfaces.covered(i) || !r.surfaces.surfaceAt(x, y, s)) continue;
        const bool directional = light.type == raster::LightType::Directional;
        const glm::vec3 toLight = directional ? -glm::normalize(light.direction) : glm::normalize(light.position - s.position);
        const bool inCone = light.type != raster::LightType::Spot || glm::dot(light.direction, -toLight) > light.cosOuterCone;
        if (!(glm::dot(s.normal, toLight) > 0.0f) || !inCone) {
            f(i, static_cast<const Ray*>(nullptr));
            continue;
        }
        const Ray ray{s.position + s.normal * rayOffset, toLight, 0.0f,
                      directional ? std::numeric_limits<float>::infinity() : glm::distance(light.position, s.position) * (1.0f - 1e-4f)};
        f(i, &ray);
    }
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

// An alpha-tested caster (glTF's alphaMode MASK: a fence, a leaf) blocks light only where its
// alpha passes the cutoff. A checkered quad (8 x 8 cells, alternately transparent and opaque,
// magnified nearest so each shadow ray's alpha is its cell's exactly) hangs over the ground.
// Ray-traced shadows, for every light type, agree with brute force that reads each cell from
// the hit's world position (not the barycentrics the stage uses), but for rays grazing a cell's
// border, where the two roundings part (bounded at 1e-3 of the receivers, as the opaque
// reference); hybrid equals ray-traced on every pixel, hard and soft, at a coarse and a fine map,
// because each alpha-tested triangle marks all the texels it covers; the grid gives the BVH's
// masks; map mode, drawing the board through its alpha test, casts its holes too. Without the
// alpha test the quad would cast one square shadow.
TEST(Shadows, AlphaTestedCastersLetLightThroughTheirHolesInEveryRayMode) {
    constexpr int kCells = 8;
    constexpr float kHalf = 1.5f, kHeight = 1.2f;
    OwnedMesh scene;
    addBox(scene, {-4.0f, -0.1f, -4.0f}, {4.0f, 0.0f, 4.0f});
    const uint32_t groundTriangles = uint32_t(scene.indices.size() / 3), groundVertices = uint32_t(scene.positions.size());
    for (const glm::vec2 c : {glm::vec2(-1, -1), glm::vec2(1, -1), glm::vec2(1, 1), glm::vec2(-1, 1)})
        scene.positions.push_back({kHalf * c.x, kHeight, kHalf * c.y});
    for (const uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) scene.indices.push_back(groundVertices + i);
    std::vector<glm::vec2> uvs;
    for (uint32_t v = groundVertices; v < scene.positions.size(); ++v)
        uvs.push_back({(scene.positions[v].x + kHalf) / (2 * kHalf), (scene.positions[v].z + kHalf) / (2 * kHalf)});
    std::vector<uint8_t> texels;
    for (int y = 0; y < kCells; ++y)
        for (int x = 0; x < kCells; ++x) texels.insert(texels.end(), {200, 200, 200, uint8_t((x + y) % 2 ? 255 : 0)});
    const raster::Texture checker(kCells, kCells, texels, raster::TexelFormat::Srgb8, raster::WrapMode::ClampToEdge,
                                  raster::WrapMode::ClampToEdge, {.magnifyNearest = true, .minify = raster::MinFilter::Nearest});
    const std::shared_ptr<const raster::Texture> white = alphaTestTexture(checker);
    const CasterRange ranges[2] = {
        {0, groundTriangles, 0, groundVertices, raster::CullMode::None, {}},
        {groundTriangles, 2, groundVertices, 4, raster::CullMode::None,
         CasterAlphaTest{.cutoff = 0.5f, .factor = 1.0f, .vertexAlphas = {}, .texCoords = uvs, .alphaOnly = {white.get(), {}}}}};
    const auto opaqueCellAt = [&](const glm::vec3& p) {
        const int x = std::clamp(int((p.x + kHalf) / (2 * kHalf) * kCells), 0, kCells - 1);
        const int y = std::clamp(int((p.z + kHalf) / (2 * kHalf) * kCells), 0, kCells - 1);
        return (x + y) % 2 == 1;
    };
    raster::Lighting lights = pointAndSpotLights();
    lights.lights[2] = sun().lights[0];
    lights.lightCount = 3;
    const TriangleMeshView mesh = scene.view();
    ShadowOptions options;
    options.mode = ShadowMode::RayTraced;
    const Rendered reference = shadowsOf(scene, lights, options, 320, 240, true, CasterAccel::Bvh, ranges);
    const Rendered opaque = shadowsOf(scene, lights, options, 320, 240);
    for (int l = 0; l < 3; ++l) {
        size_t tested = 0, throughHoles = 0, differ = 0;
        forEachReferenceShadowRay(reference, mesh, lights.lights[l], [&](size_t i, const Ray* reaching) {
            if (!reaching) return;
            const Ray& ray = *reaching;
            const WatertightRay test(ray);
            bool blocked = false, blockedIfOpaque = false;
            for (uint32_t t = 0; t < mesh.triangleCount() && !blocked; ++t) {
                RayHit hit;
                if (!test.intersect(mesh.vertex(t, 0), mesh.vertex(t, 1), mesh.vertex(t, 2), ray.tMin, ray.tMax, &hit)) continue;
                blockedIfOpaque = true;
                blocked = t < groundTriangles || opaqueCellAt(ray.origin + hit.t * ray.direction);
            }
            ++tested;
            throughHoles += blockedIfOpaque && !blocked;
            differ += (reference.masks.visibility[size_t(l)][i] == 0.0f) != blocked;
        });
        EXPECT_GT(throughHoles, 500u) << "light " << l << ": light reaches the ground through the holes";
        EXPECT_LE(double(differ), 1e-3 * double(tested)) << "light " << l << ": " << differ << " of " << tested << " differ";
        EXPECT_GT(countDifferent(reference.masks.visibility[size_t(l)], opaque.masks.visibility[size_t(l)]), 500u) << "light " << l;
    }
    for (const bool soft : {false, true})
        for (const int mapSize : {256, 2048}) {
            ShadowOptions o;
            o.soft = soft;
            o.lightRadius = 0.05f;
            o.softSamplesPerSide = 3;
            o.mapSizeTexels = mapSize;
            o.mode = ShadowMode::RayTraced;
            const Rendered traced = shadowsOf(scene, lights, o, 160, 120, true, CasterAccel::Bvh, ranges);
            const Rendered grid = shadowsOf(scene, lights, o, 160, 120, true, CasterAccel::Grid, ranges);
            o.mode = ShadowMode::Hybrid;
            const Rendered hybrid = shadowsOf(scene, lights, o, 160, 120, true, CasterAccel::Bvh, ranges);
            for (int l = 0; l < 3; ++l) {
                const std::string what = std::string(soft ? "soft" : "hard") + ", map " + std::to_string(mapSize) + ", light " + std::to_string(l);
                EXPECT_EQ(countDifferent(traced.masks.visibility[size_t(l)], hybrid.masks.visibility[size_t(l)]), 0u) << what;
                EXPECT_EQ(traced.masks.visibility[size_t(l)], grid.masks.visibility[size_t(l)]) << what;
            }
            EXPECT_LT(hybrid.masks.stats.markedPixels, hybrid.masks.stats.receiverPixels) << "the map still decides somewhere";
            if (soft) continue;
            // Map mode draws the board through its alpha test too: its holes are in the map, so
            // it parts from the rays only where a map parts anyway (edges), far less than a map
            // of the board drawn opaque.
            o.mode = ShadowMode::Map;
            const Rendered map = shadowsOf(scene, lights, o, 160, 120, true, CasterAccel::Bvh, ranges);
            const CasterRange opaqueRanges[2] = {ranges[0], {groundTriangles, 2, groundVertices, 4, raster::CullMode::None, {}}};
            const Rendered opaqueMap = shadowsOf(scene, lights, o, 160, 120, true, CasterAccel::Bvh, opaqueRanges);
            for (int l = 0; l < 3; ++l) {
                const size_t throughHoles = countDifferent(traced.masks.visibility[size_t(l)], map.masks.visibility[size_t(l)]);
                const size_t asIfOpaque = countDifferent(traced.masks.visibility[size_t(l)], opaqueMap.masks.visibility[size_t(l)]);
                EXPECT_LT(throughHoles * 4, asIfOpaque) << "map " << mapSize << ", light " << l;
            }
        }
}

// A spot or point light's map is a perspective projection whose near plane lies 1e4 times nearer
// than its far one. Stored as standard depth, a receiver near the far end was resolved to about a
// hundredth of its distance, coarser than a 2048-texel map's receiver bias: on a ground with a
// board over it, hybrid shadowed 12 receivers at a spot light's cone edge that the rays found
// lit. Stored reversed (rt/shadow_map.cpp), the depths keep float's relative precision, and
// hybrid is the ray-traced image at every size, with the map's depth within two millionths of
// the distance at which each texel centre's ray from the light meets the ground.
TEST(Shadows, PerspectiveMapsKeepTheirDepthPrecisionAtTheFarEnd) {
    OwnedMesh scene;
    addBox(scene, {-4.0f, -0.1f, -4.0f}, {4.0f, 0.0f, 4.0f});
    addBox(scene, {-1.5f, 1.2f, -1.5f}, {1.5f, 1.21f, 1.5f});
    const raster::Lighting lights = pointAndSpotLights();
    for (const int mapSize : {256, 2048, 4096}) {
        ShadowOptions options;
        options.mapSizeTexels = mapSize;
        options.mode = ShadowMode::RayTraced;
        const Rendered reference = shadowsOf(scene, lights, options);
        options.mode = ShadowMode::Hybrid;
        const Rendered hybrid = shadowsOf(scene, lights, options);
        for (int l = 0; l < 2; ++l)
            EXPECT_EQ(countDifferent(reference.masks.visibility[size_t(l)], hybrid.masks.visibility[size_t(l)]), 0u)
                << "map " << mapSize << ", light " << l;
    }
    // The ground's top face under the spot light, texel by texel: the ray through each texel
    // centre met with the plane y = 0, against the depth the map stored there.
    raster::Pipeline gpu;
    const ShadowMap map = ShadowMap::render(lights.lights[1], scene.view(), meshBounds(scene.view()), 2048, gpu);
    const ShadowMapFace& face = map.face(0);
    const glm::dmat4 worldFromView = glm::inverse(glm::dmat4(face.viewFromWorld));
    double worst = 0.0;
    size_t compared = 0;
    for (int y = 0; y < map.size(); y += 7)
        for (int x = 0; x < map.size(); x += 7) {
            // The points at depths 1 and 2 on the texel centre's ray from the light (view x is
            // texel x, view y texel -y; halfExtent is the tangent of half the field of view).
            const double a = (2.0 * (x + 0.5) / map.size() - 1.0) * face.halfExtent;
            const double b = (1.0 - 2.0 * (y + 0.5) / map.size()) * face.halfExtent;
            const glm::dvec3 p(worldFromView * glm::dvec4(a, b, -1.0, 1.0)), q(worldFromView * glm::dvec4(2.0 * a, 2.0 * b, -2.0, 1.0));
            if (!(q.y < p.y)) continue;
            // The depth where the ray reaches height h: along it, depth grows as the parameter does.
            const auto depthAtHeight = [&](double h) { return 1.0 + (p.y - h) / (p.y - q.y); };
            const auto pointAt = [&](double depth) { return p + (q - p) * (depth - 1.0); };
            const glm::dvec3 onBoard = pointAt(depthAtHeight(1.21));
            if (std::abs(onBoard.x) <= 1.6 && std::abs(onBoard.z) <= 1.6) continue;  // the board (or its rim) hides the ground
            const double depth = depthAtHeight(0.0);
            const glm::dvec3 onGround = pointAt(depth);
            if (std::abs(onGround.x) > 3.9 || std::abs(onGround.z) > 3.9) continue;  // off the ground (or its rim)
            const float stored = map.depthAt(0, x, y);
            if (stored == ShadowMap::kEmpty) continue;
            worst = std::max(worst, std::abs(double(stored) - depth) / depth);
            ++compared;
        }
    EXPECT_GT(compared, 1000u);
    // Measured 8.4e-7: the plane's interpolation rounds a few times terms as large as the depth
    // itself (6e-8 each), and linear depth comes back through one more division.
    EXPECT_LT(worst, 2e-6) << "relative error of the stored depth";
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
    for (int l = 0; l < 3; ++l) {
        size_t tested = 0, shadowed = 0, differ = 0;
        forEachReferenceShadowRay(r, mesh, lights.lights[l], [&](size_t i, const Ray* reaching) {
            const float v = r.masks.visibility[size_t(l)][i];
            if (!reaching) {
                EXPECT_EQ(v, 0.0f) << "light " << l << " pixel " << i << ": facing away or outside the cone";
                return;
            }
            const Ray& ray = *reaching;
            const WatertightRay test(ray);
            bool blocked = false;
            for (size_t t = 0; t < mesh.triangleCount() && !blocked; ++t) {
                RayHit hit;
                blocked = test.intersect(mesh.vertex(t, 0), mesh.vertex(t, 1), mesh.vertex(t, 2), ray.tMin, ray.tMax, &hit);
            }
            ++tested;
            shadowed += blocked;
            differ += (v == 0.0f) != blocked;
        });
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
    const ShadowCasters casters{.mesh = mesh, .rays = {.bvh = &bvh, .mesh = mesh}, .bounds = meshBounds(mesh), .adjacency = &adjacency, .adjacencyOnDemand = {}};
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
