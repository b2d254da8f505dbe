#pragma once
// A flight through a voxel model streamed under a memory budget, as a library call: the model's
// blocks read on demand (lod/streaming_blocks.h), a camera path (an orbit, a zoom towards the
// surface, or keyframes), each frame drawn through the same selection and pipeline as render()
// draws a voxel model, then the last view held until loading settles. `cuberille fly` is a
// client of it (apps/fly_command.h) that writes the images, the CSV and the plot.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "lod/flight.h"
#include "raster/pipeline.h"
#include "raster/resolve.h"
#include "scene/input_error.h"

namespace cuberille::render {

struct FlySettings {
    std::filesystem::path model;  // a .cvox
    std::string path = "orbit";   // orbit, zoom or a keyframe file ('px py pz tx ty tz' per line)
    int frames = 120;
    int width = 1280, height = 720, msaa = 4, threads = 0;
    double budgetMib = 1024.0, uploadLimitMib = 0.0, ioThrottleMibps = 0.0;
    std::string refine = "full";  // full or partial
    float pixelError = 1.0f;
    bool noOcclusion = false, noHybrid = false;
    int settleFrames = 1000;  // after the path, its last view until loading settles (0: not at all)
    float azimuth = 30.0f, elevation = 20.0f;
    /// A run of the path (how the distributed runner splits a flight): its frames [firstFrame,
    /// firstFrame + runFrames) of `frames`, numbered as in the whole flight and flown from a cold
    /// start — the model opened, nothing resident, no occlusion history — and settled only by the
    /// run that ends the path. runFrames 0: to the path's end.
    int firstFrame = 0, runFrames = 0;
    int lastFrame() const { return runFrames > 0 ? firstFrame + runFrames : frames; }  // one past
    bool endsThePath() const { return lastFrame() == frames; }
};

struct FlyResult {
    std::vector<lod::FlightFrame> frames;  // the path's (the run's), then the settling ones
    int pathFrames = 0;                    // of them on the path
    double openMs = 0.0;               // opening the model and reading its root
    double timeToFirstImageMs = 0.0;   // from the start to the first frame's image
    uint64_t bytesReadFromDisk = 0;
    uint64_t peakHeldBytes = 0;        // the most the pools held (resident and free lists)
    uint64_t budgetBytes = 0;
    std::vector<std::string> warnings;  // failed blocks, once each
    bool settled = false;
    raster::Image finalImage;  // the last frame drawn (the settled last view), resolved
};

/// Called after each frame, path and settling alike, with the frame's number (from 0) and the
/// pipeline that drew it: resolve what you need from its framebuffer before returning.
using FlightFrameSink = std::function<void(int frame, const lod::FlightFrame&, const raster::Pipeline&)>;

/// Throws scene::InputError for bad settings or input; `warn` hears of blocks that could not be
/// read (their parents are drawn instead).
FlyResult fly(const FlySettings& settings, const FlightFrameSink& onFrame = {}, const scene::WarningSink& warn = {});

}  // namespace cuberille::render
