// The adaptive octree voxelizer against slow-but-sure references: brute-force triangle/box
// overlap for the conservative set, flood fills for separability, hand-computed attributes.

#include <cstring>
#include <deque>
#include <fstream>
#include <random>

#include <gtest/gtest.h>

#include "raster/parallel.h"
#include "tests/voxel/triangle_box_reference.h"
#include "tests/voxel/voxel_test_support.h"
#include "voxel/packing.h"
#include "voxel/partial_voxelization_file.h"
#include "tests/temp_paths.h"
#include "tests/thread_counts.h"

namespace cuberille {
namespace {

using testing::Triangle;
using testing::VoxelKey;
using voxel::Separability;

/// Every voxel of the grid whose closed box the closed triangle touches, exactly.
std::set<VoxelKey> bruteForceVoxels(const std::vector<Triangle>& tris, uint32_t r) {
    std::set<VoxelKey> out;
    const int64_t s = int64_t(testing::kLatticeSteps);
    for (const Triangle& t : tris) {
        testing::LatticePoint v[3];
        glm::dvec3 lo(1e30), hi(-1e30);
        for (int k = 0; k < 3; ++k) {
            v[k] = {std::llround(double(t[k].x) * s), std::llround(double(t[k].y) * s), std::llround(double(t[k].z) * s)};
            lo = glm::min(lo, glm::dvec3(t[k]));
            hi = glm::max(hi, glm::dvec3(t[k]));
        }
        const glm::ivec3 a = glm::clamp(glm::ivec3(glm::floor(lo)) - 1, 0, int(r) - 1);
        const glm::ivec3 b = glm::clamp(glm::ivec3(glm::floor(hi)) + 1, 0, int(r) - 1);
        for (int z = a.z; z <= b.z; ++z)
            for (int y = a.y; y <= b.y; ++y)
                for (int x = a.x; x <= b.x; ++x)
                    if (testing::triangleTouchesBox(v, {x * s, y * s, z * s}, {(x + 1) * s, (y + 1) * s, (z + 1) * s}))
                        out.insert({uint32_t(x), uint32_t(y), uint32_t(z)});
    }
    return out;
}

std::string describeDifference(const std::set<VoxelKey>& got, const std::set<VoxelKey>& want) {
    std::string s;
    int shown = 0;
    for (const VoxelKey& k : got)
        if (!want.count(k) && shown++ < 5)
            s += " extra(" + std::to_string(std::get<0>(k)) + "," + std::to_string(std::get<1>(k)) + "," +
                 std::to_string(std::get<2>(k)) + ")";
    for (const VoxelKey& k : want)
        if (!got.count(k) && shown++ < 10)
            s += " missing(" + std::to_string(std::get<0>(k)) + "," + std::to_string(std::get<1>(k)) + "," +
                 std::to_string(std::get<2>(k)) + ")";
    return s;
}

void expectConservativeEqualsBruteForce(const std::vector<Triangle>& tris, uint32_t r, const std::string& what) {
    if (std::getenv("CUBERILLE_DEBUG_VOXELIZER"))
        for (const Triangle& t : tris) {
            const auto v1 = testing::viewOf({t});
            const auto g = testing::voxelSet(testing::voxelizeInGrid(*v1, r, Separability::Conservative));
            const auto w = bruteForceVoxels({t}, r);
            if (g != w)
                std::printf("R %u: (%.10g %.10g %.10g) (%.10g %.10g %.10g) (%.10g %.10g %.10g):%s\n", r, t[0].x, t[0].y,
                            t[0].z, t[1].x, t[1].y, t[1].z, t[2].x, t[2].y, t[2].z, describeDifference(g, w).c_str());
        }
    const auto view = testing::viewOf(tris);
    const std::set<VoxelKey> got = testing::voxelSet(testing::voxelizeInGrid(*view, r, Separability::Conservative));
    const std::set<VoxelKey> want = bruteForceVoxels(tris, r);
    EXPECT_EQ(got, want) << what << ":" << describeDifference(got, want);
}

TEST(Conservative, EqualsBruteForceOnRandomMeshes) {
    std::mt19937 rng(20261123);
    for (uint32_t r : {8u, 16u, 64u}) {
        std::uniform_real_distribution<double> anywhere(0.0, double(r));
        for (double size : {0.3, 2.0, double(r)}) {
            std::uniform_real_distribution<double> offset(-size, size);
            std::vector<Triangle> tris;
            for (int i = 0; i < 60; ++i) {
                const glm::dvec3 c(anywhere(rng), anywhere(rng), anywhere(rng));
                Triangle t;
                for (int k = 0; k < 3; ++k)
                    t[k] = glm::vec3(testing::onLattice(std::clamp(c.x + offset(rng), 0.0, double(r))),
                                     testing::onLattice(std::clamp(c.y + offset(rng), 0.0, double(r))),
                                     testing::onLattice(std::clamp(c.z + offset(rng), 0.0, double(r))));
                tris.push_back(t);
            }
            expectConservativeEqualsBruteForce(tris, r, "R " + std::to_string(r) + ", size " + std::to_string(size));
        }
    }
}

TEST(Conservative, EqualsBruteForceOnHardCases) {
    const float e = float(1.0 / testing::kLatticeSteps);
    const std::vector<std::pair<std::string, Triangle>> cases = {
        {"in a voxel face plane", {{{1, 1, 3}, {6, 2, 3}, {2, 6, 3}}}},
        {"vertices on voxel corners", {{{1, 1, 1}, {4, 1, 1}, {1, 4, 4}}}},
        {"edges along voxel edges", {{{2, 2, 2}, {5, 2, 2}, {2, 2, 5}}}},
        {"plane through voxel corners", {{{0, 0, 6}, {6, 0, 0}, {0, 6, 0}}}},
        {"vertical plane through voxel edges", {{{0, 4, 0}, {4, 0, 0}, {4, 0, 8}}}},
        {"edge through corners inside a layer", {{{0, 0, 2.5f}, {4, 4, 2.5f}, {0, 4, 2.5f}}}},
        {"edge through an interior lattice corner", {{{0, 0, 0}, {8, 4, 2}, {2, 8, 4}}}},
        {"needle", {{{0.5f, 0.5f, 0.5f}, {7.5f, 7.25f, 7.5f}, {7.5f, 7.25f + e, 7.5f}}}},
        {"sliver", {{{0, 0, 0}, {8, 8, 8}, {8, 8 - e, 8}}}},
        {"spanning the domain", {{{0, 0, 0}, {8, 0, 8}, {0, 8, 8}}}},
        {"spanning the domain, tilted", {{{0, 0, 8}, {8, 8, 0}, {8, 0, 4}}}},
        {"degenerate: collinear through corners", {{{1, 1, 1}, {3, 3, 3}, {5, 5, 5}}}},
        {"degenerate: a point on a corner", {{{2, 2, 2}, {2, 2, 2}, {2, 2, 2}}}},
        {"degenerate: a point inside a voxel", {{{2.5f, 2.5f, 2.5f}, {2.5f, 2.5f, 2.5f}, {2.5f, 2.5f, 2.5f}}}},
        {"degenerate: a segment along a voxel edge", {{{2, 2, 0}, {2, 2, 5}, {2, 2, 3}}}},
        {"touching one corner", {{{4, 4, 4}, {6, 5, 4.5f}, {5, 6, 5.5f}}}},
        {"on the grid's lower face", {{{0, 1, 1}, {0, 5, 1}, {0, 1, 5}}}},
        {"on the grid's upper face", {{{8, 1, 1}, {8, 5, 1}, {8, 1, 5}}}},
        {"one lattice step off a face", {{{1, 1, 3 + e}, {6, 2, 3 + e}, {2, 6, 3 + e}}}},
    };
    for (const auto& [name, tri] : cases) expectConservativeEqualsBruteForce({tri}, 8, name);
}

/// Voxels reachable from outside the grid through empty voxels with the given connectivity.
std::vector<uint8_t> floodFromOutside(const std::set<VoxelKey>& full, uint32_t r, int connectivity) {
    const int n = int(r) + 2;  // one empty layer around the grid
    auto index = [n](int x, int y, int z) { return (size_t(z) * n + size_t(y)) * n + size_t(x); };
    std::vector<uint8_t> solid(size_t(n) * n * n, 0), reached(solid.size(), 0);
    for (const VoxelKey& k : full) solid[index(int(std::get<0>(k)) + 1, int(std::get<1>(k)) + 1, int(std::get<2>(k)) + 1)] = 1;
    std::deque<glm::ivec3> queue{{0, 0, 0}};
    reached[0] = 1;
    while (!queue.empty()) {
        const glm::ivec3 p = queue.front();
        queue.pop_front();
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int steps = std::abs(dx) + std::abs(dy) + std::abs(dz);
                    if (steps == 0 || (connectivity == 6 && steps != 1)) continue;
                    const glm::ivec3 q = p + glm::ivec3(dx, dy, dz);
                    if (glm::any(glm::lessThan(q, glm::ivec3(0))) || glm::any(glm::greaterThanEqual(q, glm::ivec3(n)))) continue;
                    const size_t i = index(q.x, q.y, q.z);
                    if (solid[i] || reached[i]) continue;
                    reached[i] = 1;
                    queue.push_back(q);
                }
    }
    return reached;
}

struct ClosedMesh {
    std::string name;
    std::vector<Triangle> tris;
    glm::dvec3 centre;
    double innerRadius;  // every point this close to the centre is inside
};

std::vector<ClosedMesh> closedMeshes(uint32_t r) {
    std::mt19937 rng(7);
    std::vector<ClosedMesh> meshes;
    for (int i = 0; i < 3; ++i) {
        const glm::dvec3 c = glm::dvec3(r) * 0.5 + glm::dvec3(0.13 * i, 0.29 * i, 0.41 * i);
        const double radius = r * (0.25 + 0.05 * i);
        // A subdivided icosahedron's faces are at least 0.98 of the radius from the centre.
        meshes.push_back({"sphere " + std::to_string(i), testing::icosphere(2 + i, c, radius, testing::randomRotation(rng)),
                          c, radius * 0.95});
    }
    return meshes;
}

void expectSeparates(Separability s, int connectivity) {
    const uint32_t r = 32;
    for (const ClosedMesh& m : closedMeshes(r)) {
        const auto view = testing::viewOf(m.tris, 64);
        const std::set<VoxelKey> set = testing::voxelSet(testing::voxelizeInGrid(*view, r, s));
        const std::vector<uint8_t> reached = floodFromOutside(set, r, connectivity);
        int insideEmpty = 0, leaked = 0;
        for (uint32_t z = 0; z < r; ++z)
            for (uint32_t y = 0; y < r; ++y)
                for (uint32_t x = 0; x < r; ++x) {
                    const glm::dvec3 c = glm::dvec3(x, y, z) + 0.5;
                    if (glm::length(c - m.centre) > m.innerRadius - 0.87 || set.count({x, y, z})) continue;
                    ++insideEmpty;
                    const size_t n = r + 2;
                    leaked += reached[((z + 1) * n + (y + 1)) * n + (x + 1)];
                }
        EXPECT_GT(insideEmpty, 0) << m.name;
        EXPECT_EQ(leaked, 0) << m.name << ": a " << connectivity << "-connected path of empty voxels reaches inside";
    }
}

TEST(Separability, SixSeparatingBlocksSixConnectedPaths) { expectSeparates(Separability::Six, 6); }
TEST(Separability, TwentySixSeparatingBlocksTwentySixConnectedPaths) { expectSeparates(Separability::TwentySix, 26); }
TEST(Separability, ConservativeBlocksTwentySixConnectedPaths) { expectSeparates(Separability::Conservative, 26); }

TEST(Separability, SixWithinTwentySixWithinConservative) {
    for (const ClosedMesh& m : closedMeshes(32)) {
        const auto view = testing::viewOf(m.tris, 64);
        const auto six = testing::voxelSet(testing::voxelizeInGrid(*view, 32, Separability::Six));
        const auto twentySix = testing::voxelSet(testing::voxelizeInGrid(*view, 32, Separability::TwentySix));
        const auto conservative = testing::voxelSet(testing::voxelizeInGrid(*view, 32, Separability::Conservative));
        EXPECT_TRUE(std::includes(twentySix.begin(), twentySix.end(), six.begin(), six.end())) << m.name;
        EXPECT_TRUE(std::includes(conservative.begin(), conservative.end(), twentySix.begin(), twentySix.end())) << m.name;
        // The crosshair prunes a surface to about one voxel thick. The diagonals keep nearly every
        // voxel a surface touches (any plane meeting a cube meets one of its diagonals), so 26
        // differs from conservative only where a triangle's boundary grazes a voxel.
        EXPECT_LT(double(six.size()), 0.8 * double(twentySix.size())) << m.name;
    }
}

TEST(Attributes, PlaneVoxelsCarryThePlaneNormal) {
    // A tilted plane across a 16³ grid, cut into many triangles.
    const glm::dvec3 n = glm::normalize(glm::dvec3(1, 2, 3));
    auto onPlane = [&](double x, double y) { return glm::vec3(float(x), float(y), float((30.0 - x - 2.0 * y) / 3.0)); };
    std::vector<Triangle> tris;
    for (int i = 0; i < 8; ++i)
        for (int j = 0; j < 8; ++j) {
            const double x = i, y = j;
            tris.push_back({onPlane(x, y), onPlane(x + 1, y), onPlane(x + 1, y + 1)});
            tris.push_back({onPlane(x, y), onPlane(x + 1, y + 1), onPlane(x, y + 1)});
        }
    const auto view = testing::viewOf(tris);
    const voxel::VoxelModel m = testing::voxelizeInGrid(*view, 16, Separability::Conservative);
    ASSERT_GT(m.voxelCount(), 50u);
    for (const voxel::VoxelBlock& b : m.blocks)
        for (size_t v = 0; v < b.voxels.size(); ++v) {
            const glm::vec3 got = voxel::unpackNormal1010102(b.normals[v]);
            EXPECT_NEAR(got.x, n.x, 2.0 / 511) << v;
            EXPECT_NEAR(got.y, n.y, 2.0 / 511) << v;
            EXPECT_NEAR(got.z, n.z, 2.0 / 511) << v;
            // The normal points +x, +y, +z beyond the epsilon: exactly those faces are active.
            EXPECT_EQ(voxel::voxelFaceMask(b.voxels[v]), voxel::kFacePosX | voxel::kFacePosY | voxel::kFacePosZ);
        }
}

TEST(Attributes, FaceParallelTriangleActivatesOneFace) {
    const auto view = testing::viewOf({{{{1.5f, 1.5f, 2.5f}, {5.5f, 1.5f, 2.5f}, {1.5f, 5.5f, 2.5f}}}});
    const voxel::VoxelModel m = testing::voxelizeInGrid(*view, 8, Separability::Conservative);
    ASSERT_GT(m.voxelCount(), 0u);
    for (const voxel::VoxelBlock& b : m.blocks)
        for (uint32_t packed : b.voxels) EXPECT_EQ(voxel::voxelFaceMask(packed), voxel::kFacePosZ);
}

TEST(Attributes, ColoursAverageByArea) {
    // In the plane z = 0.5 of voxel (0, 0, 0): a red quarter and a blue three quarters of its
    // slice (the triangles stop at the voxel's edges, touching the neighbours only with no area).
    const std::vector<Triangle> tris = {
        {{{0, 0, 0.5f}, {1, 0, 0.5f}, {1, 0.5f, 0.5f}}},  // area 1/4
        {{{0, 0, 0.5f}, {1, 0.5f, 0.5f}, {1, 1, 0.5f}}},  // area 1/4
        {{{0, 0, 0.5f}, {1, 1, 0.5f}, {0, 1, 0.5f}}},     // area 1/2
    };
    const glm::vec3 red(1, 0, 0), blue(0, 0, 1);
    const auto view = testing::viewOf(tris, 7, {red, blue, blue});
    const voxel::VoxelModel m = testing::voxelizeInGrid(*view, 4, Separability::Conservative);
    ASSERT_TRUE(m.hasColors);
    bool found = false;
    for (const voxel::VoxelBlock& b : m.blocks)
        for (size_t v = 0; v < b.voxels.size(); ++v)
            if (m.gridPosition(b, v) == glm::uvec3(0)) {
                found = true;
                const glm::vec3 c = voxel::unpackSrgba8Rgb(b.colors[v]);
                const glm::vec3 want = 0.25f * red + 0.75f * blue;
                // One 8-bit sRGB step near these values is under 0.01 in linear terms.
                EXPECT_NEAR(c.r, want.r, 0.01f);
                EXPECT_NEAR(c.g, want.g, 0.01f);
                EXPECT_NEAR(c.b, want.b, 0.01f);
            }
    EXPECT_TRUE(found);
}

voxel::VoxelModel voxelizeWithThreads(testing::ThreadCount count, Separability s) {
    std::mt19937 rng(3);
    std::vector<Triangle> tris = testing::icosphere(4, glm::dvec3(40.0), 30.0, testing::randomRotation(rng));
    std::vector<glm::vec3> colors;
    for (size_t i = 0; i < tris.size(); ++i) colors.push_back(glm::vec3(float(i % 7) / 6.0f, 0.5f, float(i % 3) / 2.0f));
    const auto view = testing::viewOf(tris, 97, colors);
    const testing::ThreadCountScope scope(count);
    voxel::VoxelizeOptions o;
    o.resolution = 128;
    o.separability = s;
    voxel::VoxelModel m = voxel::voxelizeMesh(*view, o);
    if (count.exact) {
        EXPECT_EQ(scope.ran(), count.threads) << "threads that ran";
    }
    return m;
}

bool sameModel(const voxel::VoxelModel& a, const voxel::VoxelModel& b) {
    if (a.blocks.size() != b.blocks.size()) return false;
    for (size_t i = 0; i < a.blocks.size(); ++i) {
        const voxel::VoxelBlock &x = a.blocks[i], &y = b.blocks[i];
        if (x.coord != y.coord || x.voxels != y.voxels || x.normals != y.normals || x.colors != y.colors ||
            x.triangles.size() != y.triangles.size() || x.tightMin != y.tightMin || x.tightMax != y.tightMax)
            return false;
        if (!x.triangles.empty() &&
            std::memcmp(x.triangles.data(), y.triangles.data(), x.triangles.size() * sizeof(voxel::SourceTriangle)) != 0)
            return false;
    }
    return true;
}

TEST(Determinism, SameVoxelsForAnyThreadCount) {
    for (Separability s : {Separability::Conservative, Separability::TwentySix}) {
        const voxel::VoxelModel one = voxelizeWithThreads(testing::kThreadCounts[0], s);
        ASSERT_GT(one.voxelCount(), 1000u);
        ASSERT_GT(one.blocks.size(), 1u);
        for (const testing::ThreadCount count : {testing::kThreadCounts[1], testing::kThreadCounts[2]})
            EXPECT_TRUE(sameModel(one, voxelizeWithThreads(count, s))) << count.threads << " threads";
    }
}

// The distributed voxelization's promise (python/cuberille/dask): chunks voxelized apart, in any
// split and merged in any order, give voxelizeMesh's model bit for bit — every block's voxels,
// normals, colours, bounds and source triangles — for each separability, with and without colours.
TEST(VoxelizeChunks, MergedPartsAreTheWholeVoxelizationForAnySplit) {
    std::mt19937 rng(11);
    std::vector<Triangle> tris = testing::icosphere(4, glm::dvec3(40.0), 30.0, testing::randomRotation(rng));
    std::vector<glm::vec3> colors;
    for (size_t i = 0; i < tris.size(); ++i) colors.push_back(glm::vec3(float(i % 5) / 4.0f, 0.25f, float(i % 3) / 2.0f));
    for (const bool withColors : {false, true})
        for (const Separability s : {Separability::Conservative, Separability::Six, Separability::TwentySix}) {
            const auto view = testing::viewOf(tris, 97, withColors ? colors : std::vector<glm::vec3>{});
            voxel::VoxelizeOptions o;
            o.resolution = 128;
            o.separability = s;
            const voxel::VoxelModel whole = voxel::voxelizeMesh(*view, o);
            const size_t n = view->chunkCount();
            ASSERT_GE(n, 6u);
            // One part; three uneven parts handed over last first; a part per chunk.
            std::vector<std::vector<std::pair<size_t, size_t>>> splits = {{{0, n}}, {{n / 2, n - n / 2}, {1, n / 2 - 1}, {0, 1}}};
            splits.emplace_back();
            for (size_t c = 0; c < n; ++c) splits.back().push_back({c, 1});
            for (const auto& split : splits) {
                std::vector<voxel::PartialVoxelization> parts;
                for (const auto& [first, count] : split) parts.push_back(voxel::voxelizeChunks(*view, o, first, count));
                voxel::VoxelizeStats stats;
                const voxel::VoxelModel merged = voxel::mergePartialVoxelizations(std::move(parts), &stats);
                EXPECT_TRUE(sameModel(merged, whole)) << "colours " << withColors << ", separability " << int(s) << ", "
                                                      << split.size() << " parts";
                EXPECT_EQ(merged.grid.origin, whole.grid.origin);
                EXPECT_EQ(merged.grid.extent, whole.grid.extent);
                EXPECT_EQ(merged.hasColors, whole.hasColors);
                EXPECT_EQ(stats.chunks, n);
            }
        }
}

// Parts travel between workers as files: written and read back they merge to the whole model;
// a part cut short is refused naming the file and the field.
TEST(VoxelizeChunks, PartsReadBackFromTheirFilesMergeToTheWholeModel) {
    std::mt19937 rng(13);
    const std::vector<Triangle> tris = testing::icosphere(3, glm::dvec3(10.0), 8.0, testing::randomRotation(rng));
    std::vector<glm::vec3> colors(tris.size(), glm::vec3(0.3f, 0.6f, 0.9f));
    const auto view = testing::viewOf(tris, 50, colors);
    voxel::VoxelizeOptions o;
    o.resolution = 128;
    o.separability = Separability::Six;
    const voxel::VoxelModel whole = voxel::voxelizeMesh(*view, o);
    const size_t n = view->chunkCount();
    std::vector<voxel::PartialVoxelization> parts;
    std::string firstFile;
    for (const auto& [first, count] : {std::pair<size_t, size_t>{0, n / 3}, {n / 3, n - n / 3}}) {
        const std::filesystem::path file = cuberille::testing::uniqueTempPath("part.cvxp");
        {
            std::ofstream out(file, std::ios::binary);
            voxel::writePartialVoxelization(voxel::voxelizeChunks(*view, o, first, count), out);
        }
        parts.push_back(voxel::readPartialVoxelization(file));
        if (firstFile.empty()) {
            std::ifstream in(file, std::ios::binary);
            firstFile.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
        }
    }
    EXPECT_TRUE(sameModel(voxel::mergePartialVoxelizations(std::move(parts)), whole));
    const std::filesystem::path cut = cuberille::testing::uniqueTempPath("cut.cvxp");
    std::ofstream(cut, std::ios::binary).write(firstFile.data(), std::streamsize(firstFile.size() / 2));
    try {
        voxel::readPartialVoxelization(cut);
        ADD_FAILURE() << "a part cut in half was read";
    } catch (const scene::InputError& e) {
        EXPECT_NE(std::string(e.what()).find(cut.string()), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
    }
}

/// The voxel arrays of two models (not their source triangles, which keep their own winding).
bool sameVoxels(const voxel::VoxelModel& a, const voxel::VoxelModel& b) {
    if (a.blocks.size() != b.blocks.size()) return false;
    for (size_t i = 0; i < a.blocks.size(); ++i) {
        const voxel::VoxelBlock &x = a.blocks[i], &y = b.blocks[i];
        if (x.coord != y.coord || x.voxels != y.voxels || x.normals != y.normals || x.colors != y.colors) return false;
    }
    return true;
}

// A mesh wound inwards (clockwise seen from outside, as ../shared/data/scans/cyberware-horse is)
// voxelizes to the voxels of the same mesh wound outwards, bit for bit: each voxel's normal is
// the other's negated exactly and its active faces mirrored, so its frames no longer show the
// inside of the far wall (docs/voxelization.md). Closed, and open (a sphere with a cap cut away,
// as scans have holes); whole, in parts merged, and in parts read back from their files.
TEST(Attributes, AMeshWoundInwardsGivesTheVoxelsOfTheSameMeshWoundOutwards) {
    std::mt19937 rng(17);
    const glm::dvec3 centre(40.0);
    const std::vector<Triangle> sphere = testing::icosphere(4, centre, 30.0, testing::randomRotation(rng));
    std::vector<Triangle> open;
    for (const Triangle& t : sphere)
        if ((t[0].z + t[1].z + t[2].z) / 3.0f < float(centre.z + 18.0)) open.push_back(t);
    ASSERT_LT(open.size(), sphere.size() * 9 / 10);
    for (const auto& [name, outward] : {std::pair{"closed", sphere}, std::pair{"open", open}}) {
        std::vector<Triangle> inward = outward;
        for (Triangle& t : inward) std::swap(t[1], t[2]);
        voxel::VoxelizeOptions o;
        o.resolution = 128;
        voxel::VoxelizeStats outStats, inStats;
        const auto outView = testing::viewOf(outward, 97), inView = testing::viewOf(inward, 97);
        const voxel::VoxelModel out = voxel::voxelizeMesh(*outView, o, &outStats);
        const voxel::VoxelModel in = voxel::voxelizeMesh(*inView, o, &inStats);
        EXPECT_FALSE(outStats.woundInwards) << name;
        EXPECT_TRUE(inStats.woundInwards) << name;
        ASSERT_GT(out.voxelCount(), 10000u);
        EXPECT_TRUE(sameVoxels(in, out)) << name;
        // Every voxel of the outward sphere has an active face, and some face away from the centre.
        size_t outwardFacing = 0;
        for (const voxel::VoxelBlock& b : out.blocks)
            for (size_t i = 0; i < b.voxels.size(); ++i) {
                const glm::vec3 n = voxel::unpackNormal1010102(b.normals[i]);
                const glm::uvec3 p = voxel::voxelPositionInBlock(b.voxels[i]);
                const glm::dvec3 at = out.grid.origin + (glm::dvec3(b.coord * out.blockSize + p) + 0.5) * out.grid.voxelSize();
                outwardFacing += glm::dot(glm::dvec3(n), at - centre) > 0.0;
            }
        EXPECT_EQ(outwardFacing, out.voxelCount()) << name << ": normals point out of the sphere";
        // In parts (the distributed voxelization), merged whole and through their files.
        const size_t n = inView->chunkCount();
        std::vector<voxel::PartialVoxelization> parts, fromFiles;
        for (const auto& [first, count] : {std::pair<size_t, size_t>{0, n / 3}, {n / 3, n - n / 3}}) {
            parts.push_back(voxel::voxelizeChunks(*inView, o, first, count));
            const std::filesystem::path file = cuberille::testing::uniqueTempPath("wound.cvxp");
            {
                std::ofstream stream(file, std::ios::binary);
                voxel::writePartialVoxelization(parts.back(), stream);
            }
            fromFiles.push_back(voxel::readPartialVoxelization(file));
            std::filesystem::remove(file);
        }
        voxel::VoxelizeStats mergedStats;
        EXPECT_TRUE(sameModel(voxel::mergePartialVoxelizations(std::move(parts), &mergedStats), in)) << name;
        EXPECT_TRUE(mergedStats.woundInwards) << name;
        EXPECT_TRUE(sameModel(voxel::mergePartialVoxelizations(std::move(fromFiles)), in)) << name;
    }
    // A flat patch has no inside: kept as wound, either way (seen from the grid's centre one of
    // the two windings has a negative signed volume).
    for (const bool reversed : {false, true}) {
        std::vector<Triangle> patch;
        auto at = [](double x, double y) { return glm::vec3(float(x), float(y), float(0.3 * x + 0.2 * y + 5.0)); };
        for (int i = 0; i < 6; ++i)
            for (int j = 0; j < 6; ++j) {
                patch.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
                patch.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
            }
        if (reversed)
            for (Triangle& t : patch) std::swap(t[1], t[2]);
        voxel::VoxelizeStats stats;
        const auto view = testing::viewOf(patch);
        voxel::VoxelizeOptions o;
        o.resolution = 16;
        voxel::voxelizeMesh(*view, o, &stats);
        EXPECT_FALSE(stats.woundInwards) << "a flat patch, reversed " << reversed;
    }
}

TEST(SourceTriangles, BlockPiecesCoverTheSourceArea) {
    std::mt19937 rng(5);
    const std::vector<Triangle> tris = testing::icosphere(3, glm::dvec3(100.0), 80.0, testing::randomRotation(rng));
    double sourceArea = 0;
    for (const Triangle& t : tris) sourceArea += 0.5 * glm::length(glm::cross(glm::dvec3(t[1] - t[0]), glm::dvec3(t[2] - t[0])));
    const auto view = testing::viewOf(tris);
    const voxel::VoxelModel m = testing::voxelizeInGrid(*view, 256, Separability::Conservative);
    ASSERT_GT(m.blocks.size(), 8u);
    double clippedArea = 0;
    for (const voxel::VoxelBlock& b : m.blocks) {
        const glm::dvec3 lo = glm::dvec3(b.coord) * 64.0, hi = lo + 64.0;
        for (const voxel::SourceTriangle& t : b.triangles) {
            for (const glm::vec3& p : t.position) {  // every piece lies in its block
                EXPECT_TRUE(glm::all(glm::greaterThanEqual(glm::dvec3(p), lo - 1e-3)) &&
                            glm::all(glm::lessThanEqual(glm::dvec3(p), hi + 1e-3)));
            }
            clippedArea += 0.5 * glm::length(glm::cross(glm::dvec3(t.position[1] - t.position[0]),
                                                        glm::dvec3(t.position[2] - t.position[0])));
        }
    }
    EXPECT_NEAR(clippedArea, sourceArea, sourceArea * 1e-5);
}

}  // namespace
}  // namespace cuberille
