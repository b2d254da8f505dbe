// The streaming I/O thread: reads what is asked, drops what is no longer asked, reports a bad
// block and goes on.

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>

#include "lod/block_loader.h"
#include "tests/lod/lod_test_support.h"

namespace cuberille {
namespace {

std::string pyramidBytes() { return testing::cvoxBytes(testing::spherePyramid(512, 8)); }

using testing::writeTemp;

std::vector<lod::LoadedBlock> waitForAll(lod::BlockLoader& loader, size_t count) {
    std::vector<lod::LoadedBlock> all;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (all.size() < count && std::chrono::steady_clock::now() < deadline) {
        for (lod::LoadedBlock& b : loader.takeCompleted()) all.push_back(std::move(b));
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return all;
}

TEST(BlockLoader, ReadsTheRequestedBlocksAsTheFileHoldsThem) {
    const auto path = writeTemp("loader.cvox", pyramidBytes());
    const voxel::CvoxReader reader(path);
    const voxel::VoxelModel whole = voxel::readCvox(path);
    lod::BlockLoader loader(reader);
    std::vector<uint32_t> wanted;
    for (uint32_t i = 0; i < whole.blocks.size(); i += 3) wanted.push_back(i);
    loader.replaceRequests({wanted.begin(), wanted.end()});
    const std::vector<lod::LoadedBlock> got = waitForAll(loader, wanted.size());
    ASSERT_EQ(got.size(), wanted.size());
    for (size_t k = 0; k < got.size(); ++k) {
        EXPECT_EQ(got[k].block, wanted[k]) << "most important first";
        ASSERT_TRUE(got[k].data.has_value()) << got[k].error;
        EXPECT_EQ(got[k].data->voxels, whole.blocks[wanted[k]].voxels);
        EXPECT_EQ(got[k].data->normals, whole.blocks[wanted[k]].normals);
    }
    EXPECT_TRUE(loader.idle());
    EXPECT_GT(loader.bytesRead(), 0u);
    std::filesystem::remove(path);
}

TEST(BlockLoader, ANewFramesRequestsReplaceTheQueue) {
    const auto path = writeTemp("replace.cvox", pyramidBytes());
    const voxel::CvoxReader reader(path);
    lod::BlockLoader loader(reader, 2.0);  // a slow disk: 2 MiB/s
    std::vector<lod::BlockRequest> many;
    for (uint32_t i = 1; i < reader.blockCount(); ++i) many.push_back(i);
    loader.replaceRequests(many);
    loader.replaceRequests({0});  // the next frame wants only the root
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    std::vector<uint32_t> read;
    while (std::chrono::steady_clock::now() < deadline) {
        for (const lod::LoadedBlock& b : loader.takeCompleted()) read.push_back(b.block);
        if (std::find(read.begin(), read.end(), 0u) != read.end() && loader.idle()) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    EXPECT_NE(std::find(read.begin(), read.end(), 0u), read.end());
    EXPECT_LE(read.size(), 2u) << "at most the block already being read, then the root";
    std::filesystem::remove(path);
}

TEST(BlockLoader, ABadBlockIsReportedAndTheRestStillLoad) {
    std::string bytes = pyramidBytes();
    const auto good = writeTemp("good.cvox", bytes);
    const voxel::CvoxReader goodReader(good);
    ASSERT_GT(goodReader.blockCount(), 3u);
    // Corrupt the first voxel of block 2: a position bit pattern no block may hold.
    uint64_t offset = 0;
    std::memcpy(&offset, bytes.data() + 96 + 2 * 64 + 24, 8);
    bytes[offset + 3] = char(0xFF);
    const auto path = writeTemp("bad.cvox", bytes);
    const voxel::CvoxReader reader(path);
    lod::BlockLoader loader(reader);
    loader.replaceRequests({1, 2, 3});
    const std::vector<lod::LoadedBlock> got = waitForAll(loader, 3);
    ASSERT_EQ(got.size(), 3u);
    EXPECT_TRUE(got[0].data.has_value());
    EXPECT_FALSE(got[1].data.has_value());
    EXPECT_NE(got[1].error.find(path.string() + ": block 2"), std::string::npos) << got[1].error;
    EXPECT_TRUE(got[2].data.has_value());
    std::filesystem::remove(path);
    std::filesystem::remove(good);
}

}  // namespace
}  // namespace cuberille
