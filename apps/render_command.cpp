#include "apps/render_command.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "apps/image_io.h"
#include "raster/parallel.h"
#include "raster/pipeline.h"
#include "raster/sample_pattern.h"
#include "scene/input_error.h"
#include "scene/model_scene.h"
#include "scene/procedural.h"
#include "scene/tri_scene.h"

namespace cuberille::apps {
namespace {

double nowMs() {
    using namespace std::chrono;
    return duration<double, std::milli>(steady_clock::now().time_since_epoch()).count();
}

void validate(const RenderOptions& o) {
    using scene::InputError;
    if (o.width < 1 || o.height < 1 || o.width > raster::kMaxFramebufferPixels ||
        o.height > raster::kMaxFramebufferPixels)
        throw InputError("--width/--height: " + std::to_string(o.width) + "x" +
                         std::to_string(o.height) + " is outside 1.." +
                         std::to_string(raster::kMaxFramebufferPixels));
    if (!raster::isSupportedSampleCount(o.msaa))
        throw InputError("--msaa: " + std::to_string(o.msaa) + " is not 1, 2, 4, 8 or 16");
    if (o.threads < 0) throw InputError("--threads: must be 0 (all cores) or more");
    if (!(o.detail > 0.0f && o.detail <= 16.0f)) throw InputError("--detail: must be in (0, 16]");
    if (!std::isfinite(o.timeSeconds)) throw InputError("--time: must be a finite number of seconds");
}

raster::FramebufferDesc frameDesc(const RenderOptions& o, glm::vec4 background) {
    raster::FramebufferDesc d;
    d.widthPixels = o.width;
    d.heightPixels = o.height;
    d.samples = o.msaa;
    d.clearColor = background;
    d.recordOverdraw = o.view == View::Overdraw;
    d.recordBlockClasses = o.view == View::Tiles;
    return d;
}

void finishView(const raster::Pipeline& p, View view, raster::Image& image, double& resolveMs) {
    const double t0 = nowMs();
    raster::resolveColor(p.framebuffer(), image);
    if (view == View::Depth) raster::resolveDepth(p.framebuffer(), image);
    if (view == View::Overdraw) raster::visualizeOverdraw(p.framebuffer(), image);
    if (view == View::Tiles) {
        raster::Image color = image;
        raster::visualizeBlockClasses(p.framebuffer(), color, image);
    }
    resolveMs = nowMs() - t0;
}

const char* viewName(View v) {
    switch (v) {
        case View::Color: return "color";
        case View::Depth: return "depth";
        case View::Tiles: return "tiles";
        case View::Overdraw: return "overdraw";
    }
    return "?";
}

}  // namespace

View parseView(const std::string& name) {
    if (name == "color") return View::Color;
    if (name == "depth") return View::Depth;
    if (name == "tiles") return View::Tiles;
    if (name == "overdraw") return View::Overdraw;
    throw scene::InputError("--view: '" + name + "' is not color, depth, tiles or overdraw");
}

RenderResult renderScene(const RenderOptions& o) {
    validate(o);
    raster::ThreadLimit threadLimit(o.threads);
    RenderResult result;
    raster::Pipeline pipeline;
    const double t0 = nowMs();
    if (scene::isProceduralScene(o.scene)) {
        const scene::Scene s = scene::makeProceduralScene(o.scene, o.detail);
        result.loadMs = nowMs() - t0;
        result.sceneTriangles = s.triangleCount();
        pipeline.beginFrame(frameDesc(o, s.background));
        s.draw(pipeline, float(o.width) / float(o.height));
        pipeline.endFrame();  // while the scene's arrays are alive (Pipeline::draw's contract)
    } else if (scene::isModelFile(o.scene)) {
        const scene::Scene s = scene::loadModelScene(
            o.scene, {o.azimuth, o.elevation, o.cameraIndex, o.timeSeconds},
            [&](const std::string& w) { if (!o.quiet) std::fprintf(stderr, "cuberille: warning: %s\n", w.c_str()); });
        result.loadMs = nowMs() - t0;
        result.sceneTriangles = s.triangleCount();
        pipeline.beginFrame(frameDesc(o, s.background));
        s.draw(pipeline, float(o.width) / float(o.height));
        pipeline.endFrame();
    } else {
        if (!o.scene.ends_with(".tri"))
            throw scene::InputError("'" + o.scene + "' is not a scene: expected a .tri, .ply, .ply.gz, .obj, .gltf "
                                    "or .glb file, or a built-in scene name");
        const scene::TriScene s = scene::loadTriScene(o.scene);
        result.loadMs = nowMs() - t0;
        result.sceneTriangles = s.triangleCount();
        pipeline.beginFrame(frameDesc(o, glm::vec4(0.0f)));
        pipeline.draw(s.drawCall());
        pipeline.endFrame();
    }
    result.stats = pipeline.stats();
    finishView(pipeline, o.view, result.image, result.stats.times.resolveMs);
    return result;
}

nlohmann::json statsToJson(const RenderOptions& o, const RenderResult& r) {
    const raster::StageCounters& c = r.stats.counters;
    const raster::StageTimes& t = r.stats.times;
    nlohmann::json j;
    j["scene"] = o.scene;
    j["width"] = o.width;
    j["height"] = o.height;
    j["msaa"] = o.msaa;
    j["threads"] = o.threads > 0 ? o.threads : raster::hardwareThreads();
    j["view"] = viewName(o.view);
    j["sceneTriangles"] = r.sceneTriangles;
    j["stages"] = {
        {"vertex", {{"verticesShaded", c.verticesShaded}, {"ms", t.vertexMs}}},
        {"clip",
         {{"trianglesIn", c.trianglesIn},
          {"invalid", c.trianglesInvalid},
          {"rejected", c.trianglesClipRejected},
          {"clipped", c.trianglesClipped},
          {"clippedTrianglesOut", c.clippedTrianglesOut}}},
        {"setup",
         {{"degenerate", c.trianglesDegenerate},
          {"culled", c.trianglesCulled},
          {"noSamples", c.trianglesNoSamples},
          {"setUp", c.trianglesSetUp}}},
        {"bin", {{"binEntries", c.binEntries}, {"flushes", r.stats.flushes}}},
        {"coarse",
         {{"smallTriangleEntries", c.smallTriangleEntries},
          {"blocksEmpty", c.blocksEmpty},
          {"blocksPartial", c.blocksPartial},
          {"blocksFull", c.blocksFull},
          {"blocksDepthCulled", c.blocksDepthCulled}}},
        {"depth", {{"samplesTested", c.samplesTested}, {"samplesPassed", c.samplesPassed}}},
        {"shade", {{"pixelsShaded", c.pixelsShaded}}},
    };
    j["timesMs"] = {{"load", r.loadMs},         {"vertex", t.vertexMs},
                    {"frontEnd", t.frontEndMs}, {"backEnd", t.backEndMs},
                    {"resolve", t.resolveMs},   {"frame", t.frameMs}};
    j["occlusionSamplesPassed"] = r.stats.occlusionSamplesPassed;
    return j;
}

int runRenderCommand(const RenderOptions& o) {
    if (o.out.empty()) throw scene::InputError("--out: an output file is required (.png or .exr)");
    imageFormatFor(o.out);  // reject a bad extension before any work
    const RenderResult r = renderScene(o);
    writeImageAtomically(o.out, r.image);
    if (!o.statsPath.empty()) {
        const std::filesystem::path temp = o.statsPath.string() + ".tmp";
        {
            std::ofstream f(temp);
            f << statsToJson(o, r).dump(2) << "\n";
            if (!f) throw std::runtime_error(o.statsPath.string() + ": cannot write stats");
        }
        std::filesystem::rename(temp, o.statsPath);
    }
    if (!o.quiet) {
        const raster::StageCounters& c = r.stats.counters;
        std::printf("wrote %s (%dx%d, %d sample%s, view %s)\n", o.out.c_str(), o.width, o.height,
                    o.msaa, o.msaa > 1 ? "s" : "", viewName(o.view));
        std::printf("  %zu triangles in, %llu set up, %llu culled, %llu clipped; %.1f ms a frame "
                    "(vertex %.1f, front end %.1f, back end %.1f, resolve %.1f)\n",
                    r.sceneTriangles, (unsigned long long)c.trianglesSetUp,
                    (unsigned long long)(c.trianglesCulled + c.trianglesClipRejected),
                    (unsigned long long)c.trianglesClipped, r.stats.times.frameMs,
                    r.stats.times.vertexMs, r.stats.times.frontEndMs, r.stats.times.backEndMs,
                    r.stats.times.resolveMs);
        std::printf("  blocks: %llu full, %llu partial; %llu samples passed depth, %llu pixels "
                    "shaded\n",
                    (unsigned long long)c.blocksFull, (unsigned long long)c.blocksPartial,
                    (unsigned long long)c.samplesPassed, (unsigned long long)c.pixelsShaded);
    }
    return 0;
}

}  // namespace cuberille::apps
