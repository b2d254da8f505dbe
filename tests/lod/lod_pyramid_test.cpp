// The LOD pyramid: serial and parallel simplification agree bit for bit, parents bound their
// children, the block octree links every block to its parent, skirts close block boundaries.

#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>

#include <gtest/gtest.h>

#include "lod/lod_pyramid.h"
#include "lod/simplify.h"
#include "raster/parallel.h"
#include "tests/voxel/voxel_test_support.h"
#include "voxel/cvox_file.h"
#include "voxel/packing.h"
#include "tests/thread_counts.h"

namespace cuberille {
namespace {

using voxel::VoxelBlock;
using voxel::VoxelModel;

VoxelModel sphereModel(uint32_t resolution) {
    std::mt19937 rng(21);
    const auto tris = testing::icosphere(4, glm::dvec3(0.3, 0.1, -0.2), 2.0, testing::randomRotation(rng));
    std::vector<glm::vec3> colors;
    for (size_t i = 0; i < tris.size(); ++i) colors.push_back(glm::vec3(float(i % 11) / 10.0f, 0.3f, float(i % 5) / 4.0f));
    voxel::VoxelizeOptions o;
    o.resolution = resolution;
    return voxel::voxelizeMesh(*testing::viewOf(tris, 500, colors), o);
}

bool sameBlocks(const std::vector<VoxelBlock>& a, const std::vector<VoxelBlock>& b) {
    if (a.size() != b.size()) return false;
    for (size_t i = 0; i < a.size(); ++i)
        if (a[i].level != b[i].level || a[i].coord != b[i].coord || a[i].voxels != b[i].voxels ||
            a[i].normals != b[i].normals || a[i].colors != b[i].colors || a[i].tightMin != b[i].tightMin ||
            a[i].tightMax != b[i].tightMax || a[i].firstChild != b[i].firstChild || a[i].childMask != b[i].childMask)
            return false;
    return true;
}

TEST(Simplify, SerialAndParallelGiveIdenticalPyramids) {
    const VoxelModel base = sphereModel(512);
    VoxelModel serial = base, parallel = base;
    lod::buildLodPyramid(serial, {lod::SimplifyMethod::Serial, 0});
    lod::buildLodPyramid(parallel, {lod::SimplifyMethod::Parallel, 0});
    ASSERT_EQ(serial.blocks.front().level, 3u);  // 512 -> 256 -> 128 -> 64
    EXPECT_TRUE(sameBlocks(serial.blocks, parallel.blocks));
    // And the same for every thread count.
    for (const testing::ThreadCount count : testing::kThreadCounts) {
        const testing::ThreadCountScope scope(count);
        VoxelModel again = base;
        lod::buildLodPyramid(again, {lod::SimplifyMethod::Parallel, 0});
        if (count.exact) { EXPECT_EQ(scope.ran(), count.threads) << "threads that ran"; }
        EXPECT_TRUE(sameBlocks(again.blocks, parallel.blocks)) << count.threads << " threads";
    }
}

TEST(Simplify, SerialStreamsFromAFileHoldingAtMostEightBlocks) {
    // Level 0 in a .cvox, read block by block; the source counts the blocks alive at once.
    const VoxelModel base = sphereModel(512);
    std::ostringstream out;
    voxel::writeCvox(base, out);
    const std::filesystem::path path =
        std::filesystem::path(::testing::TempDir()) / ("cuberille_stream_" + std::to_string(::getpid()) + ".cvox");
    std::ofstream(path, std::ios::binary) << out.str();
    struct FileSource final : lod::LevelSource {
        voxel::CvoxReader reader;
        mutable int alive = 0, mostAlive = 0, loads = 0;
        explicit FileSource(const std::filesystem::path& p) : reader(p) {}
        size_t blockCount() const override { return reader.blockCount(); }
        glm::uvec3 blockCoord(size_t i) const override { return reader.layout().blocks[i].coord; }
        std::shared_ptr<const VoxelBlock> load(size_t i) const override {
            mostAlive = std::max(mostAlive, ++alive);
            ++loads;
            return std::shared_ptr<const VoxelBlock>(new VoxelBlock(reader.load(i)), [this](const VoxelBlock* b) {
                --alive;
                delete b;
            });
        }
    } source(path);
    std::vector<VoxelBlock> streamed;
    lod::simplifySerial(source, base.blockSize, [&](VoxelBlock&& b) { streamed.push_back(std::move(b)); });
    EXPECT_LE(source.mostAlive, 8);
    EXPECT_EQ(source.alive, 0);
    EXPECT_EQ(size_t(source.loads), base.blocks.size()) << "each block read once";
    std::vector<const VoxelBlock*> level0;
    for (const VoxelBlock& b : base.blocks) level0.push_back(&b);
    EXPECT_TRUE(sameBlocks(streamed, lod::simplifyParallel(level0, base.blockSize)));
    std::filesystem::remove(path);
}

TEST(Simplify, ParentFacesAreTheUnionOfTheirChildren) {
    const VoxelModel base = sphereModel(256);
    std::vector<const VoxelBlock*> level0;
    for (const VoxelBlock& b : base.blocks) level0.push_back(&b);
    std::map<std::tuple<uint32_t, uint32_t, uint32_t>, uint8_t> expected;  // parent position -> union of faces
    for (const VoxelBlock& b : base.blocks)
        for (size_t v = 0; v < b.voxels.size(); ++v) {
            const glm::uvec3 p = base.gridPosition(b, v) / 2u;
            expected[{p.x, p.y, p.z}] |= voxel::voxelFaceMask(b.voxels[v]);
        }
    const std::vector<VoxelBlock> parents = lod::simplifyParallel(level0, base.blockSize);
    size_t count = 0;
    for (const VoxelBlock& b : parents) {
        EXPECT_EQ(b.level, 1u);
        for (size_t v = 0; v < b.voxels.size(); ++v, ++count) {
            const glm::uvec3 p = b.coord * base.blockSize + voxel::voxelPositionInBlock(b.voxels[v]);
            const auto it = expected.find({p.x, p.y, p.z});
            ASSERT_NE(it, expected.end()) << "a parent without children";
            EXPECT_EQ(voxel::voxelFaceMask(b.voxels[v]), it->second);
        }
    }
    EXPECT_EQ(count, expected.size()) << "every child has its parent";
}

TEST(Simplify, ParentsOfAPlaneKeepItsNormal) {
    const glm::dvec3 n = glm::normalize(glm::dvec3(1, 2, 3));
    auto onPlane = [&](double x, double y) { return glm::vec3(float(x), float(y), float((300.0 - x - 2.0 * y) / 3.0)); };
    std::vector<testing::Triangle> tris;
    for (int i = 0; i < 16; ++i)
        for (int j = 0; j < 16; ++j) {
            const double x = i * 8.0, y = j * 8.0;
            tris.push_back({onPlane(x, y), onPlane(x + 8, y), onPlane(x + 8, y + 8)});
            tris.push_back({onPlane(x, y), onPlane(x + 8, y + 8), onPlane(x, y + 8)});
        }
    VoxelModel m = testing::voxelizeInGrid(*testing::viewOf(tris), 256, voxel::Separability::Conservative);
    lod::buildLodPyramid(m, {});
    int checked = 0;
    for (const VoxelBlock& b : m.blocks) {
        if (b.level == 0) continue;
        for (uint32_t packed : b.normals) {
            const glm::vec3 got = voxel::unpackNormal1010102(packed);
            EXPECT_LT(glm::length(glm::dvec3(got) - n), 4.0 / 511) << "level " << b.level;
            ++checked;
        }
    }
    EXPECT_GT(checked, 100);
}

TEST(BlockOctree, EveryBlockHangsFromItsParent) {
    VoxelModel m = sphereModel(512);
    lod::buildLodPyramid(m, {});
    ASSERT_FALSE(m.blocks.empty());
    const uint32_t top = m.blocks.front().level;
    EXPECT_EQ(top, lod::pyramidLevels(512, 64) - 1);
    EXPECT_TRUE(m.blocks.size() == 1 || m.blocks[1].level < top) << "one root block";
    std::vector<int> parentsOf(m.blocks.size(), 0);
    for (size_t i = 0; i < m.blocks.size(); ++i) {
        const VoxelBlock& b = m.blocks[i];
        if (i > 0) {
            EXPECT_LE(b.level, m.blocks[i - 1].level) << "coarsest level first";
        }
        uint32_t child = b.firstChild;
        for (int octant = 0; octant < 8; ++octant) {
            if (!(b.childMask >> octant & 1)) continue;
            ASSERT_LT(child, m.blocks.size());
            const VoxelBlock& c = m.blocks[child];
            EXPECT_EQ(c.level + 1, b.level);
            EXPECT_EQ(c.coord, b.coord * 2u + glm::uvec3(octant & 1, octant >> 1 & 1, octant >> 2 & 1));
            ++parentsOf[child++];
        }
    }
    for (size_t i = 1; i < m.blocks.size(); ++i) EXPECT_EQ(parentsOf[i], 1) << "block " << i;
    EXPECT_EQ(parentsOf[0], 0);
}

TEST(Skirts, BlockBoundaryVoxelsShowTheirBoundaryFaces) {
    VoxelModel m = sphereModel(256);
    lod::PyramidStats stats;
    lod::buildLodPyramid(m, {}, &stats);
    EXPECT_GT(stats.skirtFaces, 0u);
    for (const VoxelBlock& b : m.blocks)
        for (uint32_t packed : b.voxels) {
            const glm::uvec3 p = voxel::voxelPositionInBlock(packed);
            const uint8_t f = voxel::voxelFaceMask(packed);
            if (p.x == 0) { EXPECT_TRUE(f & voxel::kFaceNegX); }
            if (p.x == 63) { EXPECT_TRUE(f & voxel::kFacePosX); }
            if (p.y == 0) { EXPECT_TRUE(f & voxel::kFaceNegY); }
            if (p.y == 63) { EXPECT_TRUE(f & voxel::kFacePosY); }
            if (p.z == 0) { EXPECT_TRUE(f & voxel::kFaceNegZ); }
            if (p.z == 63) { EXPECT_TRUE(f & voxel::kFacePosZ); }
        }
}

// Every voxel of every level: a face is cleared exactly when a voxel of the same block lies across
// it (brute force over the block's positions), and nothing else of the mask changes.
TEST(HiddenFaces, AFaceIsClearedExactlyWhenAVoxelOfItsBlockLiesAcrossIt) {
    VoxelModel cleared = sphereModel(256), kept = sphereModel(256);
    lod::PyramidStats stats;
    lod::buildLodPyramid(cleared, {}, &stats);
    lod::buildLodPyramid(kept, {.clearHiddenFaces = false});
    ASSERT_EQ(cleared.blocks.size(), kept.blocks.size());
    uint64_t clearedFaces = 0, silentVoxels = 0;
    for (size_t b = 0; b < kept.blocks.size(); ++b) {
        const VoxelBlock &with = cleared.blocks[b], &without = kept.blocks[b];
        ASSERT_EQ(with.voxels.size(), without.voxels.size());
        std::set<std::tuple<uint32_t, uint32_t, uint32_t>> positions;
        for (uint32_t packed : without.voxels) {
            const glm::uvec3 p = voxel::voxelPositionInBlock(packed);
            positions.insert({p.x, p.y, p.z});
        }
        for (size_t i = 0; i < without.voxels.size(); ++i) {
            const glm::uvec3 p = voxel::voxelPositionInBlock(without.voxels[i]);
            ASSERT_EQ(p, voxel::voxelPositionInBlock(with.voxels[i]));
            uint8_t across = 0;
            for (int axis = 0; axis < 3; ++axis)
                for (int side = 0; side < 2; ++side) {
                    glm::ivec3 q(p);
                    q[axis] += side == 0 ? 1 : -1;
                    if (glm::all(glm::greaterThanEqual(q, glm::ivec3(0))) &&
                        glm::all(glm::lessThan(q, glm::ivec3(int(kept.blockSize)))) &&
                        positions.count({uint32_t(q.x), uint32_t(q.y), uint32_t(q.z)}))
                        across |= uint8_t(1u << (2 * axis + side));
                }
            const uint8_t before = voxel::voxelFaceMask(without.voxels[i]);
            EXPECT_EQ(voxel::voxelFaceMask(with.voxels[i]), uint8_t(before & ~across)) << "block " << b << ", voxel " << i;
            clearedFaces += uint64_t(__builtin_popcount(before & across));
            silentVoxels += before != 0 && (before & ~across) == 0;
        }
    }
    EXPECT_EQ(stats.hiddenFacesCleared, clearedFaces);
    EXPECT_GT(clearedFaces, 0u);
    EXPECT_GT(silentVoxels, 0u) << "a voxel inside the conservative shell draws nothing";
}

TEST(BlockOctree, SurvivesTheVoxelFile) {
    VoxelModel m = sphereModel(256);
    lod::buildLodPyramid(m, {});
    std::ostringstream out;
    voxel::writeCvox(m, out);
    const std::filesystem::path path =
        std::filesystem::path(::testing::TempDir()) / ("cuberille_pyramid_" + std::to_string(::getpid()) + ".cvox");
    std::ofstream(path, std::ios::binary) << out.str();
    const VoxelModel r = voxel::readCvox(path);
    EXPECT_TRUE(sameBlocks(r.blocks, m.blocks));
    std::filesystem::remove(path);
}

}  // namespace
}  // namespace cuberille
