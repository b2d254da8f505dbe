#pragma once
// `cuberille pack`, `cuberille voxelize` and `cuberille isosurface`: meshes to geometry streams,
// meshes to voxel models, volumes to voxel models. Library entry points, so tests and benchmarks
// run the tool's own path.

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "lod/lod_pyramid.h"
#include "voxel/geometry_stream.h"
#include "voxel/isosurface.h"
#include "voxel/octree_voxelizer.h"

namespace CLI {
class App;
}

namespace cuberille::apps {

struct PackOptions {
    std::filesystem::path input, out;
    uint32_t chunkTriangles = voxel::kDefaultChunkTriangles;
    std::filesystem::path statsPath;
    bool quiet = false;
};

struct VoxelizeCommandOptions {
    std::filesystem::path input, out;
    uint32_t resolution = 256;
    std::string separability = "conservative";  // conservative, 26 or 6
    std::filesystem::path exportVoxels;
    bool noSourceTriangles = false;
    uint32_t levels = 0;               // LOD levels to write; 0: down to a single block
    std::string simplify = "parallel";  // parallel or serial (identical output)
    int threads = 0;
    std::filesystem::path statsPath;
    bool quiet = false;
};

struct IsosurfaceCommandOptions {
    std::filesystem::path volume, out;
    std::array<uint32_t, 3> dims{0, 0, 0};
    std::string type = "u8";  // u8, u16 or f32
    double iso = 0.5;
    std::string normals = "regression";  // regression or central
    uint32_t levels = 0;
    std::filesystem::path exportVoxels;
    int threads = 0;
    std::filesystem::path statsPath;
    bool quiet = false;
};

struct InfoOptions {
    std::filesystem::path file;
};

/// Each returns the exit code; bad input throws scene::InputError (exit 2), failures while
/// working std::runtime_error (exit 1).
int runPackCommand(const PackOptions& options);
int runVoxelizeCommand(const VoxelizeCommandOptions& options);

/// `voxelize` taken apart (python/cuberille/dask), so that no process holds the finest level
/// whole (lod/pyramid_ranges.h):
///   voxelizeChunkCount   the input's chunks;
///   voxelizeChunkRun     one run of chunks voxelized into a partial voxelization file
///                        (voxel/partial_voxelization_file.h, written atomically);
///   planVoxelizeRanges   the ranges of blocks to merge, from the parts' block indexes (checks
///                        that the parts hold each chunk once); the plan as JSON;
///   voxelizeRange        one range's blocks merged from every part (the single-machine blocks
///                        bit for bit), its pyramid up to the plan's split level, into a range file
///                        (written atomically); what it counted, as JSON;
///   finishVoxelizeFromRanges  the command's last steps from the range files, in the plan's
///                        order: the levels above the split, the .cvox and --export-voxels
///                        (`cuberille voxelize`'s bytes), the summary and --stats.
/// Each checks the options as the command does and throws scene::InputError with its messages.
size_t voxelizeChunkCount(const VoxelizeCommandOptions& options);
void voxelizeChunkRun(const VoxelizeCommandOptions& options, size_t firstChunk, size_t chunkCount,
                      const std::filesystem::path& part);
std::string planVoxelizeRanges(const VoxelizeCommandOptions& options, const std::vector<std::filesystem::path>& parts,
                               size_t wantedRanges);
std::string voxelizeRange(const VoxelizeCommandOptions& options, const std::vector<std::filesystem::path>& parts,
                          const std::string& plan, size_t range, const std::filesystem::path& rangeFile);
int finishVoxelizeFromRanges(const VoxelizeCommandOptions& options, const std::vector<std::filesystem::path>& parts,
                             const std::string& plan,
                             const std::vector<std::filesystem::path>& rangeFiles, const std::vector<std::string>& rangeResults);

/// Adds the `voxelize` subcommand, whose options fill `o`.
CLI::App* addVoxelizeCommand(CLI::App& app, VoxelizeCommandOptions& o);
/// `voxelize`'s arguments (the mesh and options, without "voxelize") read by its own parser.
VoxelizeCommandOptions parseVoxelizeArguments(const std::vector<std::string>& arguments);
int runIsosurfaceCommand(const IsosurfaceCommandOptions& options);
/// `cuberille info FILE`: what a .cgs or .cvox holds (reading and checking all of it).
int runInfoCommand(const InfoOptions& options);

voxel::Separability parseSeparability(const std::string& name);  // throws scene::InputError

}  // namespace cuberille::apps
