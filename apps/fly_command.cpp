#include "apps/fly_command.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "apps/atomic_file.h"
#include "apps/frame_plot.h"
#include "apps/image_io.h"
#include "apps/process_memory.h"
#include "apps/progress.h"
#include "apps/render_command.h"
#include "apps/render_options_cli.h"
#include "raster/clock.h"
#include "raster/pipeline.h"
#include "raster/resolve.h"
#include "scene/input_error.h"
#include "scene/file_names.h"

namespace cuberille::apps {
namespace {

constexpr double kMib = 1024.0 * 1024.0;

// What the tool adds to the library's checks: its outputs.
void validateOutputs(const FlyOptions& o) {
    using scene::InputError;
    if (o.saveEvery < 0) throw InputError("--save-every: must be 0 (the final image only) or more");
    if (o.saveEvery > 0 && o.outDir.empty()) throw InputError("--save-every: needs --out-dir");
    if (!o.plotPath.empty()) imageFormatFor(o.plotPath);
    requireOutputPath(o.plotPath, "--plot");
    requireOutputPath(o.statsPath, "--stats");
}

void saveImage(const raster::Pipeline& p, const std::filesystem::path& path) {
    raster::Image image;
    raster::resolveColor(p.framebuffer(), image);
    writeImageAtomically(path, image);
}


size_t levelCount(const FlyResult& r) {
    size_t levels = 0;
    for (const lod::FlightFrame& f : r.frames) levels = std::max(levels, f.voxel.selection.drawnPerLevel.size());
    return levels;
}

std::vector<PlotPanel> plotPanels(const FlyResult& r) {
    auto series = [&](const char* name, glm::vec3 color, auto&& value) {
        PlotSeries s{name, color, {}};
        for (const lod::FlightFrame& f : r.frames) s.values.push_back(double(value(f)));
        return s;
    };
    const glm::vec3 black(0.1f), blue(0.15f, 0.35f, 0.8f), orange(0.95f, 0.5f, 0.05f), green(0.1f, 0.6f, 0.2f),
        red(0.85f, 0.1f, 0.1f), purple(0.55f, 0.25f, 0.7f), grey(0.55f);
    std::vector<PlotPanel> panels;
    panels.push_back({"frame time (ms)",
                      {series("frame", black, [](auto& f) { return f.frameMs; }),
                       series("raster", blue, [](auto& f) { return f.rasterMs; }),
                       series("traversal", green, [](auto& f) { return f.traversalMs; }),
                       series("upload", orange, [](auto& f) { return f.uploadMs; }),
                       series("I/O wait", red, [](auto& f) { return f.ioWaitMs; })},
                      {}, ""});
    panels.push_back({"data per frame (MiB)",
                      {series("requested", grey, [](auto& f) { return f.streaming.requestedBytes / kMib; }),
                       series("read from disk", red, [](auto& f) { return f.streaming.loadedBytes / kMib; }),
                       series("made resident", blue, [](auto& f) { return f.streaming.uploadedBytes / kMib; }),
                       series("revived", green, [](auto& f) { return f.streaming.revivedBytes / kMib; })},
                      {}, ""});
    PlotPanel memory{"held in the pools (MiB)",
                     {series("voxels", blue, [](auto& f) { return f.streaming.residentBytes[lod::kVoxelPool] / kMib; }),
                      series("vertices", orange, [](auto& f) { return f.streaming.residentBytes[lod::kVertexPool] / kMib; }),
                      series("indices", purple, [](auto& f) { return f.streaming.residentBytes[lod::kIndexPool] / kMib; }),
                      series("free lists", grey, [](auto& f) {
                          return double(f.streaming.freeListBytes[0] + f.streaming.freeListBytes[1] +
                                        f.streaming.freeListBytes[2]) / kMib;
                      }),
                      series("budget", red, [&](auto&) { return r.budgetBytes / kMib; })},
                     {}, "defragmentation"};
    for (const lod::FlightFrame& f : r.frames)
        if (f.streaming.defragmentations) memory.markers.push_back(f.index);
    panels.push_back(std::move(memory));
    PlotPanel drawn{"blocks selected, per level; missing ones stood in for or left as holes", {}, {}, ""};
    const glm::vec3 levelColors[] = {{0.85f, 0.15f, 0.15f}, {0.95f, 0.55f, 0.05f}, {0.75f, 0.7f, 0.0f},
                                     {0.2f, 0.65f, 0.2f},   {0.1f, 0.6f, 0.8f},    {0.2f, 0.3f, 0.9f},
                                     {0.6f, 0.25f, 0.8f},   {0.4f, 0.4f, 0.4f}};
    for (size_t level = 0; level < levelCount(r); ++level) {
        const std::string name = "level " + std::to_string(level);
        drawn.series.push_back(series(name.c_str(), levelColors[level % 8], [&](auto& f) {
            return level < f.voxel.selection.drawnPerLevel.size() ? f.voxel.selection.drawnPerLevel[level] : 0;
        }));
    }
    drawn.series.push_back(series("source triangles", black, [](auto& f) { return f.voxel.triangleBlocksDrawn; }));
    drawn.series.push_back(series("stood in for", grey, [](auto& f) { return f.voxel.standIns; }));
    drawn.series.push_back(series("holes", glm::vec3(1.0f, 0.0f, 1.0f), [](auto& f) { return f.voxel.holes; }));
    panels.push_back(std::move(drawn));
    return panels;
}

void printSummary(const FlyOptions& o, const FlyResult& r) {
    std::vector<double> times;
    double readMib = 0.0;
    for (int i = 0; i < r.pathFrames; ++i) times.push_back(r.frames[size_t(i)].frameMs);
    for (const lod::FlightFrame& f : r.frames) readMib += f.streaming.loadedBytes / kMib;
    std::sort(times.begin(), times.end());
    const double median = times[times.size() / 2], p95 = times[std::min(times.size() - 1, times.size() * 95 / 100)];
    std::printf("flew %d frames along %s through %s (%dx%d, %d sample%s, refine %s)\n", r.pathFrames, o.path.c_str(),
                o.model.c_str(), o.width, o.height, o.msaa, o.msaa > 1 ? "s" : "", o.refine.c_str());
    std::printf("  first image after %.1f ms (opening and the root: %.1f ms); frame time median %.1f ms, 95th "
                "percentile %.1f ms, largest %.1f ms\n",
                r.timeToFirstImageMs, r.openMs, median, p95, times.back());
    std::printf("  read %.1f MiB from disk (%.2f MiB a frame); held at most %.1f of %.0f MiB\n",
                double(r.bytesReadFromDisk) / kMib, readMib / double(r.frames.size()), double(r.peakHeldBytes) / kMib,
                double(r.budgetBytes) / kMib);
    if (!r.residentBytes.empty())
        std::printf("  process resident memory %.0f MiB after the first frame, %.0f MiB at most, %.0f MiB after the last\n",
                    double(r.residentBytes.front()) / kMib,
                    double(*std::max_element(r.residentBytes.begin(), r.residentBytes.end())) / kMib,
                    double(r.residentBytes.back()) / kMib);
    const size_t settling = r.frames.size() - size_t(r.pathFrames);
    if (o.settleFrames > 0)
        std::printf("  %s after %zu more frame%s of the last view\n", r.settled ? "settled" : "not settled", settling,
                    settling == 1 ? "" : "s");
    if (!r.warnings.empty()) std::printf("  %zu block%s could not be read\n", r.warnings.size(), r.warnings.size() == 1 ? "" : "s");
}

}  // namespace

FlyResult runFly(const FlyOptions& o) {
    validateOutputs(o);
    FlyResult r;
    if (!o.outDir.empty()) std::filesystem::create_directories(o.outDir);
    ProgressLine progress("frame", o.frames, o.quiet);
    const auto onFrame = [&](int frame, const lod::FlightFrame& f, const raster::Pipeline& p) {
        progress.update(std::min(frame + 1, o.frames));  // the settling frames after the path count as its last
        r.residentBytes.push_back(residentBytes());
        if (o.saveEvery > 0 && !f.settling && frame % o.saveEvery == 0) saveImage(p, flyFrameFile(o, frame));
    };
    static_cast<render::FlyResult&>(r) = render::fly(o, onFrame, [](const std::string& w) {
        std::fprintf(stderr, "cuberille: warning: %s\n", w.c_str());
    });
    progress.finish();
    if (!o.outDir.empty() && o.endsThePath()) writeImageAtomically(o.outDir / "final.png", r.finalImage);
    return r;
}

static std::string fixed3(double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%.3f", v);
    return text;
}

std::string flyCsv(const FlyResult& r) {
    std::ostringstream csv;
    const size_t levels = levelCount(r);
    csv << "frame,settling,frame_ms,traversal_ms,io_wait_ms,upload_ms,raster_ms,requested_bytes,loaded_bytes,"
           "uploaded_bytes,revived_bytes,dropped_bytes,staged_bytes,resident_voxel_bytes,resident_vertex_bytes,"
           "resident_index_bytes,free_list_bytes,defragmentations,failed_blocks,requests,missing_blocks,stand_ins,"
           "holes,triangle_blocks,occlusion_culled,faces,faces_between_samples,faces_behind_depth,covered_pixels,faces_per_covered_pixel,"
           "process_resident_bytes";
    for (size_t l = 0; l < levels; ++l) csv << ",drawn_level_" << l;
    csv << "\n";
    char ms[160];
    for (size_t i = 0; i < r.frames.size(); ++i) {
        const lod::FlightFrame& f = r.frames[i];
        const lod::StreamingFrameStats& s = f.streaming;
        std::snprintf(ms, sizeof ms, "%.3f,%.3f,%.3f,%.3f,%.3f", f.frameMs, f.traversalMs, f.ioWaitMs, f.uploadMs,
                      f.rasterMs);
        csv << f.index << ',' << int(f.settling) << ',' << ms << ',' << s.requestedBytes << ',' << s.loadedBytes << ','
            << s.uploadedBytes << ',' << s.revivedBytes << ',' << s.droppedBytes << ',' << s.stagedBytes << ','
            << s.residentBytes[0] << ',' << s.residentBytes[1] << ',' << s.residentBytes[2] << ','
            << s.freeListBytes[0] + s.freeListBytes[1] + s.freeListBytes[2] << ',' << s.defragmentations << ','
            << s.failedBlocks << ',' << s.requests << ',' << f.voxel.missingBlocks << ',' << f.voxel.standIns << ','
            << f.voxel.holes << ',' << f.voxel.triangleBlocksDrawn << ',' << f.voxel.occlusionCulled << ','
            << f.voxel.facesEmitted << ',' << f.voxel.facesBetweenSamples << ',' << f.voxel.facesBehindDepth << ','
            << f.voxel.coveredPixels << ',' << fixed3(f.voxel.facesPerCoveredPixel()) << ','
            << (i < r.residentBytes.size() ? r.residentBytes[i] : 0);
        for (size_t l = 0; l < levels; ++l)
            csv << ',' << (l < f.voxel.selection.drawnPerLevel.size() ? f.voxel.selection.drawnPerLevel[l] : 0);
        csv << "\n";
    }
    return csv.str();
}

std::filesystem::path flyFrameFile(const FlyOptions& o, int frame) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.png", frame);
    return o.outDir / name;
}

