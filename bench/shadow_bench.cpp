// Shadow modes over whole sequences (issue 27, docs/ray_tracing.md): a turntable of each model on
// its floor (`cuberille render MODEL --ground --turntable N --shadows MODE`), the shadow stage's
// time summed over the frames, each mode against the ray-traced reference run side by side in the
// same process, and the share of pixels whose final colour differs from the reference's frame.
//
//   shadow_bench [--scenes vc,dragon,brainstem,helmet] [--frames 36,1] [--width 1280 --height 720]
//                [--shadows hard,soft] [--modes hybrid,auto] [--frame-visibility auto|shadow-stage|depth-test]
//
// `--frames 1` is a single frame as `cuberille render` draws it (the sun's map focused on the
// view); more frames are a turntable as `--turntable N` draws it (the map over the whole scene,
// kept, and auto told how many frames share it).
//
// The stage's time is everything it does for a frame (render::ShadowFrameStats::totalMs): the
// visibility buffer, maps drawn or kept, marks, map lookups and rays; the BVH and edge adjacency,
// built once per scene, are added to the first frame's. Each mode renders in a LoadedScene of
// its own, so none inherits another's maps, and the modes take turns frame by frame, so the
// machine's drift (a third within a session on the shared CI VM) falls on all of them alike;
// single frames are run five times and the median taken.
//
// A raster frame of one sample may shade the stage's own visibility buffer instead of drawing the
// scene a second time (render::FrameVisibility), and then that pass is the frame's one look at the
// scene as much as the stage's: `beyond` is the stage less it where the frame did, what shadows
// add to such a frame, and `whole` the stage and the frames' own drawing together.
// `--frame-visibility` chooses as the renderer does (auto) or forces either way, for comparison.

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <memory>

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

/// One shadow mode's run of a turntable, in a scene of its own.
struct ModeRun {
    std::string mode;
    render::FrameSettings settings;
    std::unique_ptr<render::LoadedScene> scene;
    double shadowMs = 0.0;        // the stage over every frame, with its one-off set-up
    /// The same less the visibility pass, where the frame shaded from it (render::FrameSettings::
    /// frameVisibility): what shadows add to a frame that looks at the scene once anyway.
    double beyondVisibilityMs = 0.0;
    double wholeMs = 0.0;         // the stage and the frame's own drawing: what a user waits for
    double firstFrameMs = 0.0;    // of which the first frame (hierarchies built, maps first drawn)
    uint64_t differingPixels = 0, pixels = 0;  // against the reference's frames
    uint64_t markedPixels = 0, receiverPixels = 0;
    int mapsDrawn = 0, mapsKept = 0;
    int autoHybrid = 0, autoRayTraced = 0;  // lights auto gave each mode, over the frames
};

/// A frame's shadow time with what the stage's construction built for it: the BVH, and the edge
/// adjacency hybrid builds up front (auto finds its own within the frame, already in totalMs).
double stageMs(const render::ShadowFrameStats& s, bool first, rt::ShadowMode mode) {
    double ms = s.totalMs;
    if (first) ms += s.bvhBuildMs + (mode == rt::ShadowMode::Auto ? 0.0 : s.adjacencyMs);
    return ms;
}

/// Every mode's turntable, frame by frame in turn (the reference first), so the machine's drift
/// falls on all of them alike.
std::vector<ModeRun> turntables(const fs::path& path, const render::FrameSettings& base, int frames,
                                const std::vector<std::string>& modes) {
    std::vector<ModeRun> runs;
    for (const std::string& mode : modes) {
        ModeRun r{mode, base, std::make_unique<render::LoadedScene>(path.string())};
        r.settings.shadows.mode = render::parseShadowMode(mode);
        runs.push_back(std::move(r));
    }
    for (int i = 0; i < frames; ++i) {
        raster::Image reference;
        for (ModeRun& r : runs) {
            render::FrameSettings f = r.settings;
            f.orbitDegrees = 360.0f * float(i) / float(frames);
            render::RenderResult result = render::render(*r.scene, f);
            const render::ShadowFrameStats& s = *result.shadows;
            const double ms = stageMs(s, i == 0, f.shadows.mode);
            r.shadowMs += ms;
            r.beyondVisibilityMs += ms - (result.shadedShadowStageVisibility ? s.surfacesMs : 0.0);
            r.wholeMs += ms + result.stats.times.frameMs;
            if (i == 0) r.firstFrameMs = ms;
            r.markedPixels += s.shadows.markedPixels;
            r.receiverPixels += s.shadows.receiverPixels;
            r.mapsDrawn += s.shadows.mapsDrawn;
            r.mapsKept += s.shadows.mapsKept;
            r.autoHybrid += s.shadows.autoHybrid;
            r.autoRayTraced += s.shadows.autoRayTraced;
            const raster::Image& image = result.image;
            r.pixels += uint64_t(image.width) * uint64_t(image.height);
            if (&r == &runs.front()) {
                reference = std::move(result.image);
                continue;
            }
            for (size_t p = 0; p < image.rgba.size(); p += 4)
                r.differingPixels += image.rgba[p] != reference.rgba[p] || image.rgba[p + 1] != reference.rgba[p + 1] ||
                                     image.rgba[p + 2] != reference.rgba[p + 2] || image.rgba[p + 3] != reference.rgba[p + 3];
        }
    }
    for (ModeRun& r : runs) r.scene.reset();  // a repeat's scenes (textures, maps) leave before the next loads
    return runs;
}

