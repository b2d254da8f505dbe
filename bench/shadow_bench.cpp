// Shadow modes over whole sequences (issue 27, docs/ray_tracing.md): a turntable of each model on
// its floor (`cuberille render MODEL --ground --turntable N --shadows MODE`), the shadow stage's
// time summed over the frames, each mode against the ray-traced reference run side by side in the
// same process, and the share of pixels whose final colour differs from the reference's frame.
//
//   shadow_bench [--scenes vc,dragon,brainstem,helmet] [--frames 36] [--width 1280 --height 720]
//                [--shadows hard,soft] [--modes raytraced,hybrid,auto]
//
// The stage's time is everything it does for a frame (render::ShadowFrameStats::totalMs): the
// visibility buffer, maps drawn or kept, marks, map lookups and rays; the BVH and edge adjacency,
// built once per scene, are included in the first frame's. Each configuration renders its frames
// in a fresh LoadedScene, so none inherits another's maps.

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>

#include "bench/bench_support.h"
#include "raster/parallel.h"
#include "render/loaded_scene.h"
#include "render/renderer.h"
#include "render/scene_shadows.h"

namespace {

using namespace cuberille;
namespace fs = std::filesystem;

fs::path dataPath(const std::string& name) {
    const fs::path gltf = fs::path(CUBERILLE_SOURCE_DIR) / ".." / "shared" / "data" / "gltf";
    if (name == "vc") return gltf / "VC" / "VC.glb";
    if (name == "brainstem") return gltf / "BrainStem" / "BrainStem.glb";
    if (name == "helmet") return gltf / "DamagedHelmet" / "DamagedHelmet.glb";
    if (name == "cesiumman") return gltf / "CesiumMan" / "CesiumMan.glb";
    return bench::scanPath(name, CUBERILLE_SOURCE_DIR);
}

struct Sequence {
    double shadowMs = 0.0;       // the stage over every frame
    double firstFrameMs = 0.0;   // of which the first frame (hierarchies built, maps first drawn)
    uint64_t differingPixels = 0;  // against the reference's frames
    uint64_t pixels = 0;
    uint64_t markedPixels = 0, receiverPixels = 0;
    int mapsDrawn = 0, mapsKept = 0;
    std::vector<raster::Image> images;
};

/// The turntable `cuberille render --turntable frames` draws, in a scene of its own.
Sequence turntable(const fs::path& path, const render::FrameSettings& base, int frames, const Sequence* reference) {
    const render::LoadedScene scene(path.string());
    Sequence q;
    for (int i = 0; i < frames; ++i) {
        render::FrameSettings f = base;
        f.orbitDegrees = 360.0f * float(i) / float(frames);
        render::RenderResult r = render::render(scene, f);
        const render::ShadowFrameStats& s = *r.shadows;
        q.shadowMs += s.totalMs;
        if (i == 0) q.firstFrameMs = s.totalMs;
        q.markedPixels += s.shadows.markedPixels;
        q.receiverPixels += s.shadows.receiverPixels;
        q.mapsDrawn += s.shadows.mapsDrawn;
        q.mapsKept += s.shadows.mapsKept;
        const raster::Image& image = r.image;
        q.pixels += uint64_t(image.width) * uint64_t(image.height);
        if (reference) {
            const raster::Image& want = reference->images[size_t(i)];
            for (int y = 0; y < image.height; ++y)
                for (int x = 0; x < image.width; ++x) {
                    const float *a = image.pixel(x, y), *b = want.pixel(x, y);
                    q.differingPixels += a[0] != b[0] || a[1] != b[1] || a[2] != b[2] || a[3] != b[3];
                }
        } else {
            q.images.push_back(std::move(r.image));
        }
    }
    return q;
}

void benchScene(const std::string& name, int frames, int width, int height, const std::vector<std::string>& penumbrae,
                const std::vector<std::string>& modes) {
    const fs::path path = dataPath(name);
    if (!fs::exists(path)) {
        std::printf("%s skipped: %s not found\n", name.c_str(), path.string().c_str());
        return;
    }
    for (const std::string& penumbra : penumbrae) {
        render::FrameSettings base;
        base.width = width, base.height = height;
        base.ground = true;
        base.shadows.soft = penumbra == "soft";
        base.shadows.focus = rt::MapFocus::Scene;  // what --turntable's auto focus chooses
        base.shadows.mode = rt::ShadowMode::RayTraced;
        const Sequence reference = turntable(path, base, frames, nullptr);
        auto row = [&](const std::string& mode, const Sequence& q) {
            std::printf("%-10s %-5s %-10s %10.0f %9.1f %7.2f %9.4f%% %8.2f%% %5d %5d\n", name.c_str(), penumbra.c_str(), mode.c_str(),
                        q.shadowMs, q.firstFrameMs, q.shadowMs / reference.shadowMs,
                        100.0 * double(q.differingPixels) / double(std::max<uint64_t>(1, q.pixels)),
                        100.0 * double(q.markedPixels) / double(std::max<uint64_t>(1, q.receiverPixels)), q.mapsDrawn, q.mapsKept);
        };
        for (const std::string& mode : modes) {
            if (mode == "raytraced") {
                row(mode, reference);
                continue;
            }
            render::FrameSettings f = base;
            f.shadows.mode = render::parseShadowMode(mode);
            row(mode, turntable(path, f, frames, &reference));
        }
    }
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"Shadow modes over turntables, against ray-traced shadows in the same run"};
    std::string scenes = "vc,dragon,brainstem,helmet", penumbrae = "hard,soft", modes = "raytraced,hybrid";
    int frames = 36, width = 1280, height = 720;
    app.add_option("--scenes", scenes, "vc, dragon, brainstem, helmet, cesiumman, bunny, horse or a model's path")->capture_default_str();
    app.add_option("--frames", frames, "Turntable frames")->capture_default_str();
    app.add_option("--width", width)->capture_default_str();
    app.add_option("--height", height)->capture_default_str();
    app.add_option("--shadows", penumbrae, "hard, soft or both")->capture_default_str();
    app.add_option("--modes", modes, "Shadow modes besides the ray-traced reference: hybrid, map")->capture_default_str();
    CLI11_PARSE(app, argc, argv);
    std::printf("# %d threads; %d-frame turntables at %dx%d with --ground; shadow stage ms summed over the frames (and the first "
                "frame's), ratio to ray traced, share of pixels differing from the ray-traced frames, share of receivers "
                "traced, maps drawn and kept\n",
                raster::hardwareThreads(), frames, width, height);
    std::printf("%-10s %-5s %-10s %10s %9s %7s %10s %9s %5s %5s\n", "scene", "soft", "mode", "ms", "first", "x ref", "differ",
                "traced", "drawn", "kept");
    for (const std::string& s : bench::splitList(scenes))
        benchScene(s, frames, width, height, bench::splitList(penumbrae), bench::splitList(modes));
    return 0;
}
