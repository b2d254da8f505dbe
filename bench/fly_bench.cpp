// Streaming under a memory budget (Chajdas 2015, sections 4.4, 4.6 and 4.8): flights through a
// voxel model far larger than the budgets, run through the tool's own path (apps::runFly), along
// the orbit and zoom paths, for each budget and upload limit. Prints time to first image, frame
// times and MiB read per frame. Side by side in the same run, the peers that must hold the
// whole model before drawing anything: cuberille with the whole .cvox read into memory, and
// (--llvmpipe) Mesa's llvmpipe drawing every source triangle from memory.
//
//   fly_bench [--model FILE.cvox] [--triangles 100000000] [--resolution 1024] [--frames 60]
//             [--budgets 64,256,1024] [--upload-limits 1,4] [--paths orbit,zoom] [--llvmpipe]
//
// The model is made when FILE is absent: a bumpy sphere of --triangles triangles, voxelized at
// --resolution with every LOD level and the source triangles kept (hybrid rendering).

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "apps/fly_command.h"
#include "bench/bench_support.h"
#include "bench/procedural_meshes.h"
#include "lod/lod_pyramid.h"
#include "lod/voxel_scene.h"
#include "raster/clock.h"
#include "raster/parallel.h"
#include "raster/pipeline.h"
#include "voxel/cvox_file.h"
#include "voxel/mesh_view.h"
#include "voxel/octree_voxelizer.h"
#ifdef CUBERILLE_HAVE_LLVMPIPE
#include "bench/llvmpipe_peer.h"
#endif

namespace {

using namespace cuberille;
namespace fs = std::filesystem;
constexpr double kMib = 1024.0 * 1024.0;

void makeModel(const fs::path& path, uint64_t triangles, uint32_t resolution) {
    const double t0 = raster::nowMs();
    std::vector<scene::Mesh> meshes{bench::bumpySphere(triangles)};
    voxel::VoxelizeOptions vo;
    vo.resolution = resolution;
    voxel::VoxelModel model = voxel::voxelizeMesh(*voxel::viewOfMeshes(std::move(meshes), "bumpy sphere", false), vo);
    lod::buildLodPyramid(model, {});
    const fs::path temp = path.string() + ".partial";
    {
        std::ofstream out(temp, std::ios::binary);
        voxel::writeCvox(model, out);
    }
    fs::rename(temp, path);
    std::printf("# made %s: %llu triangles at %u^3, %zu blocks, %.1f GiB, %.0f s\n", path.c_str(),
                (unsigned long long)triangles, resolution, model.blocks.size(), double(fs::file_size(path)) / (kMib * 1024),
                (raster::nowMs() - t0) / 1000.0);
}

/// The peer without streaming: the whole file read into memory before the first frame.
void allResident(const fs::path& path, int width, int height, int msaa, float pixelError) {
    const double t0 = raster::nowMs();
    lod::VoxelScene scene(voxel::readCvox(path), 30.0f, 20.0f);
    const double readMs = raster::nowMs() - t0;
    lod::VoxelRenderOptions ro;
    ro.selection.pixelError = pixelError;
    raster::FramebufferDesc fb;
    fb.widthPixels = width, fb.heightPixels = height, fb.samples = msaa;
    raster::Pipeline p;
    std::vector<double> frames;
    for (int i = 0; i < 4; ++i) {
        const double f0 = raster::nowMs();
        p.beginFrame(fb);
        scene.draw(p, width, height, ro);
        p.endFrame();
        scene.readOcclusion(p.stats());
        frames.push_back(raster::nowMs() - f0);
    }
    std::printf("%-6s %7s %7s | %9.1f %9.1f %9s %9s | %10s %9s | %6s %9s   (read and index the whole file: %.1f ms)\n",
                "all", "-", "-", readMs + frames[0], bench::median({frames.begin() + 1, frames.end()}), "-", "-",
                "all", "-", "-", "-", readMs);
}

#ifdef CUBERILLE_HAVE_LLVMPIPE
void llvmpipeFirstImage(uint64_t triangles, int width, int height, int msaa) {
    scene::Scene s;
    s.meshes.push_back(bench::bumpySphere(triangles));
    glm::vec3 lo(1e30f), hi(-1e30f);
    for (const glm::vec3& p : s.meshes[0].positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
    s.camera = scene::frameBounds(lo, hi, 30.0f, 20.0f);
    s.cull = raster::CullMode::None;
    bench::LlvmpipePeer peer(width, height, msaa);
    const double t0 = raster::nowMs();
    peer.upload(s);
    const double first = peer.renderFrame(s);
    const double total = raster::nowMs() - t0;
    std::vector<double> frames;
    for (int i = 0; i < 3; ++i) frames.push_back(peer.renderFrame(s));
    std::printf("%-6s %7s %7s | %9.1f %9.1f %9s %9s | %10s %9s | %6s %9s   (llvmpipe, triangles already in memory; "
                "upload %.1f ms, first frame %.1f ms)\n",
                "llvm", "-", "-", total, bench::median(frames), "-", "-", "all", "-", "-", "-", total - first, first);
}
#endif

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"Flights through a streamed voxel model under memory budgets, beside all-resident peers"};
    std::string model = (fs::temp_directory_path() / "cuberille_fly_bench.cvox").string();
    uint64_t triangles = 100'000'000;
    uint32_t resolution = 1024;
    int frames = 60, width = 1280, height = 720, msaa = 1;
    float pixelError = 2.0f;
    std::string budgets = "64,256,1024", uploadLimits = "1,4", paths = "orbit,zoom";
    bool llvmpipe = false;
    app.add_option("--model", model, "The .cvox to fly through (made when absent)")->capture_default_str();
    app.add_option("--triangles", triangles, "Triangles of the bumpy sphere made when the model is absent")
        ->capture_default_str();
    app.add_option("--resolution", resolution, "Its voxel resolution")->capture_default_str();
    app.add_option("--frames", frames, "Frames per path")->capture_default_str();
    app.add_option("--msaa", msaa, "Samples per pixel")->capture_default_str();
    app.add_option("--pixel-error", pixelError, "LOD pixel error")->capture_default_str();
    app.add_option("--budgets", budgets, "Budgets in MiB")->capture_default_str();
    app.add_option("--upload-limits", uploadLimits, "Upload limits in MiB per frame")->capture_default_str();
    app.add_option("--paths", paths, "Camera paths")->capture_default_str();
    app.add_flag("--llvmpipe", llvmpipe, "Also time llvmpipe drawing the source triangles (regenerates them)");
    CLI11_PARSE(app, argc, argv);
    setenv("LP_NUM_THREADS", std::to_string(raster::hardwareThreads()).c_str(), 1);

