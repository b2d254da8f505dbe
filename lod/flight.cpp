#include "lod/flight.h"

#include "raster/resolve.h"

#include "raster/clock.h"

namespace cuberille::lod {

Flight::Flight(VoxelScene& scene, StreamingBlocks& blocks, const raster::FramebufferDesc& framebuffer,
               const VoxelRenderOptions& options)
    : scene_(scene), blocks_(blocks), framebuffer_(framebuffer), options_(options) {}

FlightFrame Flight::frame(const scene::Camera& camera, bool settling) {
    FlightFrame f;
    f.index = frames_++;
    f.settling = settling;
    const double t0 = raster::nowMs();
    scene_.camera = camera;
    pipeline_.beginFrame(framebuffer_);
    f.voxel = scene_.draw(pipeline_, framebuffer_.widthPixels, framebuffer_.heightPixels, options_);
    pipeline_.endFrame();
    if (options_.occlusion && !options_.viewFrom) scene_.readOcclusion(pipeline_.stats());
    f.frameMs = raster::nowMs() - t0;
    f.voxel.coveredPixels = raster::coveredPixels(pipeline_.framebuffer());
    f.streaming = blocks_.frameStats();
    f.uploadMs = f.streaming.uploadMs;
    f.traversalMs = f.voxel.selectMs - f.uploadMs;  // the upload happens inside the draw's selection step
    f.rasterMs = f.frameMs - f.voxel.selectMs;       // expansion, submission and the pipeline
    return f;
}

std::vector<FlightFrame> Flight::settle(const scene::Camera& camera, int maxFrames,
                                       const std::function<void(const FlightFrame&)>& afterFrame) {
    std::vector<FlightFrame> frames;
    while (!blocks_.settled() && int(frames.size()) < maxFrames) {
        const double waited = blocks_.frameStats().stagedBytes ? 0.0 : blocks_.waitForLoads();
        frames.push_back(frame(camera, true));
        frames.back().ioWaitMs = waited;
        frames.back().frameMs += waited;
        if (afterFrame) afterFrame(frames.back());
    }
    return frames;
}

}  // namespace cuberille::lod