int runFlyCommand(const FlyOptions& o) { return finishFlyCommand(o, runFly(o)); }

int finishFlyCommand(const FlyOptions& o, const FlyResult& r) {
    if (!o.statsPath.empty()) {
        AtomicOutputFile out(o.statsPath);
        out.stream() << flyCsv(r);
        out.commit();
    }
    if (!o.plotPath.empty()) {
        PlotLayout layout;
        layout.title = "cuberille fly " + o.model.filename().string() + " --path " + o.path + "  (" +
                       std::to_string(o.width) + "x" + std::to_string(o.height) + ", budget " +
                       std::to_string(int(o.budgetMib)) + " MiB, upload limit " +
                       (o.uploadLimitMib > 0 ? std::to_string(o.uploadLimitMib).substr(0, 4) + " MiB" : "none") +
                       ", refine " + o.refine + ")";
        layout.firstSettlingFrame = r.frames.size() > size_t(r.pathFrames) ? r.pathFrames : -1;
        std::string warning;
        const raster::Image plot = plotFrames(plotPanels(r), layout, &warning);
        if (!warning.empty()) std::fprintf(stderr, "cuberille: warning: %s\n", warning.c_str());
        writeImageAtomically(o.plotPath, plot);
    }
    if (!o.quiet) printSummary(o, r);
    return 0;
}

