// Voxel LOD rendering against drawing every source triangle, in the same run: the same model,
// camera and lighting, drawn (a) as voxel blocks selected by LOD, frustum and occlusion culling
// (converged over warm-up frames) through cuberille's pipeline, (b) as all its source triangles
// through the same pipeline, and (c) as the same triangles through Mesa's llvmpipe. Prints frame
// times (median of --frames warm frames, clear to resolved image), the ratios, blocks and faces
// drawn, and the voxel image's error against (b): RMSE of the 8-bit sRGB values and the share of
// pixels off by more than one level. The aim (Chajdas 2015, chapter 4): frame time that follows
// the pixels, not the triangle count.
//
//   lod_bench [--models bunny,dragon,1m,10m] [--resolution 1024] [--msaa 1,4] [--frames 5]
//             [--pixel-error 1]

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "raster/clock.h"
#include "bench/bench_support.h"
#include "bench/llvmpipe_peer.h"
#include "bench/procedural_meshes.h"
#include "lod/lod_pyramid.h"
#include "lod/voxel_scene.h"
#include "raster/parallel.h"
#include "raster/resolve.h"
#include "raster/srgb.h"
#include "voxel/mesh_view.h"
#include "voxel/octree_voxelizer.h"

namespace {

using namespace cuberille;
namespace fs = std::filesystem;

/// The model's meshes, or empty when its file is absent.
std::vector<scene::Mesh> loadModel(const std::string& name) {
    std::vector<scene::Mesh> meshes;
    if (name == "1m" || name == "10m" || name == "100m") {
        meshes.push_back(bench::bumpySphere(name == "1m" ? 1'000'000ull : name == "10m" ? 10'000'000ull : 100'000'000ull));
        return meshes;
    }
    const fs::path path = bench::scanPath(name, CUBERILLE_SOURCE_DIR);
    if (!fs::exists(path)) return meshes;
    const auto view = voxel::openMeshView(path, nullptr, 1u << 30);  // one chunk per mesh
    for (size_t i = 0; i < view->chunkCount(); ++i) {
        const voxel::GeometryChunk c = view->readChunk(i);
        scene::Mesh m;
        m.positions = c.positions;
        m.normals = c.normals;
        m.indices = c.indices;
        meshes.push_back(std::move(m));
    }
    return meshes;
}

struct Frame {
    double ms = 0;
    raster::Image image;
};

template <class Submit>
Frame timedFrames(int width, int height, int msaa, glm::vec4 background, int frames, Submit&& submit) {
    std::vector<double> times;
    Frame f;
    for (int i = 0; i < frames; ++i) {
        raster::Pipeline p;
        raster::FramebufferDesc d;
        d.widthPixels = width, d.heightPixels = height, d.samples = msaa, d.clearColor = background;
        const double t0 = raster::nowMs();
        p.beginFrame(d);
        submit(p);
        p.endFrame();
        raster::resolveColor(p.framebuffer(), f.image);
        times.push_back(raster::nowMs() - t0);
        submit.after(p);
    }
    f.ms = bench::median(times);
    return f;
}

/// RMSE of the 8-bit sRGB channels (in levels) and the share of pixels with a channel off by more
/// than one level. Issue 25 states its quality aim as PSNR, 20 log10(255 / RMSE), printed beside.
void imageError(const raster::Image& a, const raster::Image& b, double& rmse, double& share) {
    double sum = 0;
    size_t off = 0, n = size_t(a.width) * a.height;
    for (size_t i = 0; i < n; ++i) {
        bool far = false;
        for (int c = 0; c < 3; ++c) {
            const int d = int(raster::encodeSrgb8(a.rgba[i * 4 + c])) - int(raster::encodeSrgb8(b.rgba[i * 4 + c]));
            sum += double(d) * d;
            far |= std::abs(d) > 1;
        }
        off += far;
    }
    rmse = std::sqrt(sum / double(n * 3));
    share = double(off) / double(n);
}

uint64_t modelBytes(const voxel::VoxelModel& m) {
    uint64_t b = 0;
    for (const voxel::VoxelBlock& k : m.blocks) b += k.voxels.size() * 12 + k.triangles.size() * sizeof(voxel::SourceTriangle);
    return b;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"Voxel LOD rendering against drawing every source triangle (cuberille and llvmpipe)"};
    std::string models = "bunny,dragon,1m,10m", msaaList = "1,4";
    uint32_t resolution = 1024;
    int frames = 5, width = 1280, height = 720;
    float pixelError = 1.0f;
    std::string separability = "conservative";
    app.add_option("--separability", separability, "Voxelization: conservative, 26 or 6")->capture_default_str();
    app.add_option("--models", models, "bunny, dragon, horse, 1m, 10m, 100m (bumpy spheres), or mesh files")
        ->capture_default_str();
    app.add_option("--resolution", resolution, "Voxelization resolution")->capture_default_str();
    app.add_option("--msaa", msaaList, "Sample counts")->capture_default_str();
    app.add_option("--frames", frames, "Timed frames (median)")->capture_default_str();
    app.add_option("--pixel-error", pixelError, "LOD pixel error")->capture_default_str();
    CLI11_PARSE(app, argc, argv);
    setenv("LP_NUM_THREADS", std::to_string(raster::hardwareThreads()).c_str(), 1);

