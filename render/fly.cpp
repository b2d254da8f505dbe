#include "render/fly.h"

#include <algorithm>
#include <cmath>

#include "lod/camera_path.h"
#include "lod/streaming_blocks.h"
#include "lod/voxel_scene.h"
#include "raster/clock.h"
#include "raster/parallel.h"
#include "raster/resolve.h"
#include "render/frame_settings.h"
#include "scene/file_names.h"
#include "voxel/cvox_file.h"

namespace cuberille::render {
namespace {

constexpr double kMib = 1024.0 * 1024.0;

void validate(const FlySettings& o) {
    using scene::InputError;
    if (scene::fileKindOf(o.model) != scene::FileKind::VoxelModel) throw InputError(o.model.string() + ": fly needs a voxel model (.cvox)");
    if (o.frames < 1 || o.frames > 1000000) throw InputError("--frames: must be 1 to 1000000");
    validateFrameOptions(o.width, o.height, o.msaa, o.threads);
    if (!(o.budgetMib >= 1.0 && o.budgetMib <= 1024.0 * 1024.0)) throw InputError("--budget-mib: must be 1 to 1048576");
    if (!(o.uploadLimitMib >= 0.0 && std::isfinite(o.uploadLimitMib)))
        throw InputError("--upload-limit: must be 0 (unlimited) or more MiB");
    if (!(o.ioThrottleMibps >= 0.0 && std::isfinite(o.ioThrottleMibps)))
        throw InputError("--io-throttle: must be 0 (no throttle) or more MiB/s");
    if (o.refine != "full" && o.refine != "partial") throw InputError("--refine: '" + o.refine + "' is not full or partial");
    if (!(o.pixelError >= 0.0f && std::isfinite(o.pixelError))) throw InputError("--pixel-error: must be 0 or more");
    if (o.settleFrames < 0) throw InputError("--settle-frames: must be 0 or more");
    if (o.firstFrame < 0 || o.runFrames < 0 || o.firstFrame >= o.frames || o.lastFrame() > o.frames)
        throw InputError("a run of frames " + std::to_string(o.firstFrame) + " + " + std::to_string(o.runFrames) +
                         " outside the path's " + std::to_string(o.frames));
    if (o.path != "orbit" && o.path != "zoom" && !std::filesystem::exists(o.path))
        throw InputError("--path: '" + o.path + "' is not orbit, zoom or an existing keyframe file");
}

lod::CameraPath cameraPath(const FlySettings& o, const scene::Camera& framing) {
    if (o.path == "orbit") return lod::CameraPath::orbit(framing);
    if (o.path == "zoom") return lod::CameraPath::zoom(framing);
    return lod::CameraPath::fromFile(o.path);
}

uint64_t heldBytes(const lod::StreamingFrameStats& s) {
    uint64_t held = 0;
    for (int k = 0; k < lod::kPoolCount; ++k) held += s.residentBytes[k] + s.freeListBytes[k];
    return held;
}

}  // namespace

FlyResult fly(const FlySettings& o, const FlightFrameSink& onFrame, const scene::WarningSink& warn) {
    validate(o);
    raster::ThreadLimit threadLimit(o.threads);
    FlyResult r;
    const double start = raster::nowMs();
    const voxel::CvoxReader reader(o.model);
    if (reader.blockCount() == 0) throw scene::InputError(o.model.string() + ": no voxels to fly through (a model of no blocks)");
    lod::StreamingOptions so;
    so.budgetBytes = uint64_t(o.budgetMib * kMib);
    so.uploadLimitBytes = uint64_t(o.uploadLimitMib * kMib);
    so.ioThrottleMibPerSecond = o.ioThrottleMibps;
    lod::StreamingBlocks blocks(reader, so, [&](const std::string& w) {
        r.warnings.push_back(w);
        if (warn) warn(w + " (its parent is drawn instead)");
    });
    r.budgetBytes = blocks.capacityBytes();
    lod::VoxelScene scene(blocks, o.azimuth, o.elevation);
    r.openMs = raster::nowMs() - start;
    const lod::CameraPath path = cameraPath(o, scene.camera);
    const scene::Camera lens = scene.camera;
    lod::VoxelRenderOptions ro;
    ro.selection.pixelError = o.pixelError;
    ro.selection.hybrid = !o.noHybrid;
    ro.occlusion = ro.leaveOutVoxelsBehindDepth = !o.noOcclusion;
    ro.refine = o.refine == "partial" ? lod::Refinement::Partial : lod::Refinement::Full;
    raster::FramebufferDesc fb;
    fb.widthPixels = o.width, fb.heightPixels = o.height, fb.samples = o.msaa, fb.clearColor = scene.background;
    lod::Flight flight(scene, blocks, fb, ro);
    for (int i = o.firstFrame; i < o.lastFrame(); ++i) {
        const float t = o.frames > 1 ? float(i) / float(o.frames - 1) : 0.0f;
        r.frames.push_back(flight.frame(path.at(t, lens)));
        if (i == o.firstFrame) r.timeToFirstImageMs = raster::nowMs() - start;
        if (onFrame) onFrame(i, r.frames.back(), flight.pipeline());
    }
    r.pathFrames = o.lastFrame() - o.firstFrame;
    if (o.settleFrames > 0 && o.endsThePath()) {
        int index = o.frames;
        const auto afterFrame = [&](const lod::FlightFrame& f) {
            if (onFrame) onFrame(index, f, flight.pipeline());
            ++index;
        };
        for (lod::FlightFrame& f : flight.settle(path.at(1.0f, lens), o.settleFrames, afterFrame)) r.frames.push_back(std::move(f));
        r.settled = blocks.settled();
    }
    // Numbered as in the whole flight, whichever run draws them (the flight counts from its first).
    for (lod::FlightFrame& f : r.frames) f.index += o.firstFrame;
    for (const lod::FlightFrame& f : r.frames) r.peakHeldBytes = std::max(r.peakHeldBytes, heldBytes(f.streaming));
    r.bytesReadFromDisk = blocks.bytesReadFromDisk();
    raster::resolveColor(flight.pipeline().framebuffer(), r.finalImage);
    return r;
}

}  // namespace cuberille::render
