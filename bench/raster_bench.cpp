// Frame time of the software pipeline against Mesa's llvmpipe (OSMesa) on the same scenes, in
// the same run, at equal settings: same triangles, the same per-pixel shading (the peer's GLSL is
// raster/shade.h: bench/llvmpipe_peer.cpp), same resolution and sample count, the scene's culling
// (back faces, none for scans and double-sided materials) and a depth test. Prints the ratio
// llvmpipe / cuberille (above 1: cuberille is faster). Absolute times on shared machines are
// noise; the ratio is the figure (docs/performance.md).
//
//   raster_bench [--threads N] [--frames N] [--width W] [--height H] [--scenes a,b] [--msaa 1,4]
//
// Both renderers are timed warm (--warmup frames are drawn and discarded), as the median of
// --frames frames, from clear to a resolved image in memory (no file I/O, no readback).

#include <algorithm>
#include <filesystem>
#include <functional>
#include <memory>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <malloc.h>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "bench/bench_support.h"
#include "bench/llvmpipe_peer.h"
#include "raster/instruction_set.h"
#include "raster/parallel.h"
#include "raster/pipeline.h"
#include "raster/resolve.h"
#include "scene/model_scene.h"
#include "scene/procedural.h"

namespace {

using namespace cuberille;

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

// A depth-only pass of the scene's view, as shadow maps and the visibility buffer draw theirs
// (rt/shadow_map.cpp): no colour attachment, every mesh an opaque ConstantColor draw with colour
// writes off and the scene's culling; nothing to resolve.
OurFrame renderOursDepth(raster::Pipeline& p, const scene::Scene& s, int w, int h, int msaa) {
    const auto t0 = std::chrono::steady_clock::now();
    raster::FramebufferDesc d;
    d.widthPixels = w, d.heightPixels = h, d.samples = msaa, d.colorAttachment = false;
    p.beginFrame(d);
    for (const scene::Mesh& m : s.meshes) {
        raster::DrawCall draw;
        draw.space = raster::PositionSpace::Clip;
        draw.clipFromObject = s.camera.clipFromWorld(float(w) / h);
        draw.positions = m.positions;
        draw.indices = m.indices;
        draw.state.shading = raster::ShadingModel::ConstantColor;
        draw.state.cull = m.doubleSided ? raster::CullMode::None : s.cull;
        draw.state.colorWriteMask = 0;
        p.draw(draw);
    }
    p.endFrame();
    OurFrame f{std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count(), p.stats().times};
    f.stages.resolveMs = 0.0;
    return f;
}

// The depth-only evidence, at 1 sample: the share of pixels both renderers covered or both left
// empty (rasterization rules and depth precision decide the rest), in percent.
double depthCoverageAgreement(const raster::Pipeline& p, const std::vector<bool>& theirs, int w, int h) {
    std::vector<float> depth;
    raster::resolveDepthPlane(p.framebuffer(), depth);
    size_t same = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            same += (depth[size_t(y) * w + x] < 1.0f) == theirs[size_t(h - 1 - y) * w + x];
    return 100.0 * double(same) / (double(w) * h);
}

// How alike the two renderers' images are, as PSNR in dB over the linear RGB values both write
// (the peer's framebuffer holds them as 8-bit UNORM, bottom row first): the evidence that the
// peer did the same work. Equal shading leaves rasterization rules and rounding: around 40 dB
// and up on the bench scenes; a peer that shaded differently shows as 20 dB or less.
double peerAgreementDb(const raster::Image& ours, const std::vector<unsigned char>& theirs) {
    double squared = 0.0;
    for (int y = 0; y < ours.height; ++y)
        for (int x = 0; x < ours.width; ++x) {
            const float* p = ours.pixel(x, y);
            const unsigned char* q = theirs.data() + (size_t(ours.height - 1 - y) * ours.width + x) * 4;
            for (int c = 0; c < 3; ++c) {
                const double a = std::clamp(double(p[c]), 0.0, 1.0), b = q[c] / 255.0;
                squared += (a - b) * (a - b);
            }
        }
    const double mse = squared / (3.0 * ours.width * ours.height);
    return mse > 0.0 ? 10.0 * std::log10(1.0 / mse) : 99.0;
}

// --- What each effect costs: the field scene's geometry drawn with one effect added at a time.

std::shared_ptr<const raster::Texture> benchBumps() {  // tangent-space normals of a bumpy grid
    std::vector<glm::vec4> t(128 * 128);
    for (int y = 0; y < 128; ++y)
        for (int x = 0; x < 128; ++x) {
            const glm::vec3 n = glm::normalize(glm::vec3(0.3f * std::sin(x * 0.4f), 0.3f * std::cos(y * 0.4f), 1.0f));
            t[y * 128 + x] = glm::vec4(n * 0.5f + 0.5f, 1.0f);
        }
    return std::make_shared<raster::Texture>(128, 128, std::move(t));
}

struct EffectVariant {
    const char* name;
    std::function<void(scene::Scene&)> apply;  // empty: the bare pipeline (ConstantColor draws)
};

// The bare pipeline: every mesh as one ConstantColor draw, nothing interpolated or lit.
void drawBare(raster::Pipeline& p, const scene::Scene& s, float aspect) {
    for (const scene::Mesh& m : s.meshes) {
        raster::DrawCall d;
        d.clipFromObject = s.camera.clipFromWorld(aspect);
        d.positions = m.positions;
        d.indices = m.indices;
        d.state.cull = s.cull;
        d.state.constantColor = glm::vec4(m.color, 1.0f);
        p.draw(d);
    }
}

void runEffectTable(int width, int height, int frames, int warmup) {
    const auto checker = scene::checkerTexture(256, 8, glm::vec3(0.9f), glm::vec3(0.3f)), bumps = benchBumps();
    auto textured = [&](scene::Scene& s) {
        for (scene::Mesh& m : s.meshes) {
            m.texCoords.clear();
            for (const glm::vec3& p : m.positions) m.texCoords.emplace_back(p.x * 0.5f, p.z * 0.5f + p.y * 0.5f);
            m.textures.baseColor.texture = checker;
        }
    };
    auto pbr = [](scene::Scene& s) {
        for (scene::Mesh& m : s.meshes) m.metallicRoughness = true, m.metallic = 0.3f, m.roughness = 0.5f;
    };
    const std::vector<EffectVariant> variants = {
        {"bare pipeline (ConstantColor)", {}},
        {"flat unlit colour (Unlit)", [](scene::Scene& s) { for (auto& m : s.meshes) m.unlit = true; }},
        {"Lambert, 1 directional light", [](scene::Scene&) {}},
        {"Lambert + base colour texture", textured},
        {"Lambert + 3 point lights", [](scene::Scene& s) {
             for (int i = 0; i < 3; ++i) {
                 raster::Light& l = s.lighting.lights[s.lighting.lightCount++];
                 l.type = raster::LightType::Point;
                 l.position = glm::vec3(-8.0f + 8.0f * i, 3.0f, 0.0f);
                 l.intensity = glm::vec3(10.0f);
             }
         }},
        {"metallic-roughness", pbr},
        {"metallic-roughness + texture + normal map", [&](scene::Scene& s) {
             pbr(s);
             textured(s);
             for (scene::Mesh& m : s.meshes) {
                 m.textures.normal.texture = bumps;
                 scene::computeVertexTangents(m);
             }
         }},
        {"Lambert, alpha blended", [](scene::Scene& s) {
             for (auto& m : s.meshes) m.alpha = 0.5f, m.alphaMode = raster::AlphaMode::Blend;
         }},
    };
    std::printf("\n# what each effect costs: field geometry, %dx%d, 1 sample, median of %d frames\n", width, height,
                frames);
    std::printf("%-44s %10s %8s %14s %14s\n", "variant", "ms", "x bare", "tex samples", "light evals");
    double bareMs = 0.0;
    for (const EffectVariant& v : variants) {
        scene::Scene s = scene::makeProceduralScene("field");
        if (v.apply) v.apply(s);
        raster::Pipeline p;
        raster::Image image;
        std::vector<double> times;
        for (int i = 0; i < warmup + frames; ++i) {
            const auto t0 = std::chrono::steady_clock::now();
            raster::FramebufferDesc d;
            d.widthPixels = width, d.heightPixels = height, d.samples = 1, d.clearColor = s.background;
            p.beginFrame(d);
            if (v.apply)
                s.draw(p, float(width) / height);
            else
                drawBare(p, s, float(width) / height);
            p.endFrame();
            raster::resolveColor(p.framebuffer(), image);
            if (i >= warmup) times.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
        }
        const double ms = bench::median(times);
        if (!v.apply) bareMs = ms;
        const raster::StageCounters& c = p.stats().counters;
        std::printf("%-44s %10.1f %7.2fx %14llu %14llu\n", v.name, ms, ms / bareMs, (unsigned long long)c.textureSamples,
                    (unsigned long long)c.lightEvaluations);
        std::fflush(stdout);
    }
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"Frame time against llvmpipe, side by side"};
    int threads = 0, frames = 7, warmup = 3, width = 1920, height = 1080;
    bool verbose = false, noPeer = false, effects = false, depthOnly = false;
    std::string scenes = "field,subpixel,fill", msaaList = "1,4";
    app.add_option("--threads", threads, "Threads for both renderers (0 = all cores)");
    app.add_option("--frames", frames, "Timed frames per measurement (median reported)");
    app.add_option("--warmup", warmup, "Untimed frames first, for each renderer");
    app.add_flag("--verbose", verbose, "Print every frame time");
    app.add_flag("--no-peer", noPeer, "Time Cuberille alone (for profiling); no ratio");
    app.add_option("--width", width);
    app.add_option("--height", height);
    app.add_option("--scenes", scenes, "Comma-separated built-in scenes or model files (.gltf .glb .ply .obj)");
    app.add_flag("--effects", effects, "Also print what each shading effect costs (field geometry)");
    app.add_flag("--depth-only", depthOnly,
                 "Time depth-only passes (shadow maps, visibility buffers): colour writes off, every mesh opaque; "
                 "the last column is the share of pixels both cover alike (1 sample)");
    app.add_option("--msaa", msaaList, "Comma-separated sample counts");
    std::string instructionSet = "best";
    app.add_option("--simd", instructionSet, "Cuberille's instruction set: best, or one of the names in the header line (also CUBERILLE_SIMD)");
    CLI11_PARSE(app, argc, argv);
    raster::useInstructionSetFromEnvironment();
    if (app.count("--simd")) raster::useInstructionSet(instructionSet);

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