void benchScene(const std::string& name, const std::vector<int>& frameCounts, int width, int height,
                const std::vector<std::string>& penumbrae, const std::vector<std::string>& modes, int singleFrameRuns,
                render::FrameVisibility frameVisibility) {
    const fs::path path = dataPath(name);
    if (!fs::exists(path)) {
        std::printf("%s skipped: %s not found\n", name.c_str(), path.string().c_str());
        return;
    }
    std::vector<std::string> all{"raytraced"};
    all.insert(all.end(), modes.begin(), modes.end());
    for (const int frames : frameCounts)
        for (const std::string& penumbra : penumbrae) {
            render::FrameSettings base;
            base.width = width, base.height = height;
            base.ground = true;
            base.frameVisibility = frameVisibility;
            base.shadows.soft = penumbra == "soft";
            // What the command line chooses: a turntable's sun map over the scene, shared by its frames.
            base.shadows.focus = frames > 1 ? rt::MapFocus::Scene : rt::MapFocus::View;
            base.shadows.sequenceFrames = frames;
            // A single frame is short enough to time again: the run whose reference time is the median.
            std::vector<std::vector<ModeRun>> repeats;
            for (int k = 0; k < (frames == 1 ? singleFrameRuns : 1); ++k) repeats.push_back(turntables(path, base, frames, all));
            std::vector<double> totals(all.size(), 0.0), beyond(all.size(), 0.0), whole(all.size(), 0.0);
            std::vector<ModeRun>& runs = repeats.front();
            for (size_t m = 0; m < all.size(); ++m) {  // each mode's median over the repeats
                std::vector<double> t, b, w;
                for (const auto& r : repeats) t.push_back(r[m].shadowMs), b.push_back(r[m].beyondVisibilityMs), w.push_back(r[m].wholeMs);
                totals[m] = bench::median(t);
                beyond[m] = bench::median(b);
                whole[m] = bench::median(w);
            }
            for (size_t m = 0; m < all.size(); ++m) {
                const ModeRun& q = runs[m];
                std::string chose;
                if (q.settings.shadows.mode == rt::ShadowMode::Auto)
                    chose = "hybrid " + std::to_string(q.autoHybrid) + ", raytraced " + std::to_string(q.autoRayTraced);
                std::printf("%-10s %6d %-5s %-10s %10.0f %9.1f %7.2f %9.0f %7.2f %9.0f %9.4f%% %8.2f%% %5d %5d %s\n", name.c_str(),
                            frames, penumbra.c_str(), q.mode.c_str(), totals[m], q.firstFrameMs, totals[m] / totals[0],
                            beyond[m], beyond[m] / beyond[0], whole[m],
                            100.0 * double(q.differingPixels) / double(std::max<uint64_t>(1, q.pixels)),
                            100.0 * double(q.markedPixels) / double(std::max<uint64_t>(1, q.receiverPixels)), q.mapsDrawn,
                            q.mapsKept, chose.c_str());
            }
            std::fflush(stdout);
        }
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"Shadow modes over turntables, against ray-traced shadows in the same run"};
    std::string scenes = "vc,dragon,brainstem,helmet", penumbrae = "hard,soft", modes = "hybrid,auto", frames = "36,1";
    int width = 1280, height = 720, singleFrameRuns = 5;
    std::string visibility = "auto";
    app.add_option("--scenes", scenes, "vc, dragon, brainstem, helmet, cesiumman, bunny, horse or a model's path")->capture_default_str();
    app.add_option("--frames", frames, "Turntable lengths (1: a single frame)")->capture_default_str();
    app.add_option("--single-frame-runs", singleFrameRuns, "Single frames: runs, the median reported")->capture_default_str();
    app.add_option("--width", width)->capture_default_str();
    app.add_option("--height", height)->capture_default_str();
    app.add_option("--shadows", penumbrae, "hard, soft or both")->capture_default_str();
    app.add_option("--modes", modes, "Shadow modes besides the ray-traced reference: hybrid, auto, map")->capture_default_str();
    app.add_option("--frame-visibility", visibility,
                   "auto (the renderer's choice), shadow-stage (frames shade the stage's visibility buffer) or depth-test "
                   "(frames draw the scene again)")
        ->check(CLI::IsMember({"auto", "shadow-stage", "depth-test"}))
        ->capture_default_str();
    CLI11_PARSE(app, argc, argv);
    std::printf("# %d threads; turntables at %dx%d with --ground; shadow stage ms summed over the frames (and the first "
                "frame's), ratio to ray traced, the same less the visibility pass the frame shades from (and its ratio), the stage "
                "and frames together, share of pixels differing from the ray-traced frames, share of receivers "
                "traced, maps drawn and kept, auto's choices\n",
                raster::hardwareThreads(), width, height);
    std::printf("%-10s %6s %-5s %-10s %10s %9s %7s %9s %7s %9s %10s %9s %5s %5s\n", "scene", "frames", "soft", "mode", "ms",
                "first", "x ref", "beyond", "x ref", "whole", "differ", "traced", "drawn", "kept");
    std::vector<int> frameCounts;
    for (const std::string& f : bench::splitList(frames)) frameCounts.push_back(std::stoi(f));
    for (const std::string& s : bench::splitList(scenes))
        benchScene(s, frameCounts, width, height, bench::splitList(penumbrae), bench::splitList(modes), singleFrameRuns,
                   render::parseFrameVisibility(visibility));
    return 0;
}