    if (!fs::exists(model)) makeModel(model, triangles, resolution);
    const voxel::CvoxReader reader(model);
    std::printf("# %s: %.2f GiB, %zu blocks, %llu triangles kept; %d threads, %dx%d, %d spp, pixel error %g, %d "
                "frames a path; time to first image and frame times in ms\n",
                model.c_str(), double(fs::file_size(model)) / (kMib * 1024), reader.blockCount(),
                (unsigned long long)reader.layout().triangleCount(), raster::hardwareThreads(), width, height, msaa,
                pixelError, frames);
    std::printf("%-6s %7s %7s | %9s %9s %9s %9s | %10s %9s | %6s %9s\n", "path", "budget", "upload", "first ms",
                "median ms", "p95 ms", "max ms", "MiB read", "MiB/frame", "settle", "peak MiB");
    for (const std::string& path : bench::splitList(paths))
        for (const std::string& budget : bench::splitList(budgets))
            for (const std::string& limit : bench::splitList(uploadLimits)) {
                apps::FlyOptions o;
                o.model = model;
                o.path = path;
                o.frames = frames;
                o.width = width, o.height = height, o.msaa = msaa;
                o.pixelError = pixelError;
                o.budgetMib = std::stod(budget);
                o.uploadLimitMib = std::stod(limit);
                o.quiet = true;
                const apps::FlyResult r = apps::runFly(o);
                std::vector<double> times;
                double pathReadMib = 0;
                for (int i = 0; i < r.pathFrames; ++i) {
                    times.push_back(r.frames[size_t(i)].frameMs);
                    pathReadMib += double(r.frames[size_t(i)].streaming.loadedBytes) / kMib;
                }
                std::sort(times.begin(), times.end());
                std::printf("%-6s %7s %7s | %9.1f %9.1f %9.1f %9.1f | %10.1f %9.2f | %6zu %9.1f\n", path.c_str(),
                            budget.c_str(), limit.c_str(), r.timeToFirstImageMs, bench::median(times),
                            times[times.size() * 95 / 100], times.back(), double(r.bytesReadFromDisk) / kMib,
                            pathReadMib / r.pathFrames, r.frames.size() - size_t(r.pathFrames),
                            double(r.peakHeldBytes) / kMib);
                std::fflush(stdout);
            }
    allResident(model, width, height, msaa, pixelError);
#ifdef CUBERILLE_HAVE_LLVMPIPE
    if (llvmpipe && bench::LlvmpipePeer::available()) llvmpipeFirstImage(triangles, width, height, msaa);
#else
    if (llvmpipe) std::printf("# llvmpipe: not built (OSMesa not found)\n");
#endif
    return 0;
}
