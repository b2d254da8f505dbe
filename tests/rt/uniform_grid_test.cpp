// The uniform grid (Wald et al. 2006, §3) gives exactly the brute-force answer (same triangle,
// same t bits) on random scenes, on the lattice of faces, edges and vertices that breaks naive
// grid walks, flat and far-from-the-origin scenes, and rays starting on surfaces; its resolution
// is the paper's; its build is the same at any thread count; the walk tests few triangles.

#include <gtest/gtest.h>

#include <random>

#include <tbb/global_control.h>

#include "rt/ray_query.h"
#include "rt/uniform_grid.h"
#include "tests/rt/rt_test_support.h"

namespace cuberille::rt {
namespace {

using testing::OwnedMesh;

void expectSameAsBruteForce(const UniformGrid& grid, const TriangleMeshView& mesh, const Ray& ray) {
    const RayHit expected = closestHitBruteForce(mesh, ray);
    const RayHit got = closestHit(grid, mesh, ray);
    ASSERT_EQ(got.triangle, expected.triangle)
        << "origin " << ray.origin.x << " " << ray.origin.y << " " << ray.origin.z << " direction " << ray.direction.x << " "
        << ray.direction.y << " " << ray.direction.z << " tMin " << ray.tMin << " tMax " << ray.tMax;
    if (expected.hit()) {
        ASSERT_EQ(got.t, expected.t);
        ASSERT_EQ(got.u, expected.u);
        ASSERT_EQ(got.v, expected.v);
    } else {
        ASSERT_EQ(got.t, std::numeric_limits<float>::infinity());
    }
    ASSERT_EQ(anyHit(grid, mesh, ray), anyHitBruteForce(mesh, ray));
}

// The rays traced as packets (closestHits, anyHits) against brute force, ray by ray: the closest
// hit's triangle and the bits of t, u and v, and whether anything is hit.
void expectPacketsMatchBruteForce(const UniformGrid& grid, const TriangleMeshView& mesh, std::span<const Ray> rays) {
    std::vector<RayHit> hits(rays.size());
    closestHits(grid, mesh, rays, hits);
    std::vector<uint8_t> occluded(rays.size());
    anyHits(grid, mesh, rays, occluded);
    for (size_t i = 0; i < rays.size(); ++i) {
        ASSERT_EQ(bool(occluded[i]), anyHitBruteForce(mesh, rays[i])) << "any hit, ray " << i << " of " << rays.size();
        const RayHit expected = closestHitBruteForce(mesh, rays[i]);
        ASSERT_EQ(hits[i].triangle, expected.triangle) << "ray " << i << " of " << rays.size();
        ASSERT_EQ(hits[i].t, expected.t);
        ASSERT_EQ(hits[i].u, expected.u);
        ASSERT_EQ(hits[i].v, expected.v);
    }
}

TEST(UniformGrid, ClosestAndAnyHitEqualBruteForceOnRandomScenes) {
    for (const uint32_t seed : {1u, 2u, 3u}) {
        for (const float lambda : {kGridCellsPerTriangle, 1.0f, 40.0f}) {
            const OwnedMesh soup = testing::randomSoup(3000, seed, seed == 3 ? 1.5f : 0.3f);  // seed 3: long slivers across cells
            const UniformGrid grid = buildUniformGrid(soup.view(), lambda);
            testing::forEachRandomRay(seed + 100, 1500, [&](const Ray& ray) { expectSameAsBruteForce(grid, soup.view(), ray); });
        }
    }
}

// Every lattice coordinate is an integer and, at one cell per unit (lambda = 64 / N: a 4x4x4
// grid), every cell face lies in a plane of the lattice's faces: rays start in, run along and pass through cell faces, edges and
// corners, and through triangle edges and vertices, with +0 and -0 components.
TEST(UniformGrid, RaysAlongCellFacesThroughEdgesAndVerticesEqualBruteForce) {
    const OwnedMesh lattice = testing::cubeLattice(4);
    for (const float lambda : {kGridCellsPerTriangle, 64.0f / float(lattice.view().triangleCount())}) {
        const UniformGrid grid = buildUniformGrid(lattice.view(), lambda);
        if (lambda < 1.0f) { ASSERT_EQ(grid.cells, glm::ivec3(4)); }
        testing::forEachLatticeRay([&](const Ray& ray) { expectSameAsBruteForce(grid, lattice.view(), ray); });
    }
}

// A flat scene (one cell thick: the grid is 2D) and the same soup moved 10^5 units from the
// origin (cells a few hundred ulps of its coordinates wide): the walk's margin still holds.
TEST(UniformGrid, FlatAndFarFromTheOriginScenesEqualBruteForce) {
    OwnedMesh flat = testing::randomSoup(2000, 7, 0.2f);
    for (glm::vec3& p : flat.positions) p.z = 0.0f;
    OwnedMesh far = testing::randomSoup(2000, 8, 0.2f);
    for (glm::vec3& p : far.positions) p += glm::vec3(1e5f, -1e5f, 5e4f);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> unit(-1.5f, 1.5f);
    const UniformGrid flatGrid = buildUniformGrid(flat.view());
    EXPECT_EQ(flatGrid.cells.z, 1);
    EXPECT_GT(flatGrid.cells.x, 10);
    const UniformGrid farGrid = buildUniformGrid(far.view());
    for (int i = 0; i < 2000; ++i) {
        const glm::vec3 o(unit(rng), unit(rng), unit(rng)), d(unit(rng), unit(rng), unit(rng));
        expectSameAsBruteForce(flatGrid, flat.view(), Ray{o, d});
        expectSameAsBruteForce(flatGrid, flat.view(), Ray{{o.x, o.y, 0.0f}, {d.x, d.y, 0.0f}});  // in the plane
        expectSameAsBruteForce(farGrid, far.view(), Ray{o + glm::vec3(1e5f, -1e5f, 5e4f), d});
    }
}

TEST(UniformGrid, OriginsOnSurfacesEqualBruteForce) {
    const OwnedMesh sphere = testing::uvSphere(16, 32);
    const UniformGrid grid = buildUniformGrid(sphere.view());
    testing::forEachRayFromSurface(sphere.view(), 9, 3000, [&](const Ray& ray) { expectSameAsBruteForce(grid, sphere.view(), ray); });
}

TEST(UniformGrid, RaysLeavingFromUlpsOffASurfaceEqualBruteForce) {
    std::mt19937 rng(18);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    for (const OwnedMesh& mesh : {testing::cubeLattice(4), testing::uvSphere(24, 48, glm::vec3(37.0f, -11.0f, 5.0f), 3.0f)}) {
        const UniformGrid grid = buildUniformGrid(mesh.view());
        int rays = 0;
        testing::forEachRayLeavingNearASurface(mesh.view(), 17, 20000, 3, [&](const Ray& ray) {
            expectSameAsBruteForce(grid, mesh.view(), ray);
            if (rays++ % 16 != 0) return;
            // A coherent packet from the same origin, as an occlusion pixel's rays are: 16
            // directions within a narrow cone about this one, traced through the frustum path.
            std::vector<Ray> packet;
            for (int k = 0; k < 16; ++k)
                packet.push_back(Ray{ray.origin, ray.direction + 0.1f * glm::vec3(unit(rng), unit(rng), unit(rng)), 0.0f});
            expectPacketsMatchBruteForce(grid, mesh.view(), packet);
        });
    }
}

// Packets (Wald et al. §2) give each ray exactly brute force's closest hit and any hit: camera packets of 8x8 and 4x4
// rays from a common eye (the pixels of a small image, some rays missing the scene), shadow packets
// from points on the surface toward one light, segments, and incoherent packets (random
// directions: walked ray by ray), on random soups at three lambdas.
TEST(UniformGrid, PacketsGiveEachRayBruteForcesHit) {
    for (const uint32_t seed : {1u, 2u}) {
        const OwnedMesh soup = testing::randomSoup(3000, seed, 0.3f);
        const TriangleMeshView m = soup.view();
        std::mt19937 rng(seed + 50);
        std::uniform_real_distribution<float> unit(-1.0f, 1.0f), weight(0.0f, 1.0f);
        for (const float lambda : {kGridCellsPerTriangle, 1.0f, 20.0f}) {
            const UniformGrid grid = buildUniformGrid(m, lambda);
            auto check = [&](const std::vector<Ray>& rays) { expectPacketsMatchBruteForce(grid, m, rays); };
            for (int packet = 0; packet < 30; ++packet) {
                const int side = packet % 2 ? 8 : 4;
                // A camera outside the soup looking at a random point in it, a packet of its pixels.
                const glm::vec3 eye = 3.0f * glm::normalize(glm::vec3(unit(rng), unit(rng), unit(rng)));
                const glm::vec3 forward = glm::normalize(glm::vec3(unit(rng), unit(rng), unit(rng)) * 0.5f - eye);
                const glm::vec3 right = glm::normalize(glm::cross(forward, glm::vec3(0.3f, 1.0f, 0.1f)));
                const glm::vec3 up = glm::cross(right, forward);
                const float spread = packet % 3 == 0 ? 0.2f : 0.02f;  // a wide packet and a pixel-sized one
                std::vector<Ray> camera, shadow;
                for (int y = 0; y < side; ++y)
                    for (int x = 0; x < side; ++x) {
                        Ray r{eye, forward + spread * (float(x - side / 2) * right + float(y - side / 2) * up) / float(side)};
                        if (packet % 5 == 0) r.tMax = 3.0f;  // segments
                        camera.push_back(r);
                    }
                check(camera);
                // Shadow rays: from points on random triangles toward one light, leaving at 1e-4.
                const glm::vec3 light = glm::normalize(glm::vec3(unit(rng), unit(rng), unit(rng)));
                for (int i = 0; i < side * side; ++i) {
                    const uint32_t t = uint32_t(rng() % m.triangleCount());
                    float a = weight(rng), b = weight(rng);
                    if (a + b > 1.0f) a = 1.0f - a, b = 1.0f - b;
                    const glm::vec3 p = m.vertex(t, 0) + a * (m.vertex(t, 1) - m.vertex(t, 0)) + b * (m.vertex(t, 2) - m.vertex(t, 0));
                    shadow.push_back(Ray{p, light, 1e-4f});
                }
                check(shadow);
                std::vector<Ray> incoherent;
                for (int i = 0; i < 16; ++i) incoherent.push_back(Ray{{unit(rng), unit(rng), unit(rng)}, {unit(rng), unit(rng), unit(rng)}});
                check(incoherent);
            }
        }
    }
}

// The lattice's hard rays (faces, edges, vertices, +0 and -0), in packets of 16 consecutive rays,
// and all at once (traced as consecutive packets of 64).
TEST(UniformGrid, PacketsOfTheLatticesHardRaysGiveBruteForcesHits) {
    const OwnedMesh lattice = testing::cubeLattice(4);
    const TriangleMeshView m = lattice.view();
    const UniformGrid grid = buildUniformGrid(m, 64.0f / float(m.triangleCount()));
    std::vector<Ray> rays;
    testing::forEachLatticeRay([&](const Ray& ray) { rays.push_back(ray); });
    for (size_t first = 0; first < rays.size(); first += 16) {
        SCOPED_TRACE("packet from ray " + std::to_string(first));
        expectPacketsMatchBruteForce(grid, m, std::span<const Ray>(rays.data() + first, std::min<size_t>(16, rays.size() - first)));
    }
    expectPacketsMatchBruteForce(grid, m, rays);
}

// Macrocells (§2.4): a packet steps over a layer of macrocells its rectangle finds empty. Scenes
// of small triangles in a few clusters with empty space between (a random soup fills every
// macrocell, so the other tests rarely skip), camera and shadow packets through the gaps: the
// packets skip slices, and every ray still gets brute force's hit.
TEST(UniformGrid, PacketsSkipEmptyMacrocellsAndStillGiveBruteForcesHits) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    OwnedMesh clusters;
    const glm::vec3 centres[] = {{-0.8f, -0.7f, -0.9f}, {0.7f, 0.8f, 0.6f}, {0.75f, -0.8f, -0.1f}, {-0.6f, 0.7f, 0.85f}};
    for (const glm::vec3& c : centres) {
        const OwnedMesh blob = testing::randomSoup(400, uint32_t(rng()), 0.03f);
        for (size_t i = 0; i < blob.indices.size(); ++i) {
            clusters.positions.push_back(c + 0.12f * blob.positions[blob.indices[i]]);
            clusters.indices.push_back(uint32_t(clusters.positions.size() - 1));
        }
    }
    const TriangleMeshView m = clusters.view();
    const UniformGrid grid = buildUniformGrid(m);
    GridCounters counters;
    for (int packet = 0; packet < 40; ++packet) {
        const glm::vec3 target = centres[packet % 4] + 0.1f * glm::vec3(unit(rng), unit(rng), unit(rng));
        const glm::vec3 eye = 4.0f * glm::normalize(glm::vec3(unit(rng), unit(rng), unit(rng)));
        const glm::vec3 forward = glm::normalize(target - eye);
        const glm::vec3 right = glm::normalize(glm::cross(forward, glm::vec3(0.3f, 1.0f, 0.1f))), up = glm::cross(right, forward);
        std::vector<Ray> camera, shadow;
        for (int y = 0; y < 8; ++y)
            for (int x = 0; x < 8; ++x) camera.push_back(Ray{eye, forward + 0.01f * (float(x - 4) * right + float(y - 4) * up)});
        std::vector<RayHit> hits(camera.size());
        closestHits(grid, m, camera, hits, &counters);
        // From the camera's hits (or the target) toward a light: across the gaps to the other clusters.
        const glm::vec3 light = glm::normalize(centres[(packet + 1) % 4] - centres[packet % 4]);
        for (size_t i = 0; i < camera.size(); ++i)
            shadow.push_back(Ray{hits[i].hit() ? camera[i].origin + camera[i].direction * hits[i].t : target, light, 1e-4f});
        std::vector<uint8_t> occluded(shadow.size());
        anyHits(grid, m, shadow, occluded, &counters);
        SCOPED_TRACE("packet " + std::to_string(packet));
        expectPacketsMatchBruteForce(grid, m, camera);
        expectPacketsMatchBruteForce(grid, m, shadow);
    }
    EXPECT_GT(counters.slicesSkipped, 0u);
}

// The macrocells' ways to go wrong, each caught here: a packet skipping a slice that is not in an
// empty macrocell (the wall at every depth within a layer of macrocells, so some wall lies in the
// first slice after an empty layer), a packet judging a layer by less than the whole rectangle
// (the wall is a ring: the packet's middle rays pass through its hole, only its edge rays hit),
// and a single ray leaving an empty macrocell into the wrong cell. The same rays one at a time.
// Cells of size 1 over a 48^3 box (six layers of 6^3 macrocells), a tiny triangle at two corners
// to fix the box; an 8x8 packet of parallel rays and one from an eye, both along +z.
TEST(UniformGrid, MacrocellsSkipOnlyEmptySpaceForPacketsAndSingleRays) {
    for (int wallSlice = 6; wallSlice < 18; ++wallSlice) {
        OwnedMesh scene;
        auto triangle = [&](glm::vec3 a, glm::vec3 b, glm::vec3 c) {
            for (const glm::vec3& p : {a, b, c}) {
                scene.positions.push_back(p);
                scene.indices.push_back(uint32_t(scene.positions.size() - 1));
            }
        };
        triangle({0, 0, 0}, {0.01f, 0, 0}, {0, 0.01f, 0});
        triangle({48, 48, 48}, {47.99f, 48, 48}, {48, 47.99f, 48});
        const float z = float(wallSlice) + 0.5f;
        for (int y = 2; y < 46; ++y)
            for (int x = 2; x < 46; ++x) {
                if (x >= 8 && x < 40 && y >= 8 && y < 40) continue;  // the hole
                triangle({x, y, z}, {x + 1, y, z}, {x + 1, y + 1, z});
                triangle({x, y, z}, {x + 1, y + 1, z}, {x, y + 1, z});
            }
        const TriangleMeshView m = scene.view();
        const UniformGrid grid = buildUniformGrid(m, 48.0f * 48.0f * 48.0f / float(m.triangleCount()));
        ASSERT_EQ(grid.cells, glm::ivec3(48));
        std::vector<Ray> parallel, fromEye;
        for (int j = 0; j < 8; ++j)
            for (int i = 0; i < 8; ++i) {
                parallel.push_back(Ray{{2.5f + 43.0f * float(i) / 7.0f, 2.5f + 43.0f * float(j) / 7.0f, -1.0f}, {0, 0, 1}});
                fromEye.push_back(Ray{{24.0f, 24.0f, -10.0f}, {float(i) - 3.5f, float(j) - 3.5f, 3.0f}});
            }
        GridCounters counters;
        std::vector<RayHit> hits(64);
        closestHits(grid, m, parallel, hits, &counters);
        EXPECT_GT(counters.slicesSkipped, 0u);
        EXPECT_TRUE(hits[0].hit());  // an edge ray meets the ring
        SCOPED_TRACE("wall in slice " + std::to_string(wallSlice));
        expectPacketsMatchBruteForce(grid, m, parallel);
        expectPacketsMatchBruteForce(grid, m, fromEye);
        GridCounters walks;
        for (const std::vector<Ray>* rays : {&parallel, &fromEye})
            for (const Ray& ray : *rays) {
                closestHit(grid, m, ray, &walks);
                expectSameAsBruteForce(grid, m, ray);
            }
        EXPECT_GT(walks.macrocellsSkipped, 0u);
    }
}

// §3: N_a = d_a cbrt(lambda N / V), cubical cells; an empty mesh has no cells.
TEST(UniformGrid, ResolutionIsThePapersCubicalCellsAtLambdaPerTriangle) {
    Aabb box;
    box.grow(glm::vec3(0.0f));
    box.grow(glm::vec3(4.0f, 2.0f, 1.0f));
    const glm::ivec3 cells = gridResolution(box, 1000, 5.0f);  // 5000 cells of volume 8/5000: side 0.117
    EXPECT_EQ(cells, glm::ivec3(34, 17, 9));
    EXPECT_EQ(gridResolution(box, 0), glm::ivec3(0));
    EXPECT_TRUE(buildUniformGrid(TriangleMeshView{}).empty());
    EXPECT_FALSE(closestHit(UniformGrid{}, TriangleMeshView{}, Ray{}).hit());
}

TEST(UniformGrid, TheSameGridAtAnyThreadCount) {
    const OwnedMesh soup = testing::randomSoup(20000, 5, 0.1f);
    UniformGrid one, many;
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        one = buildUniformGrid(soup.view());
    }
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 7);
        many = buildUniformGrid(soup.view());
    }
    EXPECT_EQ(one.cells, many.cells);
    EXPECT_EQ(one.cellStart, many.cellStart);
    EXPECT_EQ(one.triangleRefs, many.triangleRefs);
}

// Coherent-enough rays into a dense soup test a small share of its 20000 triangles, the mailbox
// keeping a triangle listed in several cells to one test a ray.
TEST(UniformGrid, WalkTestsFewTriangles) {
    const OwnedMesh soup = testing::randomSoup(20000, 4, 0.05f);
    const UniformGrid grid = buildUniformGrid(soup.view());
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    GridCounters counters;
    const int rays = 1000;
    for (int i = 0; i < rays; ++i)
        closestHit(grid, soup.view(), Ray{{unit(rng), unit(rng), -3.0f}, {0.1f * unit(rng), 0.1f * unit(rng), 1.0f}}, &counters);
    EXPECT_LT(counters.trianglesTested / rays, 200u);
    EXPECT_GT(counters.cellsVisited, uint64_t(rays));
}

}  // namespace
}  // namespace cuberille::rt
