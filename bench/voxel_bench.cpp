// Mesh voxelization against OpenVDB in the same run: cuberille's adaptive octree voxelizer
// (read from a geometry stream, rasterize, merge, emit, write a .cvox) beside OpenVDB's
// meshToLevelSet building a narrow-band level set (half width 3 voxels) of the same mesh at the
// same voxel size. Prints the ratio OpenVDB / cuberille (above 1: cuberille is faster), triangles
// and voxels per second, and each side's peak memory. Each run happens in a forked child, so peak
// resident memory is that run's alone (docs/performance.md).
//
//   voxel_bench [--models bunny,dragon,procedural|FILE] [--resolutions 256,1024] [--threads 1,0]
//               [--procedural-triangles N]

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <tbb/global_control.h>

#include "raster/clock.h"
#include "bench/bench_support.h"
#include "bench/procedural_meshes.h"
#include "raster/parallel.h"
#include "voxel/cvox_file.h"
#include "voxel/geometry_stream.h"
#include "voxel/octree_voxelizer.h"

namespace {

using namespace cuberille;
namespace fs = std::filesystem;

/// What a child reports back through its pipe.
struct RunResult {
    bool ok = false;
    double totalMs = 0, readMs = 0, rasterizeMs = 0, mergeMs = 0, emitMs = 0, writeMs = 0;
    uint64_t voxels = 0;
    double structureMib = 0;  // ours: octrees; OpenVDB: the grid's memUsage
    double peakMib = 0;       // filled in by the parent from the child's rusage
};

/// Runs work() in a child process and returns its result with the child's peak resident memory.
template <class Work>
RunResult inChild(Work&& work) {
    int fds[2];
    if (pipe(fds) != 0) return {};
    const pid_t pid = fork();
    if (pid == 0) {
        close(fds[0]);
        RunResult r = work();
        r.ok = true;
        (void)!write(fds[1], &r, sizeof r);
        _exit(0);
    }
    close(fds[1]);
    RunResult r;
    if (read(fds[0], &r, sizeof r) != ssize_t(sizeof r)) r.ok = false;
    close(fds[0]);
    int status = 0;
    rusage usage{};
    wait4(pid, &status, 0, &usage);
    r.peakMib = double(usage.ru_maxrss) / 1024.0;
    return r;
}

RunResult runOurs(const fs::path& cgs, uint32_t resolution, int threads, const fs::path& out) {
    return inChild([&] {
        raster::ThreadLimit limit(threads);
        const double t0 = raster::nowMs();
        const auto view = voxel::openMeshView(cgs, nullptr);
        voxel::VoxelizeOptions o;
        o.resolution = resolution;
        voxel::VoxelizeStats s;
        const voxel::VoxelModel model = voxel::voxelizeMesh(*view, o, &s);
        const double w0 = raster::nowMs();
        {
            std::ofstream f(out, std::ios::binary);
            voxel::writeCvox(model, f);
        }
        RunResult r;
        r.writeMs = raster::nowMs() - w0;
        r.totalMs = raster::nowMs() - t0;
        r.readMs = s.readMs;
        r.rasterizeMs = s.rasterizeMs;
        r.mergeMs = s.mergeMs;
        r.emitMs = s.emitMs;
        r.voxels = s.voxels;
        r.structureMib = double(s.octreeBytes) / (1 << 20);
        return r;
    });
}

RunResult runOpenVdb(const voxel::MeshView& view, uint32_t resolution, int threads) {
    return inChild([&] {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                                  threads > 0 ? size_t(threads) : size_t(raster::hardwareThreads()));
        openvdb::initialize();
        std::vector<openvdb::Vec3s> points;
        std::vector<openvdb::Vec3I> triangles;
        for (size_t c = 0; c < view.chunkCount(); ++c) {
            const voxel::GeometryChunk chunk = view.readChunk(c);
            const uint32_t base = uint32_t(points.size());
            for (const glm::vec3& p : chunk.positions) points.emplace_back(p.x, p.y, p.z);
            for (size_t t = 0; t < chunk.triangleCount(); ++t)
                triangles.emplace_back(base + chunk.indices[3 * t], base + chunk.indices[3 * t + 1],
                                       base + chunk.indices[3 * t + 2]);
        }
        const voxel::VoxelGrid grid = voxel::gridFor(view, resolution);
        const auto transform = openvdb::math::Transform::createLinearTransform(grid.voxelSize());
        const double t0 = raster::nowMs();
        const openvdb::FloatGrid::Ptr levelSet =
            openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*transform, points, triangles, 3.0f);
        RunResult r;
        r.rasterizeMs = r.totalMs = raster::nowMs() - t0;
        r.voxels = levelSet->activeVoxelCount();
        r.structureMib = double(levelSet->memUsage()) / (1 << 20);
        return r;
    });
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"Voxelization: cuberille's octree voxelizer against OpenVDB's meshToLevelSet"};
    std::string models = "bunny,dragon,procedural", resolutions = "256,1024", threadList = "1,0";
    uint64_t proceduralTriangles = 10'000'000;
    app.add_option("--models", models, "bunny, dragon, horse, procedural, or mesh files")->capture_default_str();
    app.add_option("--resolutions", resolutions, "Grid resolutions (powers of two)")->capture_default_str();
    app.add_option("--threads", threadList, "Thread counts to run (0 = all cores)")->capture_default_str();
    app.add_option("--procedural-triangles", proceduralTriangles, "Triangles of the procedural mesh")
        ->capture_default_str();
    CLI11_PARSE(app, argc, argv);

    const fs::path tmp = fs::temp_directory_path() / ("cuberille_voxel_bench_" + std::to_string(getpid()));
    fs::create_directories(tmp);
    std::printf("# %d hardware threads; times in ms; ratio = OpenVDB / cuberille (above 1: cuberille faster)\n",
                raster::hardwareThreads());
    std::printf("%-11s %9s %5s %3s | %9s %7s %7s %7s %6s %6s %10s %7s %7s %7s | %9s %10s %7s | %6s\n", "model",
                "triangles", "R", "thr", "ours ms", "read", "raster", "merge", "emit", "write", "voxels", "Mtri/s",
                "Mvox/s", "peakMiB", "vdb ms", "vdb voxels", "peakMiB", "ratio");
    for (const std::string& name : bench::splitList(models)) {
        std::unique_ptr<voxel::MeshView> source;
        if (name == "procedural") {
            std::vector<scene::Mesh> meshes;
            meshes.push_back(bench::bumpySphere(proceduralTriangles));
            source = voxel::viewOfMeshes(std::move(meshes), "procedural", false);
        } else {
            const fs::path path = bench::scanPath(name, CUBERILLE_SOURCE_DIR);
            if (!fs::exists(path)) {
                std::printf("%-11s skipped: %s is absent\n", name.c_str(), path.string().c_str());
                continue;
            }
            source = voxel::openMeshView(path, nullptr);
        }
        // Both sides read the same geometry: ours from the packed stream (reading is part of its
        // time), OpenVDB from arrays in memory (its loading is not timed).
        const fs::path cgs = tmp / "model.cgs";
        {
            std::ofstream f(cgs, std::ios::binary);
            voxel::writeGeometryStream(*source, f);
        }
        const auto packed = voxel::openMeshView(cgs, nullptr);
        for (const std::string& rs : bench::splitList(resolutions))
            for (const std::string& ts : bench::splitList(threadList)) {
                const uint32_t r = uint32_t(std::stoul(rs));
                const int threads = std::stoi(ts);
                const RunResult ours = runOurs(cgs, r, threads, tmp / "model.cvox");
                const RunResult vdb = runOpenVdb(*packed, r, threads);
                if (!ours.ok || !vdb.ok) {
                    std::printf("%-11s R %u: a run failed\n", name.c_str(), r);
                    continue;
                }
                const double tris = double(packed->triangleCount());
                std::printf("%-11s %9.0f %5u %3d | %9.1f %7.1f %7.1f %7.1f %6.1f %6.1f %10llu %7.2f %7.2f %7.0f | %9.1f %10llu %7.0f | %6.2f\n",
                            name.c_str(), tris, r, threads == 0 ? raster::hardwareThreads() : threads, ours.totalMs,
                            ours.readMs, ours.rasterizeMs, ours.mergeMs, ours.emitMs, ours.writeMs,
                            (unsigned long long)ours.voxels, tris / ours.totalMs / 1000.0,
                            double(ours.voxels) / ours.totalMs / 1000.0, ours.peakMib, vdb.totalMs,
                            (unsigned long long)vdb.voxels, vdb.peakMib, vdb.totalMs / ours.totalMs);
                std::fflush(stdout);
            }
    }
    fs::remove_all(tmp);
    return 0;
}