// ---------------------------------------------------------------------------------------------
// A flight taken apart into runs (the distributed runner's tasks)

namespace {

nlohmann::json frameJson(const lod::FlightFrame& f) {
    const lod::StreamingFrameStats& s = f.streaming;
    const lod::VoxelFrameStats& v = f.voxel;
    return {{"index", f.index},
            {"settling", f.settling},
            {"ms", {f.frameMs, f.traversalMs, f.ioWaitMs, f.uploadMs, f.rasterMs}},
            {"streaming",
             {s.requestedBytes, s.loadedBytes, s.uploadedBytes, s.revivedBytes, s.stagedBytes, s.droppedBytes,
              s.defragmentations, s.failedBlocks, uint64_t(s.requests)}},
            {"uploadMs", s.uploadMs},
            {"residentBytes", s.residentBytes},
            {"freeListBytes", s.freeListBytes},
            {"selection", {v.selection.blocksVisited, v.selection.frustumCulled, v.selection.hybridBlocks}},
            {"drawnPerLevel", v.selection.drawnPerLevel},
            {"voxel",
             {v.voxelBlocksDrawn, v.triangleBlocksDrawn, v.occlusionCulled, v.visibilityTests, v.voxelsExpanded,
              v.facesEmitted, v.hybridTriangles, v.facesBetweenSamples, v.missingBlocks, v.standIns, v.holes,
              v.coveredPixels, v.facesBehindDepth}},
            {"voxelMs", {v.selectMs, v.expandMs}}};
}

lod::FlightFrame frameFromJson(const nlohmann::json& j) {
    lod::FlightFrame f;
    j.at("index").get_to(f.index), j.at("settling").get_to(f.settling);
    const auto& ms = j.at("ms");
    f.frameMs = ms.at(0), f.traversalMs = ms.at(1), f.ioWaitMs = ms.at(2), f.uploadMs = ms.at(3), f.rasterMs = ms.at(4);
    lod::StreamingFrameStats& s = f.streaming;
    const auto& st = j.at("streaming");
    s.requestedBytes = st.at(0), s.loadedBytes = st.at(1), s.uploadedBytes = st.at(2), s.revivedBytes = st.at(3);
    s.stagedBytes = st.at(4), s.droppedBytes = st.at(5), s.defragmentations = st.at(6), s.failedBlocks = st.at(7);
    s.requests = st.at(8).get<uint32_t>();
    j.at("uploadMs").get_to(s.uploadMs);
    for (int k = 0; k < lod::kPoolCount; ++k)
        s.residentBytes[k] = j.at("residentBytes").at(k), s.freeListBytes[k] = j.at("freeListBytes").at(k);
    lod::VoxelFrameStats& v = f.voxel;
    const auto& sel = j.at("selection");
    v.selection.blocksVisited = sel.at(0), v.selection.frustumCulled = sel.at(1), v.selection.hybridBlocks = sel.at(2);
    j.at("drawnPerLevel").get_to(v.selection.drawnPerLevel);
    const auto& vx = j.at("voxel");
    v.voxelBlocksDrawn = vx.at(0), v.triangleBlocksDrawn = vx.at(1), v.occlusionCulled = vx.at(2);
    v.visibilityTests = vx.at(3), v.voxelsExpanded = vx.at(4), v.facesEmitted = vx.at(5), v.hybridTriangles = vx.at(6);
    v.facesBetweenSamples = vx.at(7), v.missingBlocks = vx.at(8), v.standIns = vx.at(9), v.holes = vx.at(10);
    v.coveredPixels = vx.at(11), v.facesBehindDepth = vx.at(12);
    v.selectMs = j.at("voxelMs").at(0), v.expandMs = j.at("voxelMs").at(1);
    return f;
}

}  // namespace

