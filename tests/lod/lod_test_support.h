#pragma once
// Shared by the streaming tests: a voxelized sphere with its LOD pyramid, as a model and as
// .cvox bytes in a temporary file.

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <unistd.h>

#include "lod/lod_pyramid.h"
#include "tests/voxel/voxel_test_support.h"
#include "voxel/cvox_file.h"

namespace cuberille::testing {

/// A sphere of radius 2 about the origin (rotated by `seed`), voxelized with every LOD level.
inline voxel::VoxelModel spherePyramid(uint32_t resolution, unsigned seed) {
    std::mt19937 rng(seed);
    const auto tris = icosphere(4, glm::dvec3(0.0), 2.0, randomRotation(rng));
    voxel::VoxelizeOptions o;
    o.resolution = resolution;
    voxel::VoxelModel m = voxel::voxelizeMesh(*viewOf(tris, 1000), o);
    lod::buildLodPyramid(m, {});
    return m;
}

inline std::string cvoxBytes(const voxel::VoxelModel& m) {
    std::ostringstream out;
    voxel::writeCvox(m, out);
    return out.str();
}

/// The bytes as a file in the test temporary folder, named for this process.
inline std::filesystem::path writeTemp(const std::string& name, const std::string& bytes) {
    const auto path = std::filesystem::path(::testing::TempDir()) / ("cuberille_" + std::to_string(::getpid()) + name);
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
}

}  // namespace cuberille::testing
