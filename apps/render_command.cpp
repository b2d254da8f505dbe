#include "apps/render_command.h"

#include <algorithm>
#include <cstdio>

#include "apps/atomic_file.h"
#include "apps/image_io.h"
#include "apps/process_memory.h"
#include "apps/progress.h"
#include "raster/clock.h"
#include "scene/file_names.h"
#include "scene/input_error.h"

namespace cuberille::apps {
namespace {

// The checks that belong to the command rather than the frame: sequences and their limits.
void validateSequence(const RenderOptions& o) {
    using scene::InputError;
    if (o.animate < 0 || o.animate > 3600) throw InputError("--animate: 0 to 3600 frames");
    const scene::FileKind kind = scene::fileKindOf(o.scene);
    if (o.animate > 0 && !scene::isGltfKind(kind))
        throw InputError("--animate: only for glTF files (.gltf, .glb), not " + o.scene);
    if (o.animate > 0 && o.turntable > 0) throw InputError("--animate and --turntable: one or the other");
    if (!(o.fps > 0.0f && o.fps <= 1000.0f)) throw InputError("--fps: must be in (0, 1000]");
    if (o.turntable > 0 && kind == scene::FileKind::TriangleList) throw InputError("--turntable: " + o.scene + " is a 2D .tri scene");
    if (o.turntable > 3600) throw InputError("--turntable: at most 3600 frames");
    if (o.supersample > 1 && (o.turntable > 0 || o.animate > 0))
        throw InputError("--supersample: not with --turntable or --animate (each frame would be rendered without it)");
    if (o.turntable > 0 && kind == scene::FileKind::VoxelModel) throw InputError("--turntable: not for voxel models yet");
}

bool isSequence(const RenderOptions& o) { return o.turntable > 0 || o.animate > 0; }

std::filesystem::path frameFileName(const std::filesystem::path& out, int frame) {
    char suffix[16];
    std::snprintf(suffix, sizeof suffix, "_%03d", frame);
    return out.parent_path() / (out.stem().string() + suffix + out.extension().string());
}

}  // namespace

ImageWriteOptions imageWriteOptions(const RenderOptions& o) {
    ImageWriteOptions w;
    w.alpha = o.background && o.background->a < 1.0f;
    w.pngBits = o.pngBits;
    return w;
}

render::LoadedScene loadScene(const RenderOptions& o) {
    render::SceneOptions options;
    options.detail = o.detail;
    options.zUp = o.zUp;
    return render::LoadedScene(o.scene, options, [quiet = o.quiet](const std::string& w) {
        if (!quiet) std::fprintf(stderr, "cuberille: warning: %s\n", w.c_str());
    });
}

RenderResult renderScene(const RenderOptions& o) {
    const render::LoadedScene scene = loadScene(o);
    RenderResult r = render::render(scene, o);
    r.loadMs += scene.loadMs();
    return r;
}

nlohmann::json statsToJson(const RenderOptions& o, const RenderResult& r) {
    nlohmann::json j = nlohmann::json::parse(render::statsJson(o.scene, o, r));
    return j;
}

void printSummary(const RenderOptions& o, const std::filesystem::path& file, const RenderResult& r) {
    const raster::StageCounters& c = r.stats.counters;
    const int samplesPerPixel = o.msaa * o.supersample * o.supersample;
    std::printf("wrote %s (%dx%d, %d sample%s%s, view %s)\n", file.c_str(), o.width, o.height, samplesPerPixel,
                samplesPerPixel > 1 ? "s" : "", o.supersample > 1 ? " by supersampling" : "", viewName(o.view));
    // Times that add up: the drawn frame's stages plus what ran between them (flush
    // orchestration, clears), then the resolve into the image, which runs after the frame.
    const raster::StageTimes& t = r.stats.times;
    const double other = std::max(0.0, t.frameMs - t.vertexMs - t.frontEndMs - t.backEndMs);
    // A voxel model's frame draws the faces and source triangles its blocks chose, not the
    // model's source triangle count.
    std::printf(" ");
    if (r.voxel)
        std::printf(" %llu voxel faces and %llu source triangles drawn,", (unsigned long long)r.voxel->facesEmitted,
                    (unsigned long long)r.voxel->hybridTriangles);
    std::printf(" %llu triangles in, %llu set up, %llu culled, %llu clipped; %.1f ms = frame %.1f "
                "(vertex %.1f, front end %.1f, back end %.1f, other %.1f) + resolve %.1f\n",
                (unsigned long long)(r.voxel ? c.trianglesIn : r.sceneTriangles),
                (unsigned long long)c.trianglesSetUp,
                (unsigned long long)(c.trianglesCulled + c.trianglesClipRejected),
                (unsigned long long)c.trianglesClipped, t.frameMs + t.resolveMs, t.frameMs, t.vertexMs,
                t.frontEndMs, t.backEndMs, other, t.resolveMs);
    std::printf("  blocks: %llu full, %llu partial, %llu hidden by hierarchical Z; %llu samples passed "
                "depth, %llu pixels shaded\n",
                (unsigned long long)c.blocksFull, (unsigned long long)c.blocksPartial,
                (unsigned long long)c.blocksDepthCulled, (unsigned long long)c.samplesPassed,
                (unsigned long long)c.pixelsShaded);
    std::printf("  effects: %llu texture samples, %llu light evaluations, %llu pixels alpha-tested, %llu blended\n",
                (unsigned long long)c.textureSamples, (unsigned long long)c.lightEvaluations,
                (unsigned long long)c.pixelsAlphaTested, (unsigned long long)c.pixelsBlended);
    if (r.culling) {
        const render::FrustumCullStats& c = *r.culling;
        std::printf("  frustum cull: %llu of %llu triangles kept, %llu nodes visited; %.1f ms (bvh %s %.1f, "
                    "degradation %.3f)\n",
                    (unsigned long long)c.trianglesKept, (unsigned long long)c.trianglesIn,
                    (unsigned long long)c.counters.nodesVisited, c.cullMs, c.rebuilt ? "build" : "refit", c.buildMs,
                    c.degradation);
    }
    if (r.shadows && r.shadows->occlusion.raysPerPixel > 0) {
        const rt::AmbientOcclusionStats& ao = r.shadows->occlusion;
        std::printf("  ambient occlusion: %d rays a pixel within %g, %llu pixels, %llu rays; %.1f ms\n",
                    ao.raysPerPixel, ao.distance, (unsigned long long)ao.pixels,
                    (unsigned long long)ao.rays, ao.ms);
    }
    if (r.shadows && r.shadows->mode != rt::ShadowMode::None) {
        const rt::ShadowStats& st = r.shadows->shadows;
        char bvh[48];
        if (r.shadows->bvhShared)
            std::snprintf(bvh, sizeof bvh, "bvh: the camera rays'");
        else
            std::snprintf(bvh, sizeof bvh, "bvh %.1f", r.shadows->bvhBuildMs);
        std::printf("  shadows (%s%s): %d light%s, %llu receiver pixels, %llu marked (%.2f%%), %llu rays; %.1f ms "
                    "(%s, surfaces %.1f, maps %.1f, masks %.1f)\n",
                    render::shadowModeName(r.shadows->mode), r.shadows->soft ? ", soft" : "", st.lightsShadowed,
                    st.lightsShadowed == 1 ? "" : "s", (unsigned long long)st.receiverPixels,
                    (unsigned long long)st.markedPixels,
                    st.receiverPixels ? 100.0 * double(st.markedPixels) / double(st.receiverPixels) : 0.0,
                    (unsigned long long)st.raysTraced, r.shadows->totalMs, bvh, r.shadows->surfacesMs, st.mapMs, st.maskMs);
        if (r.shadows->mode == rt::ShadowMode::Auto)
            std::printf("  auto: %d light%s hybrid, %d raytraced; predicted hybrid %.1f ms, raytraced %.1f ms; took %.1f ms\n",
                        st.autoHybrid, st.autoHybrid == 1 ? "" : "s", st.autoRayTraced, st.predictedHybridMs,
                        st.predictedRayTracedMs, st.mapMs + st.maskMs);
        if (r.shadows->bvhUpdated)
            std::printf("  shadow casters moved: bvh %s in %.1f ms, degradation %.3f\n", r.shadows->bvhRebuilt ? "rebuilt" : "refitted",
                        r.shadows->bvhUpdateMs, r.shadows->degradation);
    }
}


namespace {

// Frame `index` of the command's image, in its file; returns the file.
std::filesystem::path writeFrameImage(const RenderOptions& o, int index, const RenderResult& r) {
    const std::filesystem::path file = frameFile(o, index);
    // The depth view of a 3D scene holds distances: EXR keeps them, 8-bit files get them legible.
    const bool depthIsDistance = scene::fileKindOf(o.scene) != scene::FileKind::TriangleList;
    raster::Image legible;
    const raster::Image& image =
        imageFormatFor(file) == ImageFormat::Exr ? r.image : render::displayImage(r.image, o.view, depthIsDistance, legible);
    writeImageAtomically(file, image, imageWriteOptions(o));
    return file;
}

// Frame `index` of the command: its image, its stats kept for {"frames": [...]}; the one frame's
// summary (a sequence prints one for all its frames).
void writeFrame(const RenderOptions& o, int index, const RenderResult& r, nlohmann::json& frames) {
    const std::filesystem::path file = writeFrameImage(o, index, r);
    if (!o.statsPath.empty()) frames.push_back(statsToJson(o, r));
    if (!o.quiet && !isSequence(o)) printSummary(o, file, r);
}

// What a sequence's summary adds up over its frames.
struct SequenceTotals {
    std::vector<double> frameMs;  // each frame's whole time: its frame and resolve, shadows included
    double loadMs = 0.0;
    uint64_t trianglesIn = 0, pixelsShaded = 0, raysTraced = 0;
};

void addToTotals(const RenderResult& r, SequenceTotals& t) {
    t.frameMs.push_back(r.stats.times.frameMs + r.stats.times.resolveMs + (r.shadows ? r.shadows->totalMs : 0.0));
    t.loadMs += r.loadMs;
    t.trianglesIn += r.stats.counters.trianglesIn;
    t.pixelsShaded += r.stats.counters.pixelsShaded;
    if (r.shadows) t.raysTraced += r.shadows->shadows.raysTraced;
}

// One summary for a --turntable or --animate sequence, not one per frame.
void printSequenceSummary(const RenderOptions& o, int count, SequenceTotals t) {
    const int samplesPerPixel = o.msaa * o.supersample * o.supersample;
    std::printf("wrote %s .. %s (%d frames, %dx%d, %d sample%s, view %s)\n", frameFileName(o.out, 0).c_str(),
                frameFileName(o.out, count - 1).c_str(), count, o.width, o.height, samplesPerPixel,
                samplesPerPixel > 1 ? "s" : "", render::viewName(o.view));
    double total = 0.0;
    for (double ms : t.frameMs) total += ms;
    std::sort(t.frameMs.begin(), t.frameMs.end());
    std::printf("  frames: median %.1f ms, slowest %.1f ms, %.1f ms in all; loading and posing %.1f ms\n",
                t.frameMs[t.frameMs.size() / 2], t.frameMs.back(), total, t.loadMs);
    std::printf("  %llu triangles in, %llu pixels shaded in all", (unsigned long long)t.trianglesIn,
                (unsigned long long)t.pixelsShaded);
    if (o.shadows.mode != rt::ShadowMode::None) std::printf(", %llu shadow rays", (unsigned long long)t.raysTraced);
    std::printf("; --stats has each frame\n");
}

// Frame `index` of the command: the one frame, or of --turntable N the camera turned about the
// world's up axis by 360/N degrees a frame, or of --animate N the animation posed at --time + i / --fps.
render::FrameSettings sequenceFrame(const RenderOptions& o, int index) {
    render::FrameSettings frame = o;
    frame.shadows.focus = o.shadowFocus.value_or(o.turntable > 0 ? rt::MapFocus::Scene : rt::MapFocus::View);
    if (o.turntable > 0) {
        frame.orbitDegrees = 360.0f * float(index) / float(o.turntable);
        frame.shadows.sequenceFrames = o.turntable;  // lights and casters stay; the camera turns
    }
    if (o.animate > 0) frame.timeSeconds = o.timeSeconds + float(index) / o.fps;
    return frame;
}

// The frames of the command. The scene is loaded once; the hierarchies the frustum cull and
// shadows need are built on the first frame and, for an animation, refitted to each next pose
// (render/loaded_scene.h).
int renderFrames(const render::LoadedScene& scene, const RenderOptions& o) {
    const bool sequence = isSequence(o);
    const int count = frameCount(o);
    nlohmann::json frames = nlohmann::json::array();
    SequenceTotals totals;
    ProgressLine progress("frame", count, o.quiet);
    for (int i = 0; i < count; ++i) {
        std::optional<ElapsedLine> elapsed;
        if (!sequence) elapsed.emplace("rendering", o.quiet);  // a sequence counts its frames instead
        RenderResult r = render::render(scene, sequenceFrame(o, i));
        elapsed.reset();
        if (i == 0) r.loadMs += scene.loadMs();
        writeFrame(o, i, r, frames);  // what it writes does not depend on the orbit or time
        addToTotals(r, totals);
        progress.update(i + 1);
    }
    progress.finish();
    if (sequence && !o.quiet) printSequenceSummary(o, count, std::move(totals));
    if (!o.statsPath.empty()) writeRenderStats(o, frames);
    return 0;
}

}  // namespace

int runRenderCommand(const RenderOptions& o) {
    checkRenderCommand(o);
    return renderFrames(loadScene(o), o);
}

int runRenderCommand(const RenderOptions& o, const render::LoadedScene& scene) { return renderFrames(scene, o); }

int frameCount(const RenderOptions& o) { return o.turntable > 0 ? o.turntable : o.animate > 0 ? o.animate : 1; }

std::filesystem::path frameFile(const RenderOptions& o, int index) {
    return isSequence(o) ? frameFileName(o.out, index) : o.out;
}

nlohmann::json renderFrameRun(const render::LoadedScene& scene, const RenderOptions& o, int first, int count) {
    if (first < 0 || count < 0 || first + count > frameCount(o))
        throw std::invalid_argument("renderFrameRun: frames outside the command's sequence");
    nlohmann::json frames = nlohmann::json::array();
    for (int i = first; i < first + count; ++i) {
        const RenderResult r = render::render(scene, sequenceFrame(o, i));
        writeFrameImage(o, i, r);
        frames.push_back(statsToJson(o, r));
    }
    return frames;
}

void writeRenderStats(const RenderOptions& o, const nlohmann::json& frames) {
    nlohmann::json stats = isSequence(o) ? nlohmann::json{{"frames", frames}} : frames.at(0);
    // The process that wrote the file, at the end of its work: what `accuracy` reports as a run's memory.
    stats["process"] = {{"peakResidentBytes", peakResidentBytes()}};
    writeJsonAtomically(o.statsPath, stats);
}

void checkRenderCommand(const RenderOptions& o) {
    if (o.out.empty()) throw scene::InputError("--out: an output file is required (.png, .exr or .jpg)");
    requireOutputPath(o.out, "--out");  // first: a folder given as --out is named as one
    // Refuse what cannot be written before any work: a bad extension, alpha in a JPEG.
    const ImageFormat format = imageFormatFor(o.out);
    if (format == ImageFormat::Jpeg && imageWriteOptions(o).alpha)
        throw scene::InputError("--background: an opacity below 1 needs a .png or .exr output (JPEG has no alpha)");
    if (o.pngBits != 8 && o.pngBits != 16) throw scene::InputError("--png-bits: 8 or 16");
    if (o.pngBits != 8 && format != ImageFormat::Png)
        throw scene::InputError("--png-bits: only for .png outputs");
    requireOutputPath(o.statsPath, "--stats");
    validateSequence(o);
}

}  // namespace cuberille::apps