nlohmann::json flyResultJson(const FlyResult& r) {
    nlohmann::json frames = nlohmann::json::array();
    for (const lod::FlightFrame& f : r.frames) frames.push_back(frameJson(f));
    return {{"frames", frames},
            {"pathFrames", r.pathFrames},
            {"openMs", r.openMs},
            {"timeToFirstImageMs", r.timeToFirstImageMs},
            {"bytesReadFromDisk", r.bytesReadFromDisk},
            {"peakHeldBytes", r.peakHeldBytes},
            {"budgetBytes", r.budgetBytes},
            {"warnings", r.warnings},
            {"settled", r.settled},
            {"residentBytes", r.residentBytes}};
}

FlyResult flyResultFromJson(const nlohmann::json& j) {
    FlyResult r;
    for (const nlohmann::json& f : j.at("frames")) r.frames.push_back(frameFromJson(f));
    j.at("pathFrames").get_to(r.pathFrames), j.at("openMs").get_to(r.openMs);
    j.at("timeToFirstImageMs").get_to(r.timeToFirstImageMs), j.at("bytesReadFromDisk").get_to(r.bytesReadFromDisk);
    j.at("peakHeldBytes").get_to(r.peakHeldBytes), j.at("budgetBytes").get_to(r.budgetBytes);
    j.at("warnings").get_to(r.warnings), j.at("settled").get_to(r.settled), j.at("residentBytes").get_to(r.residentBytes);
    return r;
}

