#pragma once
// `cuberille fly`: a flight through a voxel model streamed under a memory budget (lod/flight.h)
// along an orbit, a zoom or a keyframe file, with per-frame statistics as CSV and as a plot, and
// frame images on request. A library entry point, so tests and benchmarks run the tool's path.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "lod/flight.h"

namespace cuberille::apps {

struct FlyOptions {
    std::filesystem::path model;
    std::string path = "orbit";  // orbit, zoom or a keyframe file
    int frames = 120;
    int width = 1280, height = 720, msaa = 4, threads = 0;
    std::filesystem::path outDir;  // images: frame_NNNNN.png every --save-every, and final.png
    int saveEvery = 0;             // 0: only the final image
    std::filesystem::path statsPath, plotPath;
    double budgetMib = 1024.0, uploadLimitMib = 0.0, ioThrottleMibps = 0.0;
    std::string refine = "full";  // full or partial
    float pixelError = 1.0f;
    bool noOcclusion = false, noHybrid = false;
    int settleFrames = 1000;  // after the path, its last view until loading settles (0: not at all)
    float azimuth = 30.0f, elevation = 20.0f;
    bool quiet = false;
};

struct FlyResult {
    std::vector<lod::FlightFrame> frames;  // the path's, then the settling ones
    std::vector<uint64_t> residentBytes;   // the process's resident set after each frame
    int pathFrames = 0;
    double openMs = 0.0;               // opening the model and reading its root
    double timeToFirstImageMs = 0.0;   // from the start to the first frame's image
    uint64_t bytesReadFromDisk = 0;
    uint64_t peakHeldBytes = 0;        // the most the pools held (resident and free lists)
    uint64_t budgetBytes = 0;
    std::vector<std::string> warnings;  // failed blocks, once each
    bool settled = false;
};

/// Throws scene::InputError for bad options or input (exit code 2).
FlyResult runFly(const FlyOptions& o);
int runFlyCommand(const FlyOptions& o);

/// The CSV's header and one row per frame (for tests and benchmarks).
std::string flyCsv(const FlyResult& r);

}  // namespace cuberille::apps
