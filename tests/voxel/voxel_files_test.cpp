// Geometry streams, voxel files and the text export: round trips, and every truncation and a
// corruption rejected with an InputError naming the file (never a crash or a wrong answer).

#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <gtest/gtest.h>

#include "scene/input_error.h"
#include "tests/voxel/voxel_test_support.h"
#include "voxel/cvox_file.h"
#include "voxel/geometry_stream.h"
#include "voxel/voxel_export.h"

namespace cuberille {
namespace {

using testing::Triangle;

std::filesystem::path tempPath(const std::string& name) {
    return std::filesystem::path(::testing::TempDir()) / ("cuberille_" + std::to_string(::getpid()) + "_" + name);
}

void writeBytes(const std::filesystem::path& p, const std::string& bytes) {
    std::ofstream(p, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
}

std::vector<Triangle> sphereTriangles() {
    std::mt19937 rng(11);
    return testing::icosphere(3, glm::dvec3(1.0, 2.0, 3.0), 1.5, testing::randomRotation(rng));
}

std::vector<glm::vec3> triangleColors(size_t n) {
    std::vector<glm::vec3> c;
    for (size_t i = 0; i < n; ++i) c.push_back(glm::vec3(float(i % 5) / 4.0f, float(i % 3) / 2.0f, 0.25f));
    return c;
}

std::string packToBytes(const voxel::MeshView& view) {
    std::ostringstream out;
    voxel::writeGeometryStream(view, out);
    return out.str();
}

TEST(GeometryStream, RoundTripsChunks) {
    const auto tris = sphereTriangles();
    const auto view = testing::viewOf(tris, 100, triangleColors(tris.size()));
    const std::filesystem::path path = tempPath("round.cgs");
    writeBytes(path, packToBytes(*view));
    const auto read = voxel::openMeshView(path, nullptr);
    ASSERT_EQ(read->chunkCount(), view->chunkCount());
    EXPECT_EQ(read->triangleCount(), tris.size());
    for (size_t i = 0; i < view->chunkCount(); ++i) {
        const voxel::GeometryChunk a = view->readChunk(i), b = read->readChunk(i);
        EXPECT_EQ(a.positions, b.positions) << "chunk " << i;  // float32, exact
        EXPECT_EQ(a.indices, b.indices) << "chunk " << i;
        ASSERT_EQ(b.normals.size(), a.normals.size());
        ASSERT_EQ(b.colors.size(), a.colors.size());
        for (size_t v = 0; v < a.normals.size(); ++v) {
            EXPECT_LT(glm::length(a.normals[v] - b.normals[v]), 3.0f / 511.0f);  // 10-bit normals
            EXPECT_LT(glm::length(a.colors[v] - b.colors[v]), 0.01f);            // 8-bit sRGB
        }
        EXPECT_EQ(read->chunkInfo(i).boundsMin, view->chunkInfo(i).boundsMin);
        EXPECT_EQ(read->chunkInfo(i).boundsMax, view->chunkInfo(i).boundsMax);
    }
    std::filesystem::remove(path);
}

TEST(GeometryStream, VoxelizesLikeItsSource) {
    const auto tris = sphereTriangles();
    const auto view = testing::viewOf(tris, 64);
    const std::filesystem::path path = tempPath("vox.cgs");
    writeBytes(path, packToBytes(*view));
    const auto read = voxel::openMeshView(path, nullptr);
    voxel::VoxelizeOptions o;
    o.resolution = 64;
    EXPECT_EQ(testing::voxelSet(voxel::voxelizeMesh(*view, o)), testing::voxelSet(voxel::voxelizeMesh(*read, o)));
    std::filesystem::remove(path);
}

TEST(GeometryStream, EveryTruncationIsRejected) {
    const auto tris = sphereTriangles();
    const std::string bytes = packToBytes(*testing::viewOf(std::vector<Triangle>(tris.begin(), tris.begin() + 40), 16));
    const std::filesystem::path path = tempPath("trunc.cgs");
    for (size_t n = 0; n < bytes.size(); ++n) {
        writeBytes(path, bytes.substr(0, n));
        try {
            const auto view = voxel::openMeshView(path, nullptr);
            for (size_t i = 0; i < view->chunkCount(); ++i) view->readChunk(i);
            ADD_FAILURE() << "a stream cut to " << n << " of " << bytes.size() << " bytes was accepted";
        } catch (const scene::InputError& e) {
            EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
        }
    }
    std::filesystem::remove(path);
}

TEST(GeometryStream, CorruptedPayloadFailsItsChecksum) {
    const auto tris = sphereTriangles();
    std::string bytes = packToBytes(*testing::viewOf(tris, 1000));
    bytes[bytes.size() - 40] ^= 0x5A;  // inside the last chunk's compressed data
    const std::filesystem::path path = tempPath("corrupt.cgs");
    writeBytes(path, bytes);
    const auto view = voxel::openMeshView(path, nullptr);
    EXPECT_THROW(
        {
            for (size_t i = 0; i < view->chunkCount(); ++i) view->readChunk(i);
        },
        scene::InputError);
    std::filesystem::remove(path);
}

voxel::VoxelModel sphereModel() {
    const auto tris = sphereTriangles();
    const auto view = testing::viewOf(tris, 100, triangleColors(tris.size()));
    voxel::VoxelizeOptions o;
    o.resolution = 128;  // several 64³ blocks
    return voxel::voxelizeMesh(*view, o);
}

TEST(VoxelFile, RoundTripsTheModel) {
    const voxel::VoxelModel m = sphereModel();
    ASSERT_GT(m.blocks.size(), 1u);
    const std::filesystem::path path = tempPath("model.cvox");
    std::ostringstream out;
    voxel::writeCvox(m, out);
    writeBytes(path, out.str());
    const voxel::VoxelModel r = voxel::readCvox(path);
    EXPECT_EQ(r.grid.resolution, m.grid.resolution);
    EXPECT_EQ(r.grid.origin, m.grid.origin);
    EXPECT_EQ(r.grid.extent, m.grid.extent);
    EXPECT_EQ(r.hasColors, m.hasColors);
    ASSERT_EQ(r.blocks.size(), m.blocks.size());
    for (size_t i = 0; i < m.blocks.size(); ++i) {
        EXPECT_EQ(r.blocks[i].coord, m.blocks[i].coord);
        EXPECT_EQ(r.blocks[i].voxels, m.blocks[i].voxels);
        EXPECT_EQ(r.blocks[i].normals, m.blocks[i].normals);
        EXPECT_EQ(r.blocks[i].colors, m.blocks[i].colors);
        EXPECT_EQ(r.blocks[i].tightMin, m.blocks[i].tightMin);
        EXPECT_EQ(r.blocks[i].tightMax, m.blocks[i].tightMax);
        ASSERT_EQ(r.blocks[i].triangles.size(), m.blocks[i].triangles.size());
        EXPECT_EQ(0, std::memcmp(r.blocks[i].triangles.data(), m.blocks[i].triangles.data(),
                                 m.blocks[i].triangles.size() * sizeof(voxel::SourceTriangle)));
    }
    std::filesystem::remove(path);
}

TEST(VoxelFile, EveryTruncationIsRejected) {
    // A small model, so that every length can be tried.
    const auto view = testing::viewOf({{{{1, 1, 1}, {3, 1, 2}, {1, 3, 3}}}});
    const voxel::VoxelModel m = testing::voxelizeInGrid(*view, 4, voxel::Separability::Conservative);
    std::ostringstream out;
    voxel::writeCvox(m, out);
    const std::string bytes = out.str();
    const std::filesystem::path path = tempPath("trunc.cvox");
    for (size_t n = 0; n < bytes.size(); ++n) {
        writeBytes(path, bytes.substr(0, n));
        EXPECT_THROW(voxel::readCvox(path), scene::InputError) << "cut to " << n << " of " << bytes.size();
    }
    std::filesystem::remove(path);
}

TEST(VoxelFile, ALevelCountTheGridCannotHaveIsRejected) {
    // A 128-voxel grid of 64-voxel blocks has two levels at most; a block claiming level 40
    // under a header claiming 41 once shifted the resolution by 40 bits (found by fuzz_cvox_blocks).
    std::ostringstream out;
    voxel::writeCvox(sphereModel(), out);
    std::string bytes = out.str();
    const std::filesystem::path path = tempPath("levels.cvox");
    for (const uint32_t levels : {3u, 41u, 0xFFFFFFFFu}) {
        std::memcpy(bytes.data() + 16, &levels, 4);  // the header's level count
        std::memcpy(bytes.data() + 96, &levels, 4);  // block 0's level (checked against it)
        writeBytes(path, bytes);
        try {
            voxel::readCvox(path);
            ADD_FAILURE() << levels << " levels accepted";
        } catch (const scene::InputError& e) {
            EXPECT_NE(std::string(e.what()).find("level count"), std::string::npos) << e.what();
        }
    }
    std::filesystem::remove(path);
}

TEST(VoxelExport, RoundTrips) {
    const voxel::VoxelModel m = sphereModel();
    const std::filesystem::path path = tempPath("voxels.txt");
    {
        std::ofstream out(path);
        voxel::writeVoxelExport(m, out);
    }
    const voxel::VoxelExport e = voxel::readVoxelExport(path);
    EXPECT_EQ(e.grid.resolution, m.grid.resolution);
    EXPECT_EQ(e.grid.origin, m.grid.origin);  // printed with 17 digits: the same doubles
    EXPECT_EQ(e.grid.extent, m.grid.extent);
    std::set<testing::VoxelKey> read;
    for (const glm::uvec3& p : e.voxels) read.insert({p.x, p.y, p.z});
    EXPECT_EQ(read.size(), e.voxels.size());
    EXPECT_EQ(read, testing::voxelSet(m));
    std::filesystem::remove(path);
}

}  // namespace
}  // namespace cuberille