// As one flight reports: the frames in path order, then the last run's settling; the first run's
// opening and first image; bytes read summed over the runs (each read what it needed itself);
// the largest held; a failed block's warning once.
FlyResult joinFlyRuns(std::vector<FlyResult> runs) {
    FlyResult all;
    if (runs.empty()) return all;
    std::sort(runs.begin(), runs.end(), [](const FlyResult& a, const FlyResult& b) {
        return a.frames.front().index < b.frames.front().index;
    });
    all.openMs = runs.front().openMs;
    all.timeToFirstImageMs = runs.front().timeToFirstImageMs;
    all.budgetBytes = runs.front().budgetBytes;
    for (FlyResult& r : runs) {
        all.frames.insert(all.frames.end(), r.frames.begin(), r.frames.end());
        all.residentBytes.insert(all.residentBytes.end(), r.residentBytes.begin(), r.residentBytes.end());
        all.pathFrames += r.pathFrames;
        all.bytesReadFromDisk += r.bytesReadFromDisk;
        all.peakHeldBytes = std::max(all.peakHeldBytes, r.peakHeldBytes);
        for (const std::string& w : r.warnings)
            if (std::find(all.warnings.begin(), all.warnings.end(), w) == all.warnings.end()) all.warnings.push_back(w);
    }
    all.settled = runs.back().settled;
    return all;
}

CLI::App* addFlyCommand(CLI::App& app, FlyOptions& o) {
    CLI::App* fly = app.add_subcommand(
        "fly", "Fly through a voxel model (.cvox) streamed under a memory budget, recording each frame");
    fly->add_option("model", o.model, "A .cvox voxel model")->required();
    fly->add_option("--path", o.path,
                    "Camera path: orbit (a full turn), zoom (towards the surface) or a keyframe file "
                    "('px py pz tx ty tz' per line)")
        ->capture_default_str();
    fly->add_option("--frames", o.frames, "Frames along the path")->capture_default_str();
    addFrameOptions(fly, o.width, o.height, o.msaa, o.threads);
    fly->add_option("--out-dir", o.outDir, "Write final.png (the settled last view) and frames asked for by --save-every");
    fly->add_option("--save-every", o.saveEvery, "Also write every K-th frame as frame_NNNNN.png (0: none)")
        ->capture_default_str();
    fly->add_option("--stats", o.statsPath, "Write one CSV row per frame: times, bytes, pools, blocks per level");
    fly->add_option("--plot", o.plotPath, "Plot the per-frame statistics as a PNG");
    fly->add_option("--budget-mib", o.budgetMib, "Memory for resident blocks, all pools together, in MiB")
        ->capture_default_str();
    fly->add_option("--upload-limit", o.uploadLimitMib, "MiB made resident per frame at most (0: unlimited)")
        ->capture_default_str();
    fly->add_option("--io-throttle", o.ioThrottleMibps, "Simulate a disk this slow, in MiB/s (0: no throttle)")
        ->capture_default_str();
    fly->add_option("--refine", o.refine,
                    "Missing blocks: full (a resident ancestor stands in: always closed) or partial (holes while "
                    "loading)")
        ->capture_default_str();
    fly->add_option("--pixel-error", o.pixelError, "Refine blocks until a voxel's edge projects to at most this many pixels")
        ->capture_default_str();
    fly->add_flag("--no-hybrid", o.noHybrid, "Never draw source triangles");
    fly->add_flag("--no-occlusion", o.noOcclusion, "No occlusion culling (of blocks hidden last frame, or of voxels behind what the frame drew)");
    fly->add_option("--settle-frames", o.settleFrames,
                    "After the path, render its last view until loading settles, at most this many frames (0: stop)")
        ->capture_default_str();
    fly->add_option("--azimuth", o.azimuth, "Framing camera azimuth, degrees about +y")->capture_default_str();
    fly->add_option("--elevation", o.elevation, "Framing camera elevation, degrees")->capture_default_str();
    fly->add_flag("--quiet", o.quiet, "Print nothing on success");
    return fly;
}

FlyOptions parseFlyArguments(const std::vector<std::string>& arguments) {
    FlyOptions o;
    parseSubcommandArguments("fly", arguments, [&](CLI::App& app) { addFlyCommand(app, o); });
    validateOutputs(o);
    return o;
}

}  // namespace cuberille::apps