    std::printf("# %d threads, %dx%d, voxels at %u^3 (%s), pixel error %g; times in ms (median of %d warm frames)\n",
                raster::hardwareThreads(), width, height, resolution, separability.c_str(), pixelError, frames);
    std::printf("%-7s %10s %4s | %9s %7s %6s %9s %7s %9s | %9s %9s | %7s %7s | %6s %7s %7s\n", "model", "triangles", "spp",
                "voxel ms", "blocks", "occl", "faces", "hybrid", "voxMiB", "tris ms", "llvm ms", "tri/vox", "llvm/vox",
                "RMSE", "off>1", "PSNR dB");
    for (const std::string& name : bench::splitList(models)) {
        std::vector<scene::Mesh> meshes = loadModel(name);
        if (meshes.empty()) {
            std::printf("%-7s skipped: not found\n", name.c_str());
            continue;
        }
        uint64_t triangles = 0;
        for (const scene::Mesh& m : meshes) triangles += m.triangleCount();
        // Voxelize and simplify (not timed here: voxel_bench measures it).
        voxel::VoxelizeOptions vo;
        vo.resolution = resolution;
        vo.separability = separability == "6"    ? voxel::Separability::Six
                          : separability == "26" ? voxel::Separability::TwentySix
                                                 : voxel::Separability::Conservative;
        std::vector<scene::Mesh> copy = meshes;
        voxel::VoxelModel model = voxel::voxelizeMesh(*voxel::viewOfMeshes(std::move(copy), name, false), vo);
        lod::buildLodPyramid(model, {});
        const double voxelMib = double(modelBytes(model)) / (1 << 20);
        lod::VoxelScene voxels(std::move(model), 30.0f, 20.0f);
        // The same view and light for the triangles.
        scene::Scene tris;
        tris.meshes = std::move(meshes);
        tris.camera = voxels.camera;
        tris.lighting = voxels.lighting;
        tris.background = voxels.background;
        tris.cull = raster::CullMode::None;
        for (const std::string& ms : bench::splitList(msaaList)) {
            const int msaa = std::stoi(ms);
            lod::VoxelRenderOptions ro;
            ro.selection.pixelError = pixelError;
            lod::VoxelFrameStats stats;
            struct VoxelSubmit {
                lod::VoxelScene& s;
                const lod::VoxelRenderOptions& o;
                lod::VoxelFrameStats& stats;
                int w, h;
                void operator()(raster::Pipeline& p) { stats = s.draw(p, w, h, o); }
                void after(raster::Pipeline& p) { s.readOcclusion(p.stats()); }
            } vsub{voxels, ro, stats, width, height};
            timedFrames(width, height, msaa, voxels.background, 3, vsub);  // occlusion converges
            const Frame v = timedFrames(width, height, msaa, voxels.background, frames, vsub);
            struct TriSubmit {
                const scene::Scene& s;
                float aspect;
                void operator()(raster::Pipeline& p) { s.draw(p, aspect); }
                void after(raster::Pipeline&) {}
            } tsub{tris, float(width) / float(height)};
            const Frame t = timedFrames(width, height, msaa, tris.background, frames, tsub);
            double llvm = 0;
            if (bench::LlvmpipePeer::available()) {
                bench::LlvmpipePeer peer(width, height, msaa);
                peer.upload(tris);
                peer.renderFrame(tris);
                std::vector<double> times;
                for (int i = 0; i < frames; ++i) times.push_back(peer.renderFrame(tris));
                llvm = bench::median(times);
            }
            double rmse = 0, share = 0;
            imageError(v.image, t.image, rmse, share);
            const double psnr = rmse > 0.0 ? 20.0 * std::log10(255.0 / rmse) : std::numeric_limits<double>::infinity();
            std::printf("%-7s %10llu %4d | %9.1f %7llu %6llu %9llu %7llu %9.1f | %9.1f %9.1f | %7.2f %7.2f | %6.2f %6.2f%% %7.1f\n",
                        name.c_str(), (unsigned long long)triangles, msaa, v.ms,
                        (unsigned long long)stats.voxelBlocksDrawn, (unsigned long long)stats.occlusionCulled,
                        (unsigned long long)stats.facesEmitted, (unsigned long long)stats.hybridTriangles, voxelMib,
                        t.ms, llvm, t.ms / v.ms, llvm > 0 ? llvm / v.ms : 0.0, rmse, 100.0 * share, psnr);
            std::fflush(stdout);
        }
    }
    return 0;
}
