// Iso-surface voxels against the definition, checked sample by sample.

#include <cstring>

#include <gtest/gtest.h>

#include "raster/parallel.h"
#include "voxel/isosurface.h"
#include "voxel/packing.h"
#include "tests/thread_counts.h"

namespace cuberille {
namespace {

/// A ball of radius r (distance field, falling outwards) in a volume of dims, as f32 samples.
std::string ballVolume(const glm::uvec3& dims, const glm::dvec3& centre, double r) {
    std::string bytes(size_t(dims.x) * dims.y * dims.z * 4, '\0');
    size_t i = 0;
    for (uint32_t z = 0; z < dims.z; ++z)
        for (uint32_t y = 0; y < dims.y; ++y)
            for (uint32_t x = 0; x < dims.x; ++x, ++i) {
                const float v = float(r - glm::length(glm::dvec3(x, y, z) - centre));
                std::memcpy(&bytes[i * 4], &v, 4);
            }
    return bytes;
}

float sampleAt(const std::string& bytes, const glm::uvec3& dims, int x, int y, int z) {
    float v;
    std::memcpy(&v, &bytes[((size_t(z) * dims.y + size_t(y)) * dims.x + size_t(x)) * 4], 4);
    return v;
}

TEST(Isosurface, VoxelsAreInsideSamplesWithAnOutsideNeighbour) {
    const glm::uvec3 dims(70, 40, 90);  // not a multiple of the block size, not cubic
    const glm::dvec3 c(33.3, 20.1, 41.7);
    const std::string bytes = ballVolume(dims, c, 17.2);
    voxel::IsosurfaceStats stats;
    const voxel::VoxelModel m = voxel::extractIsosurface(bytes, {dims, voxel::SampleType::F32}, {0.0}, &stats);
    auto inside = [&](int x, int y, int z) {
        return x >= 0 && y >= 0 && z >= 0 && x < int(dims.x) && y < int(dims.y) && z < int(dims.z) &&
               sampleAt(bytes, dims, x, y, z) >= 0.0f;
    };
    std::set<std::tuple<int, int, int>> want;
    for (int z = 0; z < int(dims.z); ++z)
        for (int y = 0; y < int(dims.y); ++y)
            for (int x = 0; x < int(dims.x); ++x)
                if (inside(x, y, z) && (!inside(x + 1, y, z) || !inside(x - 1, y, z) || !inside(x, y + 1, z) ||
                                        !inside(x, y - 1, z) || !inside(x, y, z + 1) || !inside(x, y, z - 1)))
                    want.insert({x, y, z});
    std::set<std::tuple<int, int, int>> got;
    for (const voxel::VoxelBlock& b : m.blocks)
        for (size_t v = 0; v < b.voxels.size(); ++v) {
            const glm::uvec3 p = m.gridPosition(b, v);
            got.insert({int(p.x), int(p.y), int(p.z)});
            // Active faces are exactly the faces towards outside neighbours.
            const int x = int(p.x), y = int(p.y), z = int(p.z);
            const uint8_t expected = (inside(x + 1, y, z) ? 0 : voxel::kFacePosX) | (inside(x - 1, y, z) ? 0 : voxel::kFaceNegX) |
                                     (inside(x, y + 1, z) ? 0 : voxel::kFacePosY) | (inside(x, y - 1, z) ? 0 : voxel::kFaceNegY) |
                                     (inside(x, y, z + 1) ? 0 : voxel::kFacePosZ) | (inside(x, y, z - 1) ? 0 : voxel::kFaceNegZ);
            ASSERT_EQ(int(voxel::voxelFaceMask(b.voxels[v])), int(expected)) << x << "," << y << "," << z;
            // Normals point outwards, close to the ball's radial direction.
            const glm::dvec3 radial = glm::normalize(glm::dvec3(p) - c);
            EXPECT_GT(glm::dot(glm::dvec3(voxel::unpackNormal1010102(b.normals[v])), radial), 0.97);
        }
    EXPECT_EQ(got, want);
    EXPECT_GT(want.size(), 1000u);
    EXPECT_GT(stats.blocksSkipped, 0u) << "the corner blocks are all outside";
}

TEST(Isosurface, SampleTypesAgree) {
    const glm::uvec3 dims(24, 24, 24);
    std::string u8(dims.x * dims.y * dims.z, '\0'), u16(u8.size() * 2, '\0'), f32(u8.size() * 4, '\0');
    for (size_t i = 0; i < u8.size(); ++i) {
        const uint32_t x = uint32_t(i % 24), y = uint32_t(i / 24 % 24), z = uint32_t(i / 576);
        const uint8_t v = uint8_t((x * 7 + y * 3 + z * 5) % 200);
        u8[i] = char(v);
        const uint16_t w = uint16_t(v) * 300;
        std::memcpy(&u16[i * 2], &w, 2);
        const float f = float(v) / 4.0f;
        std::memcpy(&f32[i * 4], &f, 4);
    }
    auto set = [&](const std::string& bytes, voxel::SampleType t, double iso) {
        const voxel::VoxelModel m = voxel::extractIsosurface(bytes, {dims, t}, {iso});
        std::vector<uint32_t> all;
        for (const voxel::VoxelBlock& b : m.blocks) all.insert(all.end(), b.voxels.begin(), b.voxels.end());
        return all;
    };
    const auto a = set(u8, voxel::SampleType::U8, 100.0);
    EXPECT_FALSE(a.empty());
    EXPECT_EQ(a, set(u16, voxel::SampleType::U16, 30000.0));
    EXPECT_EQ(a, set(f32, voxel::SampleType::F32, 25.0));
}

TEST(Isosurface, SameVoxelsForAnyThreadCount) {
    const glm::uvec3 dims(130, 70, 66);
    const std::string bytes = ballVolume(dims, glm::dvec3(64.5, 35.2, 33.1), 30.0);
    auto run = [&](testing::ThreadCount count) {
        const testing::ThreadCountScope scope(count);
        voxel::VoxelModel m = voxel::extractIsosurface(bytes, {dims, voxel::SampleType::F32}, {0.0});
        if (count.exact) {
            EXPECT_EQ(scope.ran(), count.threads) << "threads that ran";
        }
        return m;
    };
    const voxel::VoxelModel one = run(testing::kThreadCounts[0]);
    for (const testing::ThreadCount count : {testing::kThreadCounts[1], testing::kThreadCounts[2]}) {
        const voxel::VoxelModel many = run(count);
        ASSERT_EQ(one.blocks.size(), many.blocks.size());
        for (size_t i = 0; i < one.blocks.size(); ++i) {
            EXPECT_EQ(one.blocks[i].coord, many.blocks[i].coord);
            EXPECT_EQ(one.blocks[i].voxels, many.blocks[i].voxels);
            EXPECT_EQ(one.blocks[i].normals, many.blocks[i].normals);
        }
    }
}

TEST(Isosurface, CentralDifferencesAlsoPointOutwards) {
    const glm::uvec3 dims(32, 32, 32);
    const glm::dvec3 c(15.5, 16.2, 15.9);
    const std::string bytes = ballVolume(dims, c, 10.0);
    voxel::IsosurfaceOptions o{0.0, voxel::GradientEstimator::CentralDifferences};
    const voxel::VoxelModel m = voxel::extractIsosurface(bytes, {dims, voxel::SampleType::F32}, o);
    ASSERT_FALSE(m.blocks.empty());
    for (const voxel::VoxelBlock& b : m.blocks)
        for (size_t v = 0; v < b.voxels.size(); ++v)
            EXPECT_GT(glm::dot(glm::dvec3(voxel::unpackNormal1010102(b.normals[v])),
                               glm::normalize(glm::dvec3(m.gridPosition(b, v)) - c)),
                      0.97);
}

}  // namespace
}  // namespace cuberille
