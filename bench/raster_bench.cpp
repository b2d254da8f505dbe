// Frame time of the software pipeline against Mesa's llvmpipe (OSMesa) on the same scenes, in
// the same run, at equal settings: same triangles, same per-pixel Lambert shading, same
// resolution and sample count, back-face culling and a depth test. Prints the ratio
// llvmpipe / cuberille (above 1: cuberille is faster). Absolute times on shared machines are
// noise; the ratio is the figure (docs/performance.md).
//
//   raster_bench [--threads N] [--frames N] [--width W] [--height H] [--scenes a,b] [--msaa 1,4]
//
// Both renderers are timed warm (--warmup frames are drawn and discarded), as the median of
// --frames frames, from clear to a resolved image in memory (no file I/O, no readback).

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <malloc.h>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "bench/llvmpipe_peer.h"
#include "raster/parallel.h"
#include "raster/pipeline.h"
#include "raster/resolve.h"
#include "scene/procedural.h"

namespace {

using namespace cuberille;

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

struct OurFrame {
    double totalMs;
    raster::StageTimes stages;
};

OurFrame renderOurs(raster::Pipeline& p, const scene::Scene& s, int w, int h, int msaa,
                    raster::Image& image) {
    const auto t0 = std::chrono::steady_clock::now();
    raster::FramebufferDesc d;
    d.widthPixels = w, d.heightPixels = h, d.samples = msaa, d.clearColor = s.background;
    p.beginFrame(d);
    s.draw(p, float(w) / h);
    p.endFrame();
    const auto t1 = std::chrono::steady_clock::now();
    raster::resolveColor(p.framebuffer(), image);
    const auto t2 = std::chrono::steady_clock::now();
    OurFrame f{std::chrono::duration<double, std::milli>(t2 - t0).count(), p.stats().times};
    f.stages.resolveMs = std::chrono::duration<double, std::milli>(t2 - t1).count();
    return f;
}

std::vector<std::string> split(const std::string& s) {
    std::vector<std::string> out;
    std::stringstream in(s);
    for (std::string item; std::getline(in, item, ',');) out.push_back(item);
    return out;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"Frame time against llvmpipe, side by side"};
    int threads = 0, frames = 7, warmup = 3, width = 1920, height = 1080;
    bool verbose = false, noPeer = false;
    std::string scenes = "field,subpixel,fill", msaaList = "1,4";
    app.add_option("--threads", threads, "Threads for both renderers (0 = all cores)");
    app.add_option("--frames", frames, "Timed frames per measurement (median reported)");
    app.add_option("--warmup", warmup, "Untimed frames first, for each renderer");
    app.add_flag("--verbose", verbose, "Print every frame time");
    app.add_flag("--no-peer", noPeer, "Time Cuberille alone (for profiling); no ratio");
    app.add_option("--width", width);
    app.add_option("--height", height);
    app.add_option("--scenes", scenes, "Comma-separated built-in scenes");
    app.add_option("--msaa", msaaList, "Comma-separated sample counts");
    CLI11_PARSE(app, argc, argv);

    const int effectiveThreads = threads > 0 ? threads : raster::hardwareThreads();
    // llvmpipe reads its thread count once, when the first context is created.
    setenv("LP_NUM_THREADS", std::to_string(effectiveThreads).c_str(), 1);
    raster::ThreadLimit limit(threads);
    // llvmpipe allocates its per-frame bins afresh every frame. Until a large block has been
    // freed in the process, glibc serves such allocations with new mmaps, and every frame then
    // pays its page faults (up to 3x slower frames on Mesa 22.3.6 here, depending only on what
    // the process did before). A fixed, high threshold gives the peer its best case in every
    // order; Cuberille reuses its buffers across frames and is unaffected.
    mallopt(M_MMAP_THRESHOLD, 256 << 20);
    mallopt(M_TRIM_THRESHOLD, 512 << 20);

    std::printf("# %dx%d, %d thread%s, median of %d warm frames\n", width, height,
                effectiveThreads, effectiveThreads > 1 ? "s" : "", frames);
    std::printf("%-9s %4s %10s | %8s %8s %8s %8s %10s | %10s | %7s\n", "scene", "msaa", "triangles",
                "vertex", "front", "back", "resolve", "cuberille", "llvmpipe", "ratio");
    for (const std::string& name : split(scenes)) {
        const scene::Scene s = scene::makeProceduralScene(name);
        for (const std::string& m : split(msaaList)) {
            const int msaa = std::stoi(m);
            raster::Pipeline pipeline;
            raster::Image image;
            for (int i = 0; i < warmup; ++i) renderOurs(pipeline, s, width, height, msaa, image);
            std::vector<double> ours;
            std::vector<OurFrame> frameLog;
            for (int i = 0; i < frames; ++i) {
                frameLog.push_back(renderOurs(pipeline, s, width, height, msaa, image));
                ours.push_back(frameLog.back().totalMs);
            }
            const double ourMedian = median(ours);
            const OurFrame& typical = *std::min_element(frameLog.begin(), frameLog.end(), [&](auto& a, auto& b) {
                return std::abs(a.totalMs - ourMedian) < std::abs(b.totalMs - ourMedian);
            });

            std::vector<double> theirs;
            if (noPeer) {
                theirs.push_back(0.0);
            } else {
                bench::LlvmpipePeer peer(width, height, msaa);
                peer.upload(s);
                for (int i = 0; i < warmup; ++i) peer.renderFrame(s);  // includes shader JIT
                for (int i = 0; i < frames; ++i) theirs.push_back(peer.renderFrame(s));
            }
            const double theirMedian = median(theirs);
            if (verbose) {
                std::printf("# frames (ms), cuberille:");
                for (double t : ours) std::printf(" %.1f", t);
                std::printf("; llvmpipe:");
                for (double t : theirs) std::printf(" %.1f", t);
                std::printf("\n");
            }

            std::printf("%-9s %4d %10zu | %8.1f %8.1f %8.1f %8.1f %10.1f | %10.1f | %6.2fx\n",
                        name.c_str(), msaa, s.triangleCount(), typical.stages.vertexMs,
                        typical.stages.frontEndMs, typical.stages.backEndMs,
                        typical.stages.resolveMs, ourMedian, theirMedian, theirMedian / ourMedian);
            std::fflush(stdout);
        }
    }
    return 0;
}