    std::string sets;
    for (const std::string& name : raster::availableInstructionSets()) sets += (sets.empty() ? "" : ", ") + name;
    std::printf("# %dx%d, %d thread%s, median of %d warm frames; Cuberille on %s (this CPU runs %s)\n", width, height,
                effectiveThreads, effectiveThreads > 1 ? "s" : "", frames, raster::activeInstructionSet().c_str(), sets.c_str());
    std::printf("%s%-9s %4s %10s | %8s %8s %8s %8s %10s | %10s | %7s | %5s\n", depthOnly ? "# depth only\n" : "", "scene",
                "msaa", "triangles", "vertex", "front", "back", "resolve", "cuberille", "llvmpipe", "ratio",
                depthOnly ? "same%" : "PSNR");
    for (const std::string& entry : bench::splitList(scenes)) {
        // Model files: load time first (parse, decode, pose), then the same frame comparison.
        const auto loadStart = std::chrono::steady_clock::now();
        const bool isFile = scene::isModelFile(entry);
        const scene::Scene s = isFile ? scene::loadModelScene(entry, {}, [](const std::string&) {})
                                      : scene::makeProceduralScene(entry);
        const std::string name = isFile ? std::filesystem::path(entry).filename().string() : entry;
        if (isFile)
            std::printf("# %s: loaded in %.1f ms\n", name.c_str(),
                        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - loadStart).count());
        for (const std::string& m : bench::splitList(msaaList)) {
            const int msaa = std::stoi(m);
            raster::Pipeline pipeline;
            raster::Image image;
            auto frame = [&] {
                return depthOnly ? renderOursDepth(pipeline, s, width, height, msaa)
                                 : renderOurs(pipeline, s, width, height, msaa, image);
            };
            for (int i = 0; i < warmup; ++i) frame();
            std::vector<double> ours;
            std::vector<OurFrame> frameLog;
            for (int i = 0; i < frames; ++i) {
                frameLog.push_back(frame());
                ours.push_back(frameLog.back().totalMs);
            }
            const double ourMedian = bench::median(ours);
            const OurFrame& typical = *std::min_element(frameLog.begin(), frameLog.end(), [&](auto& a, auto& b) {
                return std::abs(a.totalMs - ourMedian) < std::abs(b.totalMs - ourMedian);
            });

            std::vector<double> theirs;
            double agreementDb = 0.0;
            if (noPeer) {
                theirs.push_back(0.0);
            } else {
                bench::LlvmpipePeer peer(width, height, msaa);
                peer.upload(s);
                auto peerFrame = [&] { return depthOnly ? peer.renderDepthFrame(s) : peer.renderFrame(s); };
                for (int i = 0; i < warmup; ++i) peerFrame();  // includes shader JIT
                for (int i = 0; i < frames; ++i) theirs.push_back(peerFrame());
                if (!depthOnly)
                    agreementDb = peerAgreementDb(image, peer.pixels());
                else if (msaa == 1)
                    agreementDb = depthCoverageAgreement(pipeline, peer.depthCoverage(), width, height);
            }
            const double theirMedian = bench::median(theirs);
            if (verbose) {
                std::printf("# frames (ms), cuberille:");
                for (double t : ours) std::printf(" %.1f", t);
                std::printf("; llvmpipe:");
                for (double t : theirs) std::printf(" %.1f", t);
                std::printf("\n");
            }

            std::printf(depthOnly ? "%-9s %4d %10zu | %8.1f %8.1f %8.1f %8.1f %10.1f | %10.1f | %6.2fx | %7.3f\n"
                                  : "%-9s %4d %10zu | %8.1f %8.1f %8.1f %8.1f %10.1f | %10.1f | %6.2fx | %5.1f\n",
                        name.c_str(), msaa, s.triangleCount(), typical.stages.vertexMs,
                        typical.stages.frontEndMs, typical.stages.backEndMs,
                        typical.stages.resolveMs, ourMedian, theirMedian, theirMedian / ourMedian, agreementDb);
            std::fflush(stdout);
        }
    }
    if (effects) runEffectTable(width, height, frames, warmup);
    return 0;
}
