// Shadow rays through alpha-tested casters (rt/caster_alpha_test.h): every any-hit traversal
// (brute force, the binary BVH, the wide BVH alone and in packets, the lazily refitted tree, the
// grid's walk and packets) answers as brute force through the same filter, and the filter reads
// the material's alpha as the shade stage forms it.

#include <gtest/gtest.h>

#include <memory>

#include "raster/texture.h"
#include "rt/bvh_build.h"
#include "rt/caster_alpha_test.h"
#include "rt/deforming_bvh.h"
#include "rt/screen_surfaces.h"
#include "rt/uniform_grid.h"
#include "tests/rt/rt_test_support.h"

namespace cuberille::rt {
namespace {

using testing::OwnedMesh;

bool passesWhereUIsSmall(const void*, uint32_t, const Ray&, float u, float) { return u < 0.4f; }

// Random soups with every other triangle alpha-tested (a hit counts where u < 0.4, so a ray may
// pass through one part of a triangle and stop at another), random rays and rays from the
// triangles' own surfaces: each traversal's any hit is brute force's through the filter, alone
// and in packets, and the filter changes the answer for some of the rays.
TEST(AlphaTestedAnyHit, EveryTraversalAnswersAsBruteForceThroughTheFilter) {
    for (const uint32_t seed : {1u, 2u}) {
        const OwnedMesh soup = testing::randomSoup(3000, seed, 0.4f);
        const TriangleMeshView mesh = soup.view();
        std::vector<uint8_t> entries(mesh.triangleCount(), HitFilter::kKept);
        for (size_t t = 0; t < entries.size(); t += 2) entries[t] = HitFilter::kAlphaTested;
        const HitFilter filter{entries, passesWhereUIsSmall, nullptr};
        const Bvh binary = buildBvh(mesh);
        const DeformingBvh wide(mesh, BvhUpdateMethod::Refit), lazy(mesh, BvhUpdateMethod::Lazy);
        const UniformGrid grid = buildUniformGrid(mesh);
        std::vector<Ray> rays;
        testing::forEachRandomRay(seed + 40, 1500, [&](const Ray& r) { rays.push_back(r); });
        testing::forEachRayFromSurface(mesh, seed + 80, 1500, [&](const Ray& r) { rays.push_back(r); });
        std::vector<uint8_t> expected(rays.size()), widePackets(rays.size()), gridPackets(rays.size());
        size_t changed = 0;
        for (size_t i = 0; i < rays.size(); ++i) {
            const Ray& r = rays[i];
            expected[i] = anyHitBruteForce(mesh, r, &filter);
            changed += expected[i] != anyHitBruteForce(mesh, r);
            ASSERT_EQ(anyHit(binary, mesh, r, &filter), bool(expected[i])) << "binary, ray " << i;
            ASSERT_EQ(wide.anyHit(r, &filter), bool(expected[i])) << "wide, ray " << i;
            ASSERT_EQ(lazy.anyHit(r, &filter), bool(expected[i])) << "lazy, ray " << i;
            ASSERT_EQ(anyHit(grid, mesh, r, nullptr, &filter), bool(expected[i])) << "grid, ray " << i;
        }
        // Packets: shadow rays from a shared region toward one point, as the stage sends them.
        std::vector<Ray> shadow;
        testing::forEachRayFromSurface(mesh, seed + 120, 2048, [&](const Ray& r) {
            Ray s = r;
            s.direction = glm::vec3(0.3f, 2.5f, 0.4f) - r.origin;
            s.tMax = 1.0f;
            shadow.push_back(s);
        });
        std::vector<uint8_t> single(shadow.size()), occludedWide(shadow.size(), 2), occludedGrid(shadow.size(), 2);
        for (size_t i = 0; i < shadow.size(); ++i) single[i] = anyHitBruteForce(mesh, shadow[i], &filter);
        wide.anyHits(shadow, occludedWide, &filter);
        anyHits(grid, mesh, shadow, occludedGrid, nullptr, &filter);
        EXPECT_EQ(occludedWide, single) << "wide packets";
        EXPECT_EQ(occludedGrid, single) << "grid packets";
        // Most random rays miss everything or meet several opaque triangles; 53 and 61 of the
        // 4,500 rays change answer with the filter (seeds 1 and 2).
        EXPECT_GT(changed, rays.size() / 100) << "the alpha test decides some rays";
    }
}

// The alpha a shadow ray reads at a hit: the factor times the interpolated vertex alphas, times
// the base colour texture's alpha at the interpolated coordinates (through the binding's
// transform), at the texture's finest level; a hit passes where that reaches the cutoff. Two
// ranges, the first opaque, check that a triangle finds its own range and vertices.
TEST(CasterAlphaFilter, PassesWhereTheMaterialsAlphaReachesItsCutoff) {
    OwnedMesh mesh;
    for (int k = 0; k < 2; ++k) {
        const uint32_t base = uint32_t(mesh.positions.size());
        for (const glm::vec3 p : {glm::vec3(0, 0, k), glm::vec3(1, 0, k), glm::vec3(0, 1, k)}) mesh.positions.push_back(p);
        for (uint32_t i = 0; i < 3; ++i) mesh.indices.push_back(base + i);
    }
    // Alpha 0 in the left texel, 1 in the right, magnified nearest.
    const raster::Texture halves(2, 1, std::vector<uint8_t>{9, 9, 9, 0, 9, 9, 9, 255}, raster::TexelFormat::Srgb8,
                                 raster::WrapMode::ClampToEdge, raster::WrapMode::ClampToEdge,
                                 {.magnifyNearest = true, .minify = raster::MinFilter::Nearest});
    const std::shared_ptr<const raster::Texture> white = alphaTestTexture(halves);
    const std::vector<glm::vec2> uvs = {{0.0f, 0.5f}, {1.0f, 0.5f}, {0.0f, 0.5f}};  // u along the second vertex's weight
    const std::vector<float> ramp = {0.2f, 1.0f, 0.2f};
    struct Case {
        CasterAlphaTest test;
        float (*alphaAt)(float u, float v);
    };
    const Case cases[] = {
        {{.cutoff = 0.5f, .factor = 1.0f, .vertexAlphas = {}, .texCoords = uvs, .alphaOnly = {white.get(), {}}},
         [](float u, float) { return u < 0.5f ? 0.0f : 1.0f; }},
        {{.cutoff = 0.5f, .factor = 0.8f, .vertexAlphas = ramp, .texCoords = {}, .alphaOnly = {}},
         [](float u, float v) { return 0.8f * ((1.0f - u - v) * 0.2f + u * 1.0f + v * 0.2f); }},
        {{.cutoff = 0.5f, .factor = 0.4f, .vertexAlphas = {}, .texCoords = {}, .alphaOnly = {}}, [](float, float) { return 0.4f; }},
    };
    for (const Case& c : cases) {
        const CasterRange ranges[2] = {{0, 1, 0, 3, raster::CullMode::None, {}}, {1, 1, 3, 3, raster::CullMode::None, c.test}};
        CasterAlphaFilter alpha;
        alpha.reset(ranges, mesh.indices);
        ASSERT_NE(alpha.filter(), nullptr);
        EXPECT_FALSE(alpha.alphaTested(0));
        EXPECT_TRUE(alpha.alphaTested(1));
        int passed = 0, failed = 0;
        for (int i = 0; i <= 20; ++i)
            for (int j = 0; i + j <= 20; ++j) {
                const float u = float(i) / 20.0f + 0.013f, v = float(j) / 20.0f * 0.9f;
                if (u + v > 1.0f) continue;
                const float expected = c.alphaAt(u, v);
                if (std::abs(expected - c.test.cutoff) < 1e-4f) continue;  // rounding decides at the cutoff itself
                const bool passes = alpha.passes(1, u, v);
                EXPECT_EQ(passes, expected >= c.test.cutoff) << "u " << u << " v " << v;
                (passes ? passed : failed)++;
            }
        if (c.alphaAt(1.0f, 0.0f) != c.alphaAt(0.0f, 0.0f)) {
            EXPECT_GT(passed, 0);
            EXPECT_GT(failed, 0);
        }
    }
    const CasterRange opaque[1] = {{0, 2, 0, 6, raster::CullMode::None, {}}};
    CasterAlphaFilter none;
    none.reset(opaque, mesh.indices);
    EXPECT_EQ(none.filter(), nullptr) << "no alpha-tested range: the rays test nothing more";
}

}  // namespace
}  // namespace cuberille::rt
